//! `sitar bench DIR`: one table of algorithms × sequences over a results tree (rpg_trajectory_
//! evaluation's layout or a plain one, `bench_layout`): APE RMSE over runs, rpg's relative
//! error at sub-trajectory lengths, KITTI drift; printed by `bench_table`. Every run is read
//! once and computed in parallel (rayon).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use rayon::prelude::*;
use sitar_estimator::{
    DriftOptions, RPG_DEFAULT_PERCENTS, RPG_MAX_DIFF_NS, RpgAlignType, RpgAlignment,
    SegmentDuration, Statistics, Trajectory, absolute_translation_errors, cumulative_path_length,
    drift, lengths_from_percents, read_tum, relative_errors, rpg_align, rpg_associate,
};

use crate::beyond_evo::bench_layout::{Cell, discover};
use crate::beyond_evo::bench_results::{Bench, CellResult, Lengths, RunResult};
use crate::beyond_evo::bench_table::{TableFormat, render};
use crate::beyond_evo::shared_args::{LengthArgs, LengthWords};

/// One table of algorithms × sequences over a results tree.
///
/// DIR is rpg_trajectory_evaluation's results layout
/// (PLATFORM/ALG/PLATFORM_ALG_DATASET/{stamped_groundtruth.txt, stamped_traj_estimate{i}.txt,
/// eval_cfg.yaml}; DIR may be the results, a platform or an algorithm folder) or a plain tree
/// (ALG/SEQ/runN.txt with gt/SEQ.txt; an optional ALG/SEQ/eval_cfg.yaml). Files are TUM
/// (`stamp x y z qx qy qz qw`, seconds). Per run, as rpg: stamps paired within 0.02 s, the
/// alignment of eval_cfg.yaml (align_type, align_num_frames), the APE translation RMSE, the
/// relative error at sub-trajectory lengths (10–50 % of the ground truth's path unless
/// --lengths), and the KITTI drift at the same lengths. Per cell: APE RMSE mean ± std over
/// runs, relative errors pooled over runs, drift mean ± std.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar bench results/euroc_vislam_mono/laptop\n  sitar bench runs/ --format latex -o table.tex\n  sitar bench runs/ --lengths 8,16,24 --format json -o bench.json"
)]
pub struct Args {
    /// The results tree.
    dir: PathBuf,
    /// Output: a Markdown table, a LaTeX tabular, CSV (one row per cell, every number) or JSON.
    #[arg(long, value_enum, default_value_t = TableFormat::Markdown)]
    format: TableFormat,
    /// Write to this file instead of stdout.
    #[arg(short = 'o', long, value_name = "FILE")]
    output: Option<PathBuf>,
    #[command(flatten)]
    sub_trajectories: LengthArgs<BenchWords>,
    /// The alignment of a folder without an eval_cfg.yaml: posyaw, se3, sim3 or none
    /// (rpg's default: sim3).
    #[arg(long = "align_type", alias = "align-type", default_value = "sim3", value_parser = parse_align_type)]
    align_type: RpgAlignType,
    /// Poses from the start the alignment is fitted on in a folder without an eval_cfg.yaml
    /// (-1: all).
    #[arg(long = "align_num_frames", alias = "align-num-frames", default_value_t = -1, allow_negative_numbers = true)]
    align_num_frames: i64,
    /// Save rpg's comparison box plots: PNG, SVG or PDF by the extension (FILE_ape_rmse.EXT,
    /// and per sequence FILE_SEQ_trans_percent.EXT and FILE_SEQ_yaw_deg.EXT: a box per
    /// algorithm and length, every run pooled; a PDF gets every page).
    #[arg(long = "save_plot", value_name = "FILE")]
    save_plot: Option<PathBuf>,
    /// Also write one self-contained HTML page: the table, every box plot inline and the
    /// JSON document; it fetches nothing when opened.
    #[arg(long, value_name = "FILE")]
    html: Option<PathBuf>,
}

/// `sitar bench`'s help for the lengths it shares with `sitar relative`.
#[derive(Debug)]
pub struct BenchWords;

