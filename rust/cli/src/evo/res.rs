//! `sitar res`: one or several result archives (evo's or sitar's `--save_results`), as
//! `evo_res`: the statistics table as evo prints it (pandas' layout), `--save_table` (CSV),
//! `--merge`, and the plots of the raw values and the statistics.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};

use crate::figures::canvas::{self, Page};
use crate::figures::figure::{DistributionKind, Drawing, PAGE, PALETTE, Series};
use crate::io::console::{Console, SEP, UsabilityArgs};
use crate::results::archive::ResultArchive;

/// Tool for processing one or multiple result files, as evo_res.
#[derive(clap::Args, Debug)]
#[command(
    args_override_self = true,
    after_help = "Examples:\n  sitar res ape_a.zip ape_b.zip --use_filenames\n  sitar res results/*.zip --save_table table.csv --save_plot res.pdf"
)]
pub struct Args {
    /// One or multiple result files: evo's .zip archives, or the .json of `sitar ape|rpe
    /// --format json` (with several runs, one result per run).
    #[arg(required = true)]
    result_files: Vec<PathBuf>,
    /// Merge the results into a single one (averaged, or appended for other lengths).
    #[arg(long)]
    merge: bool,
    /// Use relative timestamps if available.
    #[arg(long = "use_rel_time")]
    use_rel_time: bool,
    /// Use the filenames to label the data.
    #[arg(long = "use_filenames")]
    use_filenames: bool,
    /// Don't try to find a common metric title.
    #[arg(long = "ignore_title")]
    ignore_title: bool,
    /// Show the plots (evo's -p); without a display sitar says so and shows nothing.
    #[arg(short = 'p', long)]
    plot: bool,
    /// Plot with circle markers.
    #[arg(long = "plot_markers")]
    plot_markers: bool,
    /// Path to save the plots: PNG, SVG or PDF by the extension (FILE_raw.png,
    /// FILE_stats.png, FILE_box_plot.png, FILE_histogram.png, FILE_violin_histogram.png, as
    /// evo; one PDF with every page).
    #[arg(long = "save_plot", value_name = "FILE")]
    save_plot: Option<PathBuf>,
    /// Path to a file to save the statistics in a table (CSV, one row per result).
    #[arg(long = "save_table", value_name = "FILE")]
    save_table: Option<PathBuf>,
    /// Log to Rerun (not supported by sitar).
    #[arg(long)]
    rerun: bool,
    /// Rerun recording ID (not supported by sitar).
    #[arg(long = "rerun_rec_id")]
    rerun_rec_id: Option<String>,
    #[command(flatten)]
    usability: UsabilityArgs,
}

/// The results in `path`: an evo archive (`.zip`), or SiTAR's `--format json` output of
/// `ape`/`rpe` (`.json`): one result, or one per run of a repeated-runs document
/// (`"trials"`), named `FILE[k]`.
fn read_results(path: &std::path::Path) -> Result<Vec<(String, ResultArchive)>> {
    let file = path.display().to_string();
    let is_json = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    if !is_json {
        return Ok(vec![(file, ResultArchive::read(path)?)]);
    }
    let text = std::fs::read_to_string(path).with_context(|| format!("{file}: cannot read"))?;
    let doc: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{file}: not JSON"))?;
    match doc.get("trials").and_then(serde_json::Value::as_array) {
        Some(trials) => trials
            .iter()
            .enumerate()
            .map(|(k, trial)| {
                let name = format!("{file}[{k}]");
                Ok((name.clone(), archive_of_document(trial, &name)?))
            })
            .collect(),
        None => Ok(vec![(file.clone(), archive_of_document(&doc, &file)?)]),
    }
}

