//! Repeated runs of one system (`sitar ape|rpe|drift FORMAT REF EST1 EST2 …`): each run's
//! result, and for each statistic its mean, median, min, max and std (numpy's, ddof 0) over
//! the runs. One estimate never comes here: it keeps evo's output.

use std::path::{Path, PathBuf};

use anyhow::Result;
use sitar_evo::document::STATS;
use sitar_evo::metric::Outcome;

use crate::figures::canvas::{self, Page};
use crate::figures::figure::{DistributionKind, Drawing, PAGE};
use crate::io::console::{Console, SEP};
use crate::io::output::{OutputFormat, emit};
use crate::results::metric_args::OutputArgs;

// The summaries over runs are the library's (the JSON documents use them too).
pub use sitar_evo::document::{ACROSS, across};

/// A text table: the first `left` columns left-aligned, the others right-aligned, two
/// spaces apart.
pub fn table(header: &[&str], rows: &[Vec<String>], left: usize) -> String {
    let widths: Vec<usize> = (0..header.len())
        .map(|c| {
            rows.iter()
                .map(|r| r[c].chars().count())
                .chain([header[c].chars().count()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let line = |cells: Vec<&str>| {
        let mut text = String::new();
        for (c, cell) in cells.iter().enumerate() {
            if c > 0 {
                text.push_str("  ");
            }
            let w = widths[c];
            if c < left {
                text.push_str(&format!("{cell:<w$}"));
            } else {
                text.push_str(&format!("{cell:>w$}"));
            }
        }
        text.trim_end().to_owned() + "\n"
    };
    let mut text = line(header.to_vec());
    for row in rows {
        text += &line(row.iter().map(String::as_str).collect());
    }
    text
}

/// The table of a statistic's summary over runs: one row per statistic.
pub fn across_table(names: &[&str], value: impl Fn(usize, &str) -> f64, runs: usize) -> String {
    let mut header = vec!["across trials"];
    header.extend(ACROSS);
    let rows: Vec<Vec<String>> = names
        .iter()
        .map(|name| {
            let values: Vec<f64> = (0..runs).map(|k| value(k, name)).collect();
            std::iter::once((*name).to_owned())
                .chain(across(&values).iter().map(|v| format!("{v:.6}")))
                .collect()
        })
        .collect();
    table(&header, &rows, 1)
}

/// `DIR/STEM_trialK.EXT` beside `path`: run `k`'s file of a per-run output.
pub fn trial_path(path: &Path, k: usize) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match path.extension() {
        Some(e) => format!("{stem}_trial{k}.{}", e.to_string_lossy()),
        None => format!("{stem}_trial{k}"),
    };
    path.with_file_name(name)
}

/// A distribution page's group label: the run's file name (evo_res labels by file name).
pub fn run_label(name: &str) -> String {
    crate::results::compare::file_name(Path::new(name))
}

/// Writes `pages` as `-p` (show) and `--save_plot FILE` say, and the first page to SiTAR's
/// `--plot FILE`.
pub fn plots(
    pages: &[(&str, Page<'_>)],
    show: bool,
    save_plot: Option<&Path>,
    single_file: Option<&Path>,
    console: &Console,
) -> Result<()> {
    if let (Some(path), Some((_, page))) = (single_file, pages.first()) {
        canvas::save_one(path, PAGE, page)?;
        console.debug(&format!("Plot saved to {}", path.display()))?;
    }
    if show {
        canvas::show(PAGE, pages, console)?;
    }
    if let Some(path) = save_plot {
        for file in canvas::save_collection(path, PAGE, pages)? {
            console.info(&format!("Plot saved to {}", file.display()))?;
        }
    }
    Ok(())
}

/// Prints, saves and plots the outcomes of `ape`/`rpe` on several runs: the per-run and the
/// across-runs tables (or `--format csv|json`), one evo archive per run
/// (`--save_results FILE.zip` → `FILE_trialK.zip`), and a box plot of each run's errors.
pub fn finish(outcomes: &[Outcome], output: &OutputArgs, console: &Console) -> Result<()> {
    let n = outcomes.len();
    let value = |k: usize, name: &str| outcomes[k].stat(name);
    let single_file = output
        .plot
        .as_deref()
        .filter(|p| !p.is_empty())
        .map(Path::new);
    let label = outcomes[0].label();
    let box_plot = Drawing::Distributions {
        title: format!("{}\n{n} runs", outcomes[0].title),
        label: label.clone(),
        kind: DistributionKind::Box,
        groups: outcomes
            .iter()
            .map(|o| (run_label(&o.est_name), o.errors.errors.clone()))
            .collect(),
    };
    let pages = [("box_plot", Page::Other(&box_plot))];
    // An unwritable `--plot FILE` fails before anything is printed, as for one run.
    plots(&pages[..1], false, None, single_file, console)?;
    match output.format {
        Some(OutputFormat::Json) => {
            let doc = sitar_evo::document::runs_json(outcomes);
            emit(output.output.as_deref(), &(doc.to_string() + "\n"))?;
        }
        Some(OutputFormat::Csv) => {
            let mut text = format!("trial,estimate,{}\n", STATS.join(","));
            for (k, o) in outcomes.iter().enumerate() {
                text += &format!("{k},{}", csv_field(&o.est_name));
                for name in STATS {
                    text += &format!(",{}", value(k, name));
                }
                text.push('\n');
            }
            for (i, summary) in ACROSS.iter().enumerate() {
                text += &format!("{summary},");
                for name in STATS {
                    let values: Vec<f64> = (0..n).map(|k| value(k, name)).collect();
                    text += &format!(",{}", across(&values)[i]);
                }
                text.push('\n');
            }
            emit(output.output.as_deref(), &text)?;
        }
        None => {
            console.debug(SEP)?;
            let mut header = vec!["trial", "estimate"];
            header.extend(STATS);
            let rows: Vec<Vec<String>> = outcomes
                .iter()
                .enumerate()
                .map(|(k, o)| {
                    [k.to_string(), o.est_name.clone()]
                        .into_iter()
                        .chain(STATS.iter().map(|s| format!("{:.6}", value(k, s))))
                        .collect()
                })
                .collect();
            console.info(&format!(
                "{}\n\n{n} runs against {}\n\n{}\n{}",
                outcomes[0].title,
                outcomes[0].ref_name,
                table(&header, &rows, 2),
                across_table(&STATS, value, n)
            ))?;
        }
    }
    let show = output.plot.as_ref().is_some_and(|p| p.is_empty());
    plots(&pages, show, output.save_plot.as_deref(), None, console)?;
    if let Some(path) = &output.html {
        crate::figures::html::write(path, &sitar_evo::document::runs_json(outcomes), &pages)?;
        console.debug(&format!("Page saved to {}", path.display()))?;
    }
    if let Some(path) = &output.save_results {
        console.debug(SEP)?;
        for (k, outcome) in outcomes.iter().enumerate() {
            let file = trial_path(path, k);
            if file.exists() {
                console.warn(&format!("{} exists, overwriting", file.display()));
            }
            crate::results::archive::ResultArchive::of(outcome).write(&file)?;
            console.debug(&format!("Saved results to {}", file.display()))?;
        }
    }
    Ok(())
}

/// A CSV field, quoted when it holds a comma, a quote or a line break.
pub fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn across_runs_is_numpy_mean_median_min_max_and_population_std() {
        let [mean, median, min, max, std] = across(&[1.0, 4.0, 2.0, 3.0]);
        assert_eq!((mean, median, min, max), (2.5, 2.5, 1.0, 4.0));
        assert_eq!(std, 1.25f64.sqrt());
    }

    #[test]
    fn trial_files_sit_beside_the_named_one() {
        assert_eq!(
            trial_path(Path::new("out/ape.zip"), 3),
            Path::new("out/ape_trial3.zip")
        );
        assert_eq!(trial_path(Path::new("res"), 0), Path::new("res_trial0"));
    }

    #[test]
    fn tables_align_their_columns() {
        let text = table(
            &["a", "bb"],
            &[
                vec!["xyz".into(), "1".into()],
                vec!["q".into(), "22.5".into()],
            ],
            1,
        );
        assert_eq!(text, "a      bb\nxyz     1\nq    22.5\n");
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("plain"), "plain");
    }
}
