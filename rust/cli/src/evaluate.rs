//! `sitar evaluate`: the paper's evaluation protocol (section 3.3) against ground truth.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use plotters::prelude::*;
use sitar_estimator::{
    EstimateOptions, EvaluationOptions, EvaluationRow, PAPER_CLASSIFIERS, Setting, Thresholds,
    evaluate, ground_truth_errors,
};

use crate::input::{self, Format, progress_bar};
use crate::output::{emit, json_number};

/// The paper's trial counts.
const PAPER_COUNTS: [usize; 11] = [5, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100];

/// Scores the estimate against ground truth: accuracy and F1 per setting and trial count.
///
/// The paper's section 3.3 protocol: the true error of each window is the mean RPE against GT over the trials of set A; the
/// estimate comes from the first k trials of set B (a disjoint set), for each k and every
/// setting; both are classified low/medium/high with boundaries 5 & 10 cm, 2 & 10 cm and
/// 2 & 5 cm; reported are accuracy, macro F1 and mean per-class sensitivity and specificity.
/// Also draws accuracy and F1 against k per setting (the paper's Figure 5) as SVG.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  sitar simulate --out sim --trials 30 --second-set\n  sitar evaluate --ground-truth sim/ground_truth.txt --trials-a sim/trials --trials-b sim/trials-b --trial-counts 5,10,20,30"
)]
pub struct Args {
    /// Ground-truth trajectory.
    #[arg(long = "ground-truth", value_name = "GT")]
    ground_truth: PathBuf,
    /// Directory of trials (*.txt) giving the true average error per window (set A).
    #[arg(long = "trials-a", value_name = "DIR")]
    trials_a: PathBuf,
    /// Directory of other trials (*.txt) to estimate from (set B), used in natural order.
    #[arg(long = "trials-b", value_name = "DIR")]
    trials_b: PathBuf,
    /// Numbers of set-B trials to estimate from [default: 5,10,20,…,100 up to the size of B].
    #[arg(long = "trial-counts", value_delimiter = ',', value_name = "K,...")]
    trial_counts: Option<Vec<usize>>,
    /// Settings to evaluate [default: all seven].
    #[arg(long, value_delimiter = ',', value_parser = parse_setting, value_name = "SETTING,...")]
    settings: Option<Vec<Setting>>,
    /// RPE delta in frames (the sub-trajectory length).
    #[arg(short = 'd', long, default_value_t = 10)]
    delta: usize,
    /// Largest time difference (s) for associating poses.
    #[arg(long = "t-max-diff", alias = "t_max_diff", default_value_t = 0.01)]
    t_max_diff: f64,
    /// Format of the trajectory files.
    #[arg(short = 'i', long, value_enum, default_value_t)]
    input_format: Format,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Report::Table)]
    format: Report,
    /// Write the report to this file instead of stdout.
    #[arg(short = 'o', long)]
    output: Option<PathBuf>,
    /// Where to draw the accuracy/F1 plot (SVG).
    #[arg(long, default_value = "evaluation.svg")]
    plot: PathBuf,
    /// Do not draw the plot.
    #[arg(long = "no-plot")]
    no_plot: bool,
}

/// Report format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Report {
    /// Aligned text table.
    Table,
    /// One row per (boundaries, setting, trials).
    Csv,
    /// One JSON document.
    Json,
}

fn parse_setting(s: &str) -> Result<Setting, String> {
    s.parse().map_err(|e: sitar_estimator::Error| e.to_string())
}