/// The archive of one `ape`/`rpe` JSON document: its title, names and label, its statistics
/// and its errors (as `error_array`).
fn archive_of_document(doc: &serde_json::Value, file: &str) -> Result<ResultArchive> {
    let text = |key: &str| doc.get(key).and_then(serde_json::Value::as_str);
    let (Some(metric), Some(stats), Some(errors)) = (
        text("metric"),
        doc.get("statistics").and_then(serde_json::Value::as_object),
        doc.get("errors").and_then(serde_json::Value::as_array),
    ) else {
        bail!(
            "{file}: not an ape or rpe result of `--format json` (a {} result has no errors for res)",
            text("metric").unwrap_or("different")
        );
    };
    let number =
        |v: Option<&serde_json::Value>| v.and_then(serde_json::Value::as_f64).unwrap_or(f64::NAN);
    let info = [
        ("title", text("title").unwrap_or_default().to_owned()),
        ("ref_name", text("reference").unwrap_or_default().to_owned()),
        ("est_name", text("estimate").unwrap_or_default().to_owned()),
        (
            "label",
            format!(
                "{} ({})",
                metric.to_uppercase(),
                text("unit").unwrap_or_default()
            ),
        ),
    ];
    Ok(ResultArchive {
        info: info.map(|(k, v)| (k.to_owned(), v)).to_vec(),
        stats: ["rmse", "mean", "median", "std", "min", "max", "sse"]
            .iter()
            .filter(|k| stats.contains_key(**k))
            .map(|k| ((*k).to_owned(), number(stats.get(*k))))
            .collect(),
        arrays: vec![(
            "error_array".to_owned(),
            crate::results::archive::Array::vector(
                errors.iter().map(|e| number(e.get("error"))).collect(),
            ),
        )],
    })
}

/// One loaded result and its label.
struct Labelled {
    label: String,
    file: String,
    archive: ResultArchive,
}

pub fn run(args: Args) -> Result<()> {
    let console = Console::new(&args.usability)?;
    if args.rerun || args.rerun_rec_id.is_some() {
        bail!("--rerun is not supported by sitar (it needs evo's optional viewers)");
    }
    let mut results = Vec::new();
    for (file, archive) in args
        .result_files
        .iter()
        .map(|path| read_results(path))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
    {
        let label = if args.use_filenames {
            file.clone()
        } else {
            archive
                .info("est_name")
                .map(|n| {
                    std::path::Path::new(n)
                        .file_name()
                        .map_or_else(|| n.to_owned(), |b| b.to_string_lossy().into_owned())
                })
                .unwrap_or_else(|| "unnamed_result".into())
        };
        results.push(Labelled {
            label,
            file,
            archive,
        });
    }
    if args.merge && results.len() > 1 {
        let merged = merge(&results, &console)?;
        let label = merged
            .info("est_name")
            .map(|n| {
                std::path::Path::new(n)
                    .file_name()
                    .map_or_else(|| n.to_owned(), |b| b.to_string_lossy().into_owned())
            })
            .unwrap_or_else(|| "unnamed_result".into());
        let file = results[0].file.clone();
        results = vec![Labelled {
            label,
            file,
            archive: merged,
        }];
    }
    let mut seen = std::collections::BTreeSet::new();
    let duplicates: Vec<&str> = results
        .iter()
        .filter(|r| !seen.insert(r.label.as_str()))
        .map(|r| r.label.as_str())
        .collect();
    if !duplicates.is_empty() {
        bail!(
            "Values of 'est_name' must be unique - duplicates: {} (try --use_filenames to label by file name)",
            duplicates.join(", ")
        );
    }
    let title = if args.ignore_title {
        String::new()
    } else {
        results[0]
            .archive
            .info("title")
            .unwrap_or_default()
            .to_owned()
    };
    if !args.ignore_title {
        for r in &results[1..] {
            let other = r.archive.info("title").unwrap_or_default();
            if other != title {
                console.warn(&format!(
                    "Mismatching titles - risk of aggregating data from different metrics ({} has '{}', {} has '{}'); only the first one is used as the title (--ignore_title to aggregate silently)",
                    results[0].file,
                    title.replace('\n', " "),
                    r.file,
                    other.replace('\n', " ")
                ));
            }
        }
    }
    console.debug(SEP)?;
    if !args.ignore_title {
        console.info(&format!("\n{title}\n\n"))?;
    }
    let keys = stat_keys(&results);
    console.info(&(table(&results, &keys) + "\n"))?;
    if let Some(path) = &args.save_table {
        console.debug(SEP)?;
        if path.exists() {
            console.warn(&format!("{} exists, overwriting", path.display()));
        }
        std::fs::write(path, csv(&results, &keys))
            .map_err(|e| anyhow::anyhow!("{}: cannot write the table: {e}", path.display()))?;
    }
    if args.plot || args.save_plot.is_some() {
        plot(&args, &results, &keys, &title, &console)?;
    }
    Ok(())
}

