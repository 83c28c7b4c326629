//! `sitar evaluate`: the paper's evaluation protocol (section 3.3) against ground truth.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use plotters::prelude::*;
use rayon::prelude::*;
use sitar_estimator::{
    DeltaUnit, EstimateOptions, PairwiseValues, PoseRelation, RpeOptions, Setting, Trajectory,
    associate_trajectories, rpe, seconds_to_ns,
};

use crate::input::{self, Format, progress_bar};
use crate::output::{emit, json_number};

/// The paper's class boundaries (low | medium | high), metres.
const BOUNDARIES: [(f64, f64); 3] = [(0.05, 0.10), (0.02, 0.10), (0.02, 0.05)];
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

/// Classifier quality of one (boundaries, setting, trial count).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Scores {
    boundaries: (f64, f64),
    setting: Setting,
    trials: usize,
    windows: usize,
    accuracy: f64,
    macro_f1: f64,
    sensitivity: f64,
    specificity: f64,
}

/// 0 low, 1 medium, 2 high.
fn class(error: f64, (medium, high): (f64, f64)) -> usize {
    if error >= high {
        2
    } else if error >= medium {
        1
    } else {
        0
    }
}

/// Accuracy, macro F1, mean sensitivity and mean specificity of 3-class predictions, averaged
/// over the classes present in truth or prediction (as scikit-learn's macro average); a
/// class without positives (or negatives) has no sensitivity (or specificity) to average.
fn classification_scores(truth: &[usize], predicted: &[usize]) -> (f64, f64, f64, f64) {
    let mut confusion = [[0usize; 3]; 3];
    for (&t, &p) in truth.iter().zip(predicted) {
        confusion[t][p] += 1;
    }
    let total = truth.len();
    let correct: usize = (0..3).map(|c| confusion[c][c]).sum();
    let (mut f1, mut sensitivity, mut specificity) = (Vec::new(), Vec::new(), Vec::new());
    for (c, row) in confusion.iter().enumerate() {
        let tp = row[c];
        let fn_ = row.iter().sum::<usize>() - tp;
        let fp = confusion.iter().map(|r| r[c]).sum::<usize>() - tp;
        let tn = total - tp - fn_ - fp;
        // Classes neither true nor predicted do not count (scikit-learn's default labels).
        if tp + fn_ + fp == 0 {
            continue;
        }
        f1.push(2.0 * tp as f64 / (2 * tp + fp + fn_) as f64);
        if tp + fn_ > 0 {
            sensitivity.push(tp as f64 / (tp + fn_) as f64);
        }
        if tn + fp > 0 {
            specificity.push(tn as f64 / (tn + fp) as f64);
        }
    }
    let mean = |v: &[f64]| {
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    (
        correct as f64 / total as f64,
        mean(&f1),
        mean(&sensitivity),
        mean(&specificity),
    )
}

/// Mean RPE against `gt` per GT window start over `trials` (sorted by start).
fn true_errors(
    gt: &Trajectory,
    trials: &[Trajectory],
    files: &[PathBuf],
    opts: &RpeOptions,
    t_max_diff: f64,
) -> Result<Vec<(i64, f64)>> {
    let per_trial: Vec<Vec<(i64, f64)>> = trials
        .par_iter()
        .zip(files)
        .map(|(trial, file)| -> Result<Vec<(i64, f64)>> {
            let (reference, estimate) = associate_trajectories(gt, trial, t_max_diff, 0.0)
                .with_context(|| format!("associating the ground truth with {}", file.display()))?;
            let errors = rpe(&reference, &estimate, opts)
                .with_context(|| format!("RPE of {} against the ground truth", file.display()))?;
            Ok(errors
                .pairs
                .iter()
                .zip(&errors.errors)
                .map(|(&(i, _), &e)| (reference.stamps[i], e))
                .collect())
        })
        .collect::<Result<_>>()?;
    let mut sums: BTreeMap<i64, (f64, usize)> = BTreeMap::new();
    for (start, e) in per_trial.into_iter().flatten() {
        let entry = sums.entry(start).or_default();
        entry.0 += e;
        entry.1 += 1;
    }
    Ok(sums
        .into_iter()
        .map(|(k, (s, n))| (k, s / n as f64))
        .collect())
}

/// The true error of the window nearest to `start` within `tolerance`.
fn nearest(truth: &[(i64, f64)], start: i64, tolerance: i64) -> Option<f64> {
    let i = truth.partition_point(|&(k, _)| k < start);
    [i.checked_sub(1), Some(i)]
        .into_iter()
        .flatten()
        .filter_map(|j| truth.get(j))
        .filter(|(k, _)| (k - start).abs() <= tolerance)
        .min_by_key(|(k, _)| (k - start).abs())
        .map(|&(_, e)| e)
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

    let rpe_opts = RpeOptions {
        pose_relation: PoseRelation::TranslationPart,
        delta: args.delta as f64,
        delta_unit: DeltaUnit::Frames,
        all_pairs: true,
        ..RpeOptions::default()
    };
    let truth = true_errors(&gt, &trials_a, &files_a, &rpe_opts, args.t_max_diff)?;
    let tolerance = seconds_to_ns(args.t_max_diff);

    let bar = progress_bar(counts.len() as u64, "estimating");
    let mut scores = Vec::new();
    for &k in &counts {
        let opts = EstimateOptions {
            delta: args.delta,
            t_max_diff_s: args.t_max_diff,
            ..EstimateOptions::default()
        };
        let pairwise = PairwiseValues::compute(&trials_b[..k], &opts)
            .with_context(|| format!("estimating from the first {k} trials of set B"))?;
        for &setting in &settings {
            let estimate = pairwise.estimate(setting);
            let (mut t, mut e) = (Vec::new(), Vec::new());
            for w in &estimate.windows {
                if let Some(true_error) = nearest(&truth, w.start, tolerance) {
                    t.push(true_error);
                    e.push(w.error_m);
                }
            }
            if t.is_empty() {
                bail!("no estimated window matches a ground-truth window (check --t-max-diff)");
            }
            for boundaries in BOUNDARIES {
                let tc: Vec<usize> = t.iter().map(|&x| class(x, boundaries)).collect();
                let ec: Vec<usize> = e.iter().map(|&x| class(x, boundaries)).collect();
                let (accuracy, macro_f1, sensitivity, specificity) =
                    classification_scores(&tc, &ec);
                scores.push(Scores {
                    boundaries,
                    setting,
                    trials: k,
                    windows: t.len(),
                    accuracy,
                    macro_f1,
                    sensitivity,
                    specificity,
                });
            }
        }
        bar.inc(1);
    }
    bar.finish_and_clear();

    let truth_classes: Vec<[usize; 3]> = BOUNDARIES
        .iter()
        .map(|&b| {
            let mut n = [0; 3];
            truth.iter().for_each(|&(_, e)| n[class(e, b)] += 1);
            n
        })
        .collect();
    let text = match args.format {
        Report::Table => table(
            &args,
            &truth,
            &truth_classes,
            files_a.len(),
            files_b.len(),
            &scores,
        ),
        Report::Csv => csv(&scores),
        Report::Json => json(
            &args,
            &truth,
            &truth_classes,
            files_a.len(),
            files_b.len(),
            &scores,
        ),
    };
    emit(args.output.as_deref(), &text)?;
    if !args.no_plot {
        plot(&args.plot, &scores, &settings, &counts)?;
        eprintln!("wrote the plot to {}", args.plot.display());
    }
    Ok(())
}

fn cm(b: (f64, f64)) -> String {
    format!("{} & {} cm", b.0 * 100.0, b.1 * 100.0)
}

fn table(
    args: &Args,
    truth: &[(i64, f64)],
    classes: &[[usize; 3]],
    a: usize,
    b: usize,
    scores: &[Scores],
) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "ground truth: {} ({} windows, mean error over the {a} trials of set A)",
        args.ground_truth.display(),
        truth.len()
    );
    let _ = writeln!(out, "estimates: first k of the {b} trials of set B");
    for (bounds, n) in BOUNDARIES.iter().zip(classes) {
        let _ = writeln!(out);
        let _ = writeln!(
            out,
            "class boundaries {} (true windows: {} low, {} medium, {} high)",
            cm(*bounds),
            n[0],
            n[1],
            n[2]
        );
        let _ = writeln!(
            out,
            "{:<14} {:>6} {:>8} {:>9} {:>8} {:>12} {:>12}",
            "setting", "trials", "windows", "accuracy", "F1", "sensitivity", "specificity"
        );
        for s in scores.iter().filter(|s| s.boundaries == *bounds) {
            let _ = writeln!(
                out,
                "{:<14} {:>6} {:>8} {:>8.1}% {:>8.3} {:>12.3} {:>12.3}",
                s.setting.to_string(),
                s.trials,
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

fn csv(scores: &[Scores]) -> String {
    let mut out = String::from(
        "medium_m,high_m,setting,trials,windows,accuracy,macro_f1,sensitivity,specificity\n",
    );
    for s in scores {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{}",
            s.boundaries.0,
            s.boundaries.1,
            s.setting,
            s.trials,
            s.windows,
            s.accuracy,
            s.macro_f1,
            s.sensitivity,
            s.specificity
        );
    }
    out
}

fn json(
    args: &Args,
    truth: &[(i64, f64)],
    classes: &[[usize; 3]],
    a: usize,
    b: usize,
    scores: &[Scores],
) -> String {
    let results: Vec<serde_json::Value> = scores
        .iter()
        .map(|s| {
            serde_json::json!({
                "boundaries_m": [s.boundaries.0, s.boundaries.1],
                "setting": s.setting.to_string(),
                "trials": s.trials,
                "windows": s.windows,
                "accuracy": json_number(s.accuracy),
                "macro_f1": json_number(s.macro_f1),
                "sensitivity": json_number(s.sensitivity),
                "specificity": json_number(s.specificity),
            })
        })
        .collect();
    let truth_classes: Vec<serde_json::Value> = BOUNDARIES
        .iter()
        .zip(classes)
        .map(|(b, n)| serde_json::json!({"boundaries_m": [b.0, b.1], "low": n[0], "medium": n[1], "high": n[2]}))
        .collect();
    serde_json::json!({
        "version": 1,
        "ground_truth": args.ground_truth.display().to_string(),
        "trials_a": a,
        "trials_b": b,
        "delta": args.delta,
        "truth_windows": truth.len(),
        "truth_classes": truth_classes,
        "results": results,
    })
    .to_string()
        + "\n"
}

/// The paper's Figure 5: per class-boundary setting, accuracy (left) and F1 (right) against
/// the number of trials, one line per setting.
fn plot(path: &Path, scores: &[Scores], settings: &[Setting], counts: &[usize]) -> Result<()> {
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::new(path, (1100, 1200)).into_drawing_area();
        root.fill(&WHITE)?;
        let (title, body) = root.split_vertically(40);
        title.titled(
            "SiTAR uncertainty-based pose error estimation vs ground truth",
            ("sans-serif", 22),
        )?;
        let panels = body.split_evenly((BOUNDARIES.len(), 2));
        let x_max = counts.iter().copied().max().unwrap_or(2) as f64;
        let x_min = counts.iter().copied().min().unwrap_or(2) as f64;
        let x_range = if x_max > x_min {
            x_min..x_max
        } else {
            x_min - 1.0..x_max + 1.0
        };
        // A common y range for all panels, like the paper's, zoomed to the data.
        let lowest = scores
            .iter()
            .flat_map(|s| [s.accuracy, s.macro_f1])
            .filter(|v| v.is_finite())
            .fold(1.0f64, f64::min);
        let y_min = ((lowest - 0.05) * 10.0).floor().max(0.0) / 10.0;
        for (row, bounds) in BOUNDARIES.iter().enumerate() {
            for (col, metric) in ["accuracy", "F1"].iter().enumerate() {
                let value = |s: &Scores| if col == 0 { s.accuracy } else { s.macro_f1 };
                let mut chart = ChartBuilder::on(&panels[row * 2 + col])
                    .caption(
                        format!("{metric}, boundaries {}", cm(*bounds)),
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
                    let points: Vec<(f64, f64)> = scores
                        .iter()
                        .filter(|s| s.boundaries == *bounds && s.setting == *setting)
                        .map(|s| (s.trials as f64, value(s)))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classification_scores_match_hand_computed_values() {
        // truth:     0 0 0 0 1 1 2 2
        // predicted: 0 0 0 1 1 2 2 2
        let truth = [0, 0, 0, 0, 1, 1, 2, 2];
        let predicted = [0, 0, 0, 1, 1, 2, 2, 2];
        let (accuracy, f1, sensitivity, specificity) = classification_scores(&truth, &predicted);
        assert_eq!(accuracy, 6.0 / 8.0);
        // F1: class 0: 2*3/(6+0+1) = 6/7; class 1: 2/(2+1+1) = 1/2; class 2: 4/(4+1+0) = 4/5.
        assert!((f1 - (6.0 / 7.0 + 0.5 + 0.8) / 3.0).abs() < 1e-15);
        // Sensitivity: 3/4, 1/2, 2/2.
        assert!((sensitivity - (0.75 + 0.5 + 1.0) / 3.0).abs() < 1e-15);
        // Specificity: class 0: 4/4; class 1: 5/6; class 2: 5/6.
        assert!((specificity - (1.0 + 5.0 / 6.0 + 5.0 / 6.0) / 3.0).abs() < 1e-15);
    }

    #[test]
    fn absent_classes_are_left_out_of_the_macro_average() {
        let (accuracy, f1, sensitivity, specificity) =
            classification_scores(&[0, 0, 0], &[0, 0, 0]);
        assert_eq!((accuracy, f1, sensitivity), (1.0, 1.0, 1.0));
        assert!(specificity.is_nan());
    }

    #[test]
    fn classes_follow_the_boundaries() {
        assert_eq!(class(0.049, (0.05, 0.10)), 0);
        assert_eq!(class(0.05, (0.05, 0.10)), 1);
        assert_eq!(class(0.10, (0.05, 0.10)), 2);
    }

    #[test]
    fn nearest_window_within_tolerance() {
        let truth = [(100, 1.0), (200, 2.0), (300, 3.0)];
        assert_eq!(nearest(&truth, 190, 20), Some(2.0));
        assert_eq!(nearest(&truth, 251, 60), Some(3.0));
        assert_eq!(nearest(&truth, 250, 10), None);
        assert_eq!(nearest(&truth, 0, 10), None);
    }
}