pub fn run(args: Args) -> Result<()> {
    if args.delta == 0 {
        bail!("--delta must be at least 1 frame");
    }
    let files_a = input::trial_files(&args.trials_a)?;
    let files_b = input::trial_files(&args.trials_b)?;
    if files_b.len() < 2 {
        bail!(
            "{}: the estimate needs at least 2 trials, found {}",
            args.trials_b.display(),
            files_b.len()
        );
    }
    let counts: Vec<usize> = match &args.trial_counts {
        Some(counts) => {
            if let Some(&bad) = counts.iter().find(|&&k| k < 2 || k > files_b.len()) {
                bail!(
                    "--trial-counts: {bad} is not between 2 and the {} trials of set B",
                    files_b.len()
                );
            }
            counts.clone()
        }
        None => {
            let counts: Vec<usize> = PAPER_COUNTS
                .iter()
                .copied()
                .filter(|&k| k <= files_b.len())
                .collect();
            if counts.is_empty() {
                vec![files_b.len()]
            } else {
                counts
            }
        }
    };
    let settings = args
        .settings
        .clone()
        .unwrap_or_else(|| Setting::ALL.to_vec());

    let bar = progress_bar(
        (1 + files_a.len() + files_b.len()) as u64,
        "reading trajectories",
    );
    let gt = input::read(&args.ground_truth, args.input_format)?;
    bar.inc(1);
    let trials_a = input::read_all(&files_a, args.input_format, &bar)?;
    let trials_b = input::read_all(&files_b, args.input_format, &bar)?;
    bar.finish_and_clear();

    let estimate = EstimateOptions {
        delta: args.delta,
        t_max_diff_s: args.t_max_diff,
        ..EstimateOptions::default()
    };
    // Trials are numbered from 0 in natural file order in the estimator's messages.
    let context = || {
        format!(
            "evaluating (trial i = the i-th file of {} or {})",
            args.trials_a.display(),
            args.trials_b.display()
        )
    };
    let truth = ground_truth_errors(&gt, &trials_a, &estimate).with_context(context)?;
    let bar = progress_bar(counts.len() as u64, "estimating");
    let mut rows = Vec::new();
    for &k in &counts {
        let opts = EvaluationOptions {
            trial_counts: vec![k],
            settings: settings.clone(),
            boundaries: PAPER_CLASSIFIERS.to_vec(),
            estimate,
        };
        rows.extend(
            evaluate(&gt, &trials_a, &trials_b, &opts)
                .with_context(context)?
                .rows,
        );
        bar.inc(1);
    }
    bar.finish_and_clear();

    let truth_classes: Vec<[usize; 3]> = PAPER_CLASSIFIERS
        .iter()
        .map(|b| {
            let mut n = [0; 3];
            truth
                .iter()
                .for_each(|&(_, e)| n[b.classify(e).index().unwrap_or(0)] += 1);
            n
        })
        .collect();
    let summary = Summary {
        args: &args,
        truth_windows: truth.len(),
        truth_classes: &truth_classes,
        trials_a: files_a.len(),
        trials_b: files_b.len(),
    };
    let text = match args.format {
        Report::Table => table(&summary, &rows),
        Report::Csv => csv(&rows),
        Report::Json => json(&summary, &rows),
    };
    emit(args.output.as_deref(), &text)?;
    if !args.no_plot {
        plot(&args.plot, &rows, &settings, &counts)?;
        eprintln!("wrote the plot to {}", args.plot.display());
    }
    Ok(())
}

/// What the report says besides the rows.
struct Summary<'a> {
    args: &'a Args,
    truth_windows: usize,
    truth_classes: &'a [[usize; 3]],
    trials_a: usize,
    trials_b: usize,
}

fn cm(b: &Thresholds) -> String {
    format!("{} & {} cm", b.medium * 100.0, b.high * 100.0)
}

fn table(summary: &Summary<'_>, rows: &[EvaluationRow]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "ground truth: {} ({} windows, mean error over the {} trials of set A)",
        summary.args.ground_truth.display(),
        summary.truth_windows,
        summary.trials_a
    );
    let _ = writeln!(
        out,
        "estimates: first k of the {} trials of set B",
        summary.trials_b
    );
    for (bounds, n) in PAPER_CLASSIFIERS.iter().zip(summary.truth_classes) {
        let _ = writeln!(out);
        let _ = writeln!(
            out,
            "class boundaries {} (true windows: {} low, {} medium, {} high)",
            cm(bounds),
            n[0],
            n[1],
            n[2]
        );
        let _ = writeln!(
            out,
            "{:<14} {:>6} {:>8} {:>9} {:>8} {:>12} {:>12}",
            "setting", "trials", "windows", "accuracy", "F1", "sensitivity", "specificity"
        );
        for r in rows.iter().filter(|r| r.boundaries == *bounds) {
            let s = &r.scores;
            let _ = writeln!(
                out,
                "{:<14} {:>6} {:>8} {:>8.1}% {:>8.3} {:>12.3} {:>12.3}",
                r.setting.to_string(),
                r.trials,
                s.windows,
                100.0 * s.accuracy,
                s.macro_f1,
                s.sensitivity,
                s.specificity
            );
        }
    }
    out
}

fn csv(rows: &[EvaluationRow]) -> String {
    let mut out = String::from(
        "medium_m,high_m,setting,trials,windows,accuracy,macro_f1,sensitivity,specificity\n",
    );
    for r in rows {
        let s = &r.scores;
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{}",
            r.boundaries.medium,
            r.boundaries.high,
            r.setting,
            r.trials,
            s.windows,
            s.accuracy,
            s.macro_f1,
            s.sensitivity,
            s.specificity
        );
    }
    out
}