/// The statistics' names in the first result's order, then any others.
fn stat_keys(results: &[Labelled]) -> Vec<String> {
    let mut keys: Vec<String> = Vec::new();
    for r in results {
        for (k, _) in &r.archive.stats {
            if !keys.contains(k) {
                keys.push(k.clone());
            }
        }
    }
    keys
}

fn stat(r: &Labelled, key: &str) -> Option<f64> {
    r.archive
        .stats
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| *v)
}

/// The table as pandas prints `df.loc["stats"].T.to_string(line_width=80)`: the labels
/// left-aligned, each column right-aligned to its widest cell, two spaces apart; columns
/// that do not fit in 80 characters continue in blocks below (pandas' `_binify`), the lines
/// of a continued block ending in `  \\` (header) or three spaces.
fn table(results: &[Labelled], keys: &[String]) -> String {
    let index_width = results
        .iter()
        .map(|r| r.label.chars().count())
        .max()
        .unwrap_or(0);
    let columns: Vec<(String, Vec<String>, usize)> = keys
        .iter()
        .map(|k| {
            let cells: Vec<String> = results
                .iter()
                .map(|r| stat(r, k).map_or_else(|| "NaN".into(), sitar_evo::pyfmt::pandas_cell))
                .collect();
            let width = cells
                .iter()
                .map(String::len)
                .chain([k.len()])
                .max()
                .unwrap_or(0);
            (k.clone(), cells, width)
        })
        .collect();
    // pandas: each column is `width + 1` characters with its sign space, plus one to adjoin;
    // a column wraps when the running width (+2, or +1 for the last) exceeds the line.
    let line_width = 80 - (index_width + 1);
    let mut bins = Vec::new();
    let mut current = 0;
    for (i, c) in columns.iter().enumerate() {
        let adjoined = c.2 + 3;
        current += adjoined;
        let margin = if i + 1 == columns.len() { 1 } else { 2 };
        if i > 0 && current + margin > line_width {
            bins.push(i);
            current = adjoined;
        }
    }
    bins.push(columns.len());
    let several = bins.len() > 1;
    let mut blocks = Vec::new();
    let mut start = 0;
    for (b, &end) in bins.iter().enumerate() {
        let mut lines = vec![" ".repeat(index_width)];
        lines.extend(results.iter().map(|r| format!("{:<index_width$}", r.label)));
        for (name, cells, width) in &columns[start..end] {
            lines[0] += &format!("  {name:>width$}");
            for (k, cell) in cells.iter().enumerate() {
                lines[k + 1] += &format!("  {cell:>width$}");
            }
        }
        if several {
            let continued = b + 1 < bins.len();
            for (k, line) in lines.iter_mut().enumerate() {
                line.push_str(match (continued, k) {
                    (true, 0) => "  \\",
                    (true, _) => "   ",
                    (false, _) => "  ",
                });
            }
        }
        blocks.push(lines.join("\n"));
        start = end;
    }
    blocks.join("\n\n")
}

/// evo's `--save_table` (pandas `to_csv` of the transposed stats): `,rmse,mean,…` then one
/// row per result, numbers as Python writes them.
fn csv(results: &[Labelled], keys: &[String]) -> String {
    let mut out = format!(",{}\n", keys.join(","));
    for r in results {
        out += &r.label;
        for k in keys {
            out.push(',');
            if let Some(v) = stat(r, k) {
                out += &sitar_evo::pyfmt::repr(v);
            }
        }
        out.push('\n');
    }
    out
}

