//! `sitar bench --save_plot FILE`: rpg_trajectory_evaluation's comparison box plots — per
//! sequence, a box per algorithm and sub-trajectory length of the relative errors (every run
//! pooled), and a box per algorithm and sequence of the APE RMSE over runs.

use std::path::Path;

use anyhow::Result;

use crate::beyond_evo::bench_results::{Bench, Lengths};
use crate::figures::canvas::Page;
use crate::figures::figure::{DistributionKind, Drawing};
use crate::io::console::{Console, UsabilityArgs};

/// The length's label in a box's name.
fn label(lengths: &Lengths, k: usize, metres: f64) -> String {
    match lengths {
        Lengths::Percent(p) => format!("{} % ({metres} m)", p[k]),
        Lengths::Metres(_) => format!("{metres} m"),
    }
}

/// Writes the pages: `FILE_ape_rmse.EXT`, then per sequence `FILE_SEQ_trans_percent.EXT` and
/// `FILE_SEQ_yaw_deg.EXT` (one PDF with every page).
pub fn save(bench: &Bench, path: &Path) -> Result<()> {
    let drawings = drawings(bench);
    let pages: Vec<(&str, Page<'_>)> = drawings
        .iter()
        .map(|(name, d)| (name.as_str(), Page::Other(d)))
        .collect();
    let console = Console::new(&UsabilityArgs::default())?;
    crate::results::runs::plots(&pages, false, Some(path), None, &console)
}

/// The figures, by page name: APE RMSE over runs, then per sequence the relative
/// translation and yaw errors by algorithm and length.
pub fn drawings(bench: &Bench) -> Vec<(String, Drawing)> {
    let mut sequences: Vec<&str> = bench
        .cells
        .iter()
        .map(|c| c.cell.sequence.as_str())
        .collect();
    sequences.sort_unstable();
    sequences.dedup();
    let mut drawings: Vec<(String, Drawing)> = vec![(
        "ape_rmse".into(),
        Drawing::Distributions {
            title: "APE RMSE over runs".into(),
            label: "APE RMSE (m)".into(),
            kind: DistributionKind::Box,
            groups: bench
                .cells
                .iter()
                .map(|c| {
                    (
                        format!("{} {}", c.cell.algorithm, c.cell.sequence),
                        c.runs.iter().map(|r| r.ape_rmse).collect(),
                    )
                })
                .collect(),
        },
    )];
    for seq in sequences {
        for (metric, axis) in [
            ("trans_percent", "relative translation error (%)"),
            ("yaw_deg", "relative yaw error (deg)"),
        ] {
            let mut groups = Vec::new();
            for c in bench.cells.iter().filter(|c| c.cell.sequence == seq) {
                for (k, &metres) in c.lengths_m.iter().enumerate() {
                    let values: Vec<f64> = c
                        .runs
                        .iter()
                        .flat_map(|r| r.relative[k].samples.iter())
                        .map(|s| match metric {
                            "trans_percent" => s.trans_percent,
                            _ => s.yaw_deg,
                        })
                        .collect();
                    groups.push((
                        format!("{} {}", c.cell.algorithm, label(&bench.lengths, k, metres)),
                        values,
                    ));
                }
            }
            drawings.push((
                format!("{seq}_{metric}"),
                Drawing::Distributions {
                    title: format!("{seq}: relative error at sub-trajectory lengths"),
                    label: axis.into(),
                    kind: DistributionKind::Box,
                    groups,
                },
            ));
        }
    }
    drawings
}