fn json(summary: &Summary<'_>, rows: &[EvaluationRow]) -> String {
    let results: Vec<serde_json::Value> = rows
        .iter()
        .map(|r| {
            let s = &r.scores;
            serde_json::json!({
                "boundaries_m": [r.boundaries.medium, r.boundaries.high],
                "setting": r.setting.to_string(),
                "trials": r.trials,
                "windows": s.windows,
                "accuracy": json_number(s.accuracy),
                "macro_f1": json_number(s.macro_f1),
                "sensitivity": json_number(s.sensitivity),
                "specificity": json_number(s.specificity),
                "confusion": s.confusion,
            })
        })
        .collect();
    let truth_classes: Vec<serde_json::Value> = PAPER_CLASSIFIERS
        .iter()
        .zip(summary.truth_classes)
        .map(|(b, n)| {
            serde_json::json!({
                "boundaries_m": [b.medium, b.high], "low": n[0], "medium": n[1], "high": n[2],
            })
        })
        .collect();
    serde_json::json!({
        "version": 1,
        "ground_truth": summary.args.ground_truth.display().to_string(),
        "trials_a": summary.trials_a,
        "trials_b": summary.trials_b,
        "delta": summary.args.delta,
        "truth_windows": summary.truth_windows,
        "truth_classes": truth_classes,
        "results": results,
    })
    .to_string()
        + "\n"
}

/// The paper's Figure 5: per class-boundary setting, accuracy (left) and F1 (right) against
/// the number of trials, one line per setting.
fn plot(path: &Path, rows: &[EvaluationRow], settings: &[Setting], counts: &[usize]) -> Result<()> {
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::new(path, (1100, 1200)).into_drawing_area();
        root.fill(&WHITE)?;
        let (title, body) = root.split_vertically(40);
        title.titled(
            "SiTAR uncertainty-based pose error estimation vs ground truth",
            ("sans-serif", 22),
        )?;
        let panels = body.split_evenly((PAPER_CLASSIFIERS.len(), 2));
        let x_max = counts.iter().copied().max().unwrap_or(2) as f64;
        let x_min = counts.iter().copied().min().unwrap_or(2) as f64;
        let x_range = if x_max > x_min {
            x_min..x_max
        } else {
            x_min - 1.0..x_max + 1.0
        };
        // A common y range for all panels, like the paper's, zoomed to the data.
        let lowest = rows
            .iter()
            .flat_map(|r| [r.scores.accuracy, r.scores.macro_f1])
            .filter(|v| v.is_finite())
            .fold(1.0f64, f64::min);
        let y_min = ((lowest - 0.05) * 10.0).floor().max(0.0) / 10.0;
        for (row, bounds) in PAPER_CLASSIFIERS.iter().enumerate() {
            for (col, metric) in ["accuracy", "F1"].iter().enumerate() {
                let value = |r: &EvaluationRow| {
                    if col == 0 {
                        r.scores.accuracy
                    } else {
                        r.scores.macro_f1
                    }
                };
                let mut chart = ChartBuilder::on(&panels[row * 2 + col])
                    .caption(
                        format!("{metric}, boundaries {}", cm(bounds)),
                        ("sans-serif", 16),
                    )
                    .margin(10)
                    .x_label_area_size(35)
                    .y_label_area_size(45)
                    .build_cartesian_2d(x_range.clone(), y_min..1.0)?;
                chart
                    .configure_mesh()
                    .max_light_lines(1)
                    .x_desc("trials")
                    .y_desc(*metric)
                    .x_label_formatter(&|x| format!("{x:.0}"))
                    .y_label_formatter(&|y| format!("{y:.2}"))
                    .draw()?;
                for (i, setting) in settings.iter().enumerate() {
                    let colour = Palette99::pick(i).to_rgba();
                    let points: Vec<(f64, f64)> = rows
                        .iter()
                        .filter(|r| r.boundaries == *bounds && r.setting == *setting)
                        .map(|r| (r.trials as f64, value(r)))
                        .filter(|(_, v)| v.is_finite())
                        .collect();
                    chart
                        .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))?
                        .label(setting.to_string())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                        });
                    chart
                        .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
                }
                if row == 0 && col == 1 {
                    chart
                        .configure_series_labels()
                        .position(SeriesLabelPosition::LowerRight)
                        .background_style(WHITE.mix(0.8))
                        .border_style(BLACK)
                        .draw()?;
                }
            }
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| anyhow::anyhow!("{}: cannot draw the plot: {e}", path.display()))
}