/// evo's `merge_results`: statistics averaged; arrays averaged when all have the same
/// lengths, appended otherwise; the first result's info.
fn merge(results: &[Labelled], console: &Console) -> Result<ResultArchive> {
    let first = &results[0].archive;
    let names =
        |a: &ResultArchive| -> Vec<String> { a.arrays.iter().map(|(k, _)| k.clone()).collect() };
    let stat_names =
        |a: &ResultArchive| -> Vec<String> { a.stats.iter().map(|(k, _)| k.clone()).collect() };
    for r in &results[1..] {
        let (mut a, mut b) = (names(first), names(&r.archive));
        a.sort();
        b.sort();
        let (mut c, mut d) = (stat_names(first), stat_names(&r.archive));
        c.sort();
        d.sort();
        if a != b || c != d {
            bail!(
                "can't merge results with non-matching keys ({} and {})",
                results[0].file,
                r.file
            );
        }
    }
    let same_lengths = results.iter().all(|r| {
        first.arrays.iter().all(|(k, v)| {
            r.archive
                .array(k)
                .is_some_and(|w| w.data.len() == v.data.len())
        })
    });
    if same_lengths {
        console.info("Averaging raw values of input results in merged result.")?;
    } else {
        console.warn("Appending raw value arrays due to different lengths.");
    }
    console.warn("Using info dict of first result.");
    let n = results.len() as f64;
    let mut merged = first.clone();
    for (k, v) in &mut merged.stats {
        let sum: f64 = results.iter().filter_map(|r| stat(r, k)).sum();
        *v = sum / n;
    }
    for (k, array) in &mut merged.arrays {
        if same_lengths {
            for (i, value) in array.data.iter_mut().enumerate() {
                let sum: f64 = results
                    .iter()
                    .filter_map(|r| r.archive.array(k).map(|a| a.data[i]))
                    .sum();
                *value = sum / n;
            }
        } else {
            let mut all = Vec::new();
            for r in results {
                if let Some(a) = r.archive.array(k) {
                    all.extend_from_slice(&a.data);
                }
            }
            array.shape = vec![all.len()];
            array.data = all;
        }
    }
    Ok(merged)
}

/// evo_res's raw values over the common index and the statistics as bars.
fn plot(
    args: &Args,
    results: &[Labelled],
    keys: &[String],
    title: &str,
    console: &Console,
) -> Result<()> {
    let mut index = ["timestamps", "seconds_from_start", "sec_from_start"].as_slice();
    if args.use_rel_time {
        index = &index[1..];
    }
    let common = index
        .iter()
        .find(|k| results.iter().all(|r| r.archive.array(k).is_some()))
        .copied();
    let label = results[0].archive.info("label").unwrap_or("").to_owned();
    let series: Vec<Series> = results
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let errors = r
                .archive
                .array("error_array")
                .map(|a| a.data.clone())
                .unwrap_or_default();
            let xs: Vec<f64> = match common.and_then(|k| r.archive.array(k)) {
                Some(a) => a.data.clone(),
                None => (0..errors.len()).map(|k| k as f64).collect(),
            };
            Series {
                name: r.label.clone(),
                points: xs.into_iter().zip(errors).collect(),
                colour: PALETTE[i % PALETTE.len()],
                dashed: false,
                markers: false,
            }
        })
        .collect();
    let _ = args.plot_markers;
    let raw = Drawing::Panels {
        title: title.to_owned(),
        x_label: if common.is_some() {
            "t (s)".into()
        } else {
            "index".into()
        },
        panels: vec![(label.clone(), series)],
        y_from_zero: false,
    };
    let shown: Vec<String> = ["rmse", "median", "mean", "std", "min", "max"]
        .iter()
        .filter(|k| keys.iter().any(|x| x == *k))
        .map(|k| (*k).to_owned())
        .collect();
    let stats_label = label.clone();
    let stats = Drawing::Bars {
        title: title.to_owned(),
        x_label: label,
        groups: shown.clone(),
        series: results
            .iter()
            .map(|r| {
                (
                    r.label.clone(),
                    shown
                        .iter()
                        .map(|k| stat(r, k).unwrap_or(f64::NAN))
                        .collect(),
                )
            })
            .collect(),
    };
    let distributions = |kind| Drawing::Distributions {
        title: title.to_owned(),
        label: stats_label.clone(),
        kind,
        groups: results
            .iter()
            .map(|r| {
                let values = r.archive.array("error_array").map(|a| a.data.clone());
                (r.label.clone(), values.unwrap_or_default())
            })
            .collect(),
    };
    let (box_plot, histogram, violin) = (
        distributions(DistributionKind::Box),
        distributions(DistributionKind::Histogram),
        distributions(DistributionKind::Violin),
    );
    let pages = [
        ("raw", Page::Other(&raw)),
        ("stats", Page::Other(&stats)),
        ("box_plot", Page::Other(&box_plot)),
        ("histogram", Page::Other(&histogram)),
        ("violin_histogram", Page::Other(&violin)),
    ];
    if args.plot {
        canvas::show(PAGE, &pages, console)?;
    }
    if let Some(path) = &args.save_plot {
        for file in canvas::save_collection(path, PAGE, &pages)? {
            console.info(&format!("Plot saved to {}", file.display()))?;
        }
    }
    Ok(())
}