impl LengthWords for BenchWords {
    const LENGTHS: &'static str = "Sub-trajectory lengths in metres, comma-separated, for every \
        sequence";
    const LENGTHS_PERCENT: &'static str = "Sub-trajectory lengths as percentages of each ground \
        truth's path (rpg's default 10,20,30,40,50), truncated to centimetres as rpg does";
}

fn parse_align_type(s: &str) -> Result<RpgAlignType, String> {
    s.parse().map_err(|e: sitar_estimator::Error| e.to_string())
}

pub fn run(args: Args) -> Result<()> {
    if args.align_num_frames == 0 || args.align_num_frames < -1 {
        bail!(
            "--align_num_frames must be -1 (all) or positive, got {}",
            args.align_num_frames
        );
    }
    let lengths = match (
        &args.sub_trajectories.lengths,
        &args.sub_trajectories.lengths_percent,
    ) {
        (Some(m), _) => Lengths::Metres(m.clone()),
        (None, Some(p)) => Lengths::Percent(p.clone()),
        (None, None) => Lengths::Percent(RPG_DEFAULT_PERCENTS.to_vec()),
    };
    let (Lengths::Metres(values) | Lengths::Percent(values)) = &lengths;
    if values.is_empty() || values.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        bail!("--lengths and --lengths_percent take positive numbers, got {values:?}");
    }
    let default = RpgAlignment {
        align_type: args.align_type,
        num_frames: args.align_num_frames,
    };
    let bench = compute(&args.dir, default, lengths)?;
    crate::io::output::emit(args.output.as_deref(), &render(&bench, args.format))?;
    if let Some(path) = &args.save_plot {
        crate::beyond_evo::bench_plot::save(&bench, path)?;
    }
    if let Some(path) = &args.html {
        let drawings = crate::beyond_evo::bench_plot::drawings(&bench);
        let pages: Vec<(&str, crate::figures::canvas::Page<'_>)> = drawings
            .iter()
            .map(|(name, d)| (name.as_str(), crate::figures::canvas::Page::Other(d)))
            .collect();
        crate::figures::html::write(
            path,
            &crate::beyond_evo::bench_table::document(&bench),
            &pages,
        )?;
    }
    Ok(())
}

/// Discovers the cells under `dir` and computes every run.
pub fn compute(dir: &Path, default: RpgAlignment, lengths: Lengths) -> Result<Bench> {
    let cells = discover(dir, default)?;
    // Each ground truth once, however many algorithms share it (the plain tree's gt/SEQ.txt).
    let mut files: Vec<&Path> = cells.iter().map(|c| c.ground_truth.as_path()).collect();
    files.sort_unstable();
    files.dedup();
    let truths: HashMap<PathBuf, Trajectory> = files
        .into_par_iter()
        .map(|f| Ok((f.to_path_buf(), read(f)?)))
        .collect::<Result<_>>()?;
    let cells = cells
        .into_par_iter()
        .map(|cell| {
            let gt = &truths[&cell.ground_truth];
            compute_cell(cell, gt, &lengths)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Bench { lengths, cells })
}

fn read(path: &Path) -> Result<Trajectory> {
    read_tum(path)
        .map_err(|e| anyhow!("{e}"))
        .with_context(|| format!("{}", path.display()))
}

fn compute_cell(cell: Cell, gt: &Trajectory, lengths: &Lengths) -> Result<CellResult> {
    let lengths_m = match lengths {
        Lengths::Metres(m) => m.clone(),
        Lengths::Percent(p) => lengths_from_percents(cumulative_path_length(gt), p),
    };
    let runs = cell
        .runs
        .par_iter()
        .map(|file| {
            compute_run(gt, file, cell.alignment, &lengths_m).with_context(|| {
                format!("{} against {}", file.display(), cell.ground_truth.display())
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(CellResult {
        cell,
        lengths_m,
        runs,
    })
}

fn compute_run(
    gt: &Trajectory,
    file: &Path,
    alignment: RpgAlignment,
    lengths_m: &[f64],
) -> Result<RunResult> {
    let estimate = read(file)?;
    let pairs = rpg_associate(&estimate, gt, RPG_MAX_DIFF_NS);
    if pairs.len() < 2 {
        bail!(
            "{} poses paired with the ground truth (stamps within 0.02 s); 2 at least are needed",
            pairs.len()
        );
    }
    let est = estimate.reduce_to_ids(&pairs.iter().map(|p| p.0).collect::<Vec<_>>());
    let reference = gt.reduce_to_ids(&pairs.iter().map(|p| p.1).collect::<Vec<_>>());
    let transform = rpg_align(&est, &reference, alignment).map_err(|e| anyhow!("{e}"))?;
    let ape = Statistics::from_errors(&absolute_translation_errors(&est, &reference, &transform));
    let relative = relative_errors(&reference, &est, transform.scale, lengths_m)
        .map_err(|e| anyhow!("{e}"))?;
    let mut aligned = est;
    aligned.transform(
        glam::DQuat::from_mat3(&transform.rotation),
        transform.translation,
        transform.scale,
    );
    let options = DriftOptions {
        lengths_m: lengths_m.to_vec(),
        duration: SegmentDuration::Stamps,
        ..DriftOptions::default()
    };
    let drift = drift(&reference, &aligned, &options)
        .ok()
        .map(|d| (d.t_err_percent, d.r_err_deg_per_m));
    Ok(RunResult {
        file: file.to_path_buf(),
        pairs: pairs.len(),
        scale: transform.scale,
        ape_rmse: ape.rmse,
        relative,
        drift,
    })
}
