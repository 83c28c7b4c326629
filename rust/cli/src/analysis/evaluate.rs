//! `sitar evaluate`: the paper's evaluation protocol (section 3.3, Figure 5, Table 2) against
//! ground truth, over one or many sequences, with what the paper left open: bootstrap
//! intervals over sequences, estimate/truth agreement, a calibrated scale, threshold sweeps
//! and the sub-trajectory length.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use plotters::prelude::*;
use sitar_estimator::{
    Calibration, ClassificationScores, EstimateOptions, EvaluationOptions, MatchedWindows,
    MeanInterval, PAPER_CLASSIFIERS, Setting, ThresholdSweep, Thresholds, bootstrap_mean,
    calibrated_matched_windows, classification_scores, fit_scale, high_called_low, matched_windows,
    median_ratio, spearman, threshold_sweep,
};

use crate::analysis::sequences::{self, SequenceInput};
use crate::io::input::{self, Format, progress_bar};
use crate::io::output::{emit, json_number};

/// The paper's trial counts.
const PAPER_COUNTS: [usize; 11] = [5, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100];
/// The true-error boundaries a threshold sweep looks at (metres): the paper's 2, 5 and 10 cm.
const SWEEP_BOUNDARIES: [f64; 3] = [0.02, 0.05, 0.10];

/// Scores the estimate against ground truth: accuracy, F1, sensitivity and specificity per
/// setting and trial count, per sequence and averaged over sequences.
///
/// The paper's section 3.3 protocol, per sequence: the true error of each window is the mean
/// RPE against the ground truth over the trials of set A; the estimate comes from the first k
/// trials of set B (a disjoint set), for each k and every setting; both are classified
/// low/medium/high with boundaries 5 & 10 cm, 2 & 10 cm and 2 & 5 cm. Scores are averaged over
/// sequences with percentile-bootstrap intervals (resampling sequences); the report adds the
/// median estimate/truth ratio and Spearman's rank correlation, and draws accuracy and F1
/// against k per setting (the paper's Figure 5) as SVG.
///
/// SEQUENCE: a directory with ground_truth.txt and either runs/ (repeated runs of one SLAM,
/// natural order: the first ⌈N/2⌉ are set A, the rest set B; --split K puts K in set A) or
/// trials/ (set A) and trials-b/ (set B), or a directory of such directories (`sitar simulate
/// --sequences N` output).
///
/// With --calibration FILE (made by `sitar calibrate`) the calibrated estimate is scored, with
/// the share of windows whose interval holds the true error (coverage).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar simulate --out eval --sequences 8 --trials 100 --seconds 30 --tracker ransac\n  sitar evaluate eval --trial_counts 5,10,20,30,100 --calibrate --sweep\n  sitar evaluate --ground_truth sim/ground_truth.txt --trials_a sim/trials --trials_b sim/trials-b"
)]
pub struct Args {
    /// Sequence directories (each with ground_truth.txt and runs/ or trials/ + trials-b/), or directories of them.
    #[arg(value_name = "SEQUENCE", conflicts_with_all = ["ground_truth", "trials_a", "trials_b"])]
    sequences: Vec<PathBuf>,
    /// Ground-truth trajectory (one sequence given by its parts).
    #[arg(long = "ground_truth", alias = "ground-truth", value_name = "GT", requires_all = ["trials_a", "trials_b"])]
    ground_truth: Option<PathBuf>,
    /// Directory of trials (*.txt) giving the true average error per window (set A).
    #[arg(long = "trials_a", alias = "trials-a", value_name = "DIR")]
    trials_a: Option<PathBuf>,
    /// Directory of other trials (*.txt) to estimate from (set B), used in natural order.
    #[arg(long = "trials_b", alias = "trials-b", value_name = "DIR")]
    trials_b: Option<PathBuf>,
    /// Numbers of set-B trials to estimate from [default: 5,10,20,…,100 up to the size of B].
    #[arg(
        long = "trial_counts",
        alias = "trial-counts",
        value_delimiter = ',',
        value_name = "K,..."
    )]
    trial_counts: Option<Vec<usize>>,
    /// Settings to evaluate [default: all seven].
    #[arg(long, value_delimiter = ',', value_parser = parse_setting, value_name = "SETTING,...")]
    settings: Option<Vec<Setting>>,
    /// RPE delta in frames (the sub-trajectory length).
    #[arg(short = 'd', long, default_value_t = 10)]
    delta: usize,
    /// Sweep the sub-trajectory length: evaluate with each of these deltas (frames) instead of --delta.
    #[arg(
        long = "window_frames",
        alias = "window-frames",
        value_delimiter = ',',
        value_name = "F,..."
    )]
    window_frames: Option<Vec<usize>>,
    /// Largest time difference (s) for associating poses.
    #[arg(long = "t_max_diff", alias = "t-max-diff", default_value_t = 0.01)]
    t_max_diff: f64,
    /// Format of the trajectory files.
    #[arg(
        short = 'i',
        long = "input_format",
        alias = "input-format",
        value_enum,
        default_value_t
    )]
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
    #[arg(long = "no_plot", alias = "no-plot")]
    no_plot: bool,
    /// Fit one scale factor on the first --train sequences and report its effect on the rest.
    #[arg(long)]
    calibrate: bool,
    /// Training sequences for --calibrate [default: half of them].
    #[arg(long, value_name = "N")]
    train: Option<usize>,
    /// Sweep the estimate threshold (ROC and precision-recall) for true boundaries 2, 5, 10 cm.
    #[arg(long)]
    sweep: bool,
    /// Bootstrap resamples of the sequences for the intervals.
    #[arg(long, default_value_t = 2000)]
    bootstrap: usize,
    /// Confidence level of the intervals.
    #[arg(long, default_value_t = 0.95)]
    confidence: f64,
    /// Runs in set A (the truth) of each runs/ folder [default: half, rounded up].
    #[arg(long, value_name = "K")]
    split: Option<usize>,
    /// Score the estimate calibrated by this file (`sitar calibrate`); its setting and window
    /// are the ones evaluated.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["window_frames", "calibrate"])]
    calibration: Option<PathBuf>,
}

/// Report format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Report {
    /// Aligned text tables.
    Table,
    /// One row per (sequence or mean, window frames, boundaries, setting, trials).
    Csv,
    /// One JSON document.
    Json,
}

fn parse_setting(s: &str) -> Result<Setting, String> {
    s.parse().map_err(|e: sitar_estimator::Error| e.to_string())
}

/// Expands the SEQUENCE arguments (or the single-sequence flags).
fn sequence_inputs(args: &Args) -> Result<Vec<SequenceInput>> {
    if let (Some(gt), Some(a), Some(b)) = (&args.ground_truth, &args.trials_a, &args.trials_b) {
        return Ok(vec![SequenceInput {
            name: gt.display().to_string(),
            ground_truth: gt.clone(),
            set_a: input::trial_files(a)?,
            set_b: input::trial_files(b)?,
            dir_a: a.clone(),
            dir_b: b.clone(),
        }]);
    }
    if args.sequences.is_empty() {
        bail!("give SEQUENCE directories, or --ground_truth with --trials_a and --trials_b");
    }
    sequences::sequence_inputs(&args.sequences, args.split)
}

/// One sequence evaluated: per window length, the matched windows of every (k, setting).
struct Evaluated {
    input: SequenceInput,
    trials_a: usize,
    trials_b: usize,
    /// Per entry of `window_frames`: ground-truth windows and the matched windows.
    by_window: Vec<(usize, Vec<MatchedWindows>)>,
}

pub fn run(args: Args) -> Result<()> {
    let window_frames = args
        .window_frames
        .clone()
        .unwrap_or_else(|| vec![args.delta]);
    if window_frames.contains(&0) {
        bail!("--delta and --window_frames must be at least 1 frame");
    }
    if !(args.confidence > 0.0 && args.confidence < 1.0) {
        bail!(
            "--confidence must be between 0 and 1, got {}",
            args.confidence
        );
    }
    if args.bootstrap == 0 || args.bootstrap > 1_000_000 {
        bail!(
            "--bootstrap must be between 1 and 1000000, got {}",
            args.bootstrap
        );
    }
    let inputs = sequence_inputs(&args)?;
    let calibration = match &args.calibration {
        Some(path) => Some(Calibration::read(path)?),
        None => None,
    };
    let settings = match (&args.settings, &calibration) {
        (Some(settings), _) => settings.clone(),
        // A calibration is fitted for one setting.
        (None, Some(c)) => vec![c.fitted_on.setting.parse()?],
        (None, None) => Setting::ALL.to_vec(),
    };
    let bar = progress_bar(inputs.len() as u64, "evaluating sequences");
    let mut evaluated = Vec::new();
    let mut counts: Option<Vec<usize>> = None;
    for input in inputs {
        let (files_a, files_b) = (input.set_a.clone(), input.set_b.clone());
        if files_b.len() < 2 {
            bail!(
                "{}: the estimate needs at least 2 trials, found {}",
                input.dir_b.display(),
                files_b.len()
            );
        }
        let these = trial_counts(&args, files_b.len())?;
        match &counts {
            Some(c) if *c != these => bail!(
                "{}: {} trials in set B give other trial counts than the first sequence's; give --trial_counts",
                input.dir_b.display(),
                files_b.len()
            ),
            _ => counts = Some(these.clone()),
        }
        let hidden = indicatif::ProgressBar::hidden();
        let gt = input::read(&input.ground_truth, args.input_format)?;
        let trials_a = input::read_all(&files_a, args.input_format, &hidden)?;
        let trials_b = input::read_all(&files_b, args.input_format, &hidden)?;
        let context = || {
            format!(
                "evaluating {} (trial i = the i-th file of {} or {})",
                input.name,
                input.dir_a.display(),
                input.dir_b.display()
            )
        };
        let mut by_window = Vec::new();
        for &delta in &window_frames {
            let opts = EvaluationOptions {
                trial_counts: these.clone(),
                settings: settings.clone(),
                boundaries: PAPER_CLASSIFIERS.to_vec(),
                estimate: EstimateOptions {
                    delta,
                    t_max_diff_s: args.t_max_diff,
                    ..EstimateOptions::default()
                },
            };
            let matched = match &calibration {
                Some(c) => calibrated_matched_windows(&gt, &trials_a, &trials_b, &opts, c),
                None => matched_windows(&gt, &trials_a, &trials_b, &opts),
            };
            by_window.push(matched.with_context(context)?);
        }
        evaluated.push(Evaluated {
            input,
            trials_a: files_a.len(),
            trials_b: files_b.len(),
            by_window,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let counts = counts.unwrap_or_default();
    let report = Computed::new(&args, &evaluated, &window_frames, &settings, &counts)?;
    let text = match args.format {
        Report::Table => report.table(&evaluated),
        Report::Csv => report.csv(&evaluated),
        Report::Json => report.json(&evaluated),
    };
    emit(args.output.as_deref(), &text)?;
    if !args.no_plot {
        let rows: Vec<PlotRow> = report
            .averaged
            .iter()
            .filter(|r| r.window_frames == window_frames[0])
            .map(|r| PlotRow {
                boundaries: r.boundaries,
                setting: r.setting,
                trials: r.trials,
                accuracy: r.accuracy.mean,
                macro_f1: r.macro_f1.mean,
            })
            .collect();
        plot(&args.plot, &rows, &settings, &counts)?;
        eprintln!("wrote the plot to {}", args.plot.display());
    }
    Ok(())
}

fn trial_counts(args: &Args, available: usize) -> Result<Vec<usize>> {
    Ok(match &args.trial_counts {
        Some(counts) => {
            if let Some(&bad) = counts.iter().find(|&&k| k < 2 || k > available) {
                bail!("--trial_counts: {bad} is not between 2 and the {available} trials of set B");
            }
            counts.clone()
        }
        None => {
            let counts: Vec<usize> = PAPER_COUNTS
                .iter()
                .copied()
                .filter(|&k| k <= available)
                .collect();
            if counts.is_empty() {
                vec![available]
            } else {
                counts
            }
        }
    })
}

/// Scores of one sequence for one (window frames, setting, trials, boundaries).
struct SequenceRow {
    sequence: usize,
    window_frames: usize,
    setting: Setting,
    trials: usize,
    boundaries: Thresholds,
    scores: ClassificationScores,
}

/// The mean over sequences of one (window frames, setting, trials, boundaries).
struct AveragedRow {
    window_frames: usize,
    setting: Setting,
    trials: usize,
    boundaries: Thresholds,
    accuracy: MeanInterval,
    macro_f1: MeanInterval,
    sensitivity: MeanInterval,
    specificity: MeanInterval,
    /// Share of the misclassified windows (all sequences) whose class was predicted too high.
    over_predicted: f64,
    windows: usize,
}

/// How the estimate follows the truth for one (window frames, setting, trials).
struct AgreementRow {
    window_frames: usize,
    setting: Setting,
    trials: usize,
    /// Per sequence: median estimate/truth ratio and Spearman's rank correlation.
    ratios: Vec<f64>,
    spearman: Vec<f64>,
    ratio: MeanInterval,
    rank_correlation: MeanInterval,
    /// Over the windows of all sequences together.
    pooled_ratio: f64,
    /// Per sequence: the share of the truly high windows (5 & 10 cm) the estimate calls low.
    high_called_low: Vec<f64>,
    /// The same over the windows of all sequences.
    pooled_high_called_low: f64,
    /// With a calibration: per sequence and over all windows, the share of windows whose
    /// interval holds the true error.
    coverage: Option<(Vec<f64>, f64)>,
}

/// The calibration of one (window frames, setting, trials, boundaries).
struct CalibrationRow {
    window_frames: usize,
    setting: Setting,
    trials: usize,
    boundaries: Thresholds,
    scale: f64,
    raw: (f64, f64),
    calibrated: (f64, f64),
}

/// One sweep over the pooled windows of every sequence.
struct SweepRow {
    window_frames: usize,
    setting: Setting,
    trials: usize,
    sweep: ThresholdSweep,
}

struct Computed {
    per_sequence: Vec<SequenceRow>,
    averaged: Vec<AveragedRow>,
    agreement: Vec<AgreementRow>,
    calibration: Option<(usize, Vec<CalibrationRow>)>,
    sweeps: Vec<SweepRow>,
    confidence: f64,
    /// The calibration scored (`--calibration`), by its file name.
    calibration_name: Option<String>,
}

/// The windows of every sequence for one (window-frames index, setting, trials).
fn windows_of(
    evaluated: &[Evaluated],
    w: usize,
    setting: Setting,
    trials: usize,
) -> Vec<&MatchedWindows> {
    evaluated
        .iter()
        .filter_map(|e| {
            e.by_window[w]
                .1
                .iter()
                .find(|m| m.setting == setting && m.trials == trials)
        })
        .collect()
}

fn pooled(windows: &[&MatchedWindows]) -> (Vec<f64>, Vec<f64>) {
    let truth = windows
        .iter()
        .flat_map(|m| m.truth.iter().copied())
        .collect();
    let estimate = windows
        .iter()
        .flat_map(|m| m.estimate.iter().copied())
        .collect();
    (truth, estimate)
}

/// (windows whose interval holds the truth, windows).
fn held(m: &MatchedWindows) -> (usize, usize) {
    let inside = (0..m.truth.len())
        .filter(|&i| m.lower[i] <= m.truth[i] && m.truth[i] <= m.upper[i])
        .count();
    (inside, m.truth.len())
}

impl Computed {
    fn new(
        args: &Args,
        evaluated: &[Evaluated],
        window_frames: &[usize],
        settings: &[Setting],
        counts: &[usize],
    ) -> Result<Self> {
        let interval = |values: &[f64], salt: u64| -> MeanInterval {
            bootstrap_mean(values, args.bootstrap, args.confidence, 0x5175_7a72 ^ salt).unwrap_or(
                MeanInterval {
                    mean: f64::NAN,
                    low: f64::NAN,
                    high: f64::NAN,
                },
            )
        };
        let mut per_sequence = Vec::new();
        let mut averaged = Vec::new();
        let mut agreement = Vec::new();
        let mut sweeps = Vec::new();
        let mut salt = 0u64;
        for (w, &frames) in window_frames.iter().enumerate() {
            for &trials in counts {
                for &setting in settings {
                    let windows = windows_of(evaluated, w, setting, trials);
                    let (ratios, ranks): (Vec<f64>, Vec<f64>) = windows
                        .iter()
                        .map(|m| {
                            (
                                median_ratio(&m.truth, &m.estimate).unwrap_or(f64::NAN),
                                spearman(&m.truth, &m.estimate).unwrap_or(f64::NAN),
                            )
                        })
                        .unzip();
                    let (truth, estimate) = pooled(&windows);
                    let high_low_per_sequence: Vec<f64> = windows
                        .iter()
                        .map(|m| high_called_low(&m.truth, &m.estimate, Thresholds::DEFAULT_M))
                        .collect();
                    let coverage = windows.iter().all(|m| !m.lower.is_empty()).then(|| {
                        let per: Vec<(usize, usize)> = windows.iter().map(|m| held(m)).collect();
                        let (inside, total) =
                            per.iter().fold((0, 0), |(a, b), &(i, t)| (a + i, b + t));
                        (
                            per.iter().map(|&(i, t)| i as f64 / t as f64).collect(),
                            inside as f64 / total.max(1) as f64,
                        )
                    });
                    salt += 1;
                    agreement.push(AgreementRow {
                        pooled_high_called_low: high_called_low(
                            &truth,
                            &estimate,
                            Thresholds::DEFAULT_M,
                        ),
                        high_called_low: high_low_per_sequence,
                        coverage,
                        window_frames: frames,
                        setting,
                        trials,
                        ratio: interval(&ratios, salt),
                        rank_correlation: interval(&ranks, salt + (1 << 40)),
                        ratios,
                        spearman: ranks,
                        pooled_ratio: median_ratio(&truth, &estimate).unwrap_or(f64::NAN),
                    });
                    if args.sweep && trials == *counts.last().unwrap_or(&trials) {
                        for boundary in SWEEP_BOUNDARIES {
                            sweeps.push(SweepRow {
                                window_frames: frames,
                                setting,
                                trials,
                                sweep: threshold_sweep(&truth, &estimate, boundary)?,
                            });
                        }
                    }
                    for boundaries in PAPER_CLASSIFIERS {
                        let mut scores = Vec::new();
                        for (sequence, m) in windows.iter().enumerate() {
                            let s = classification_scores(&m.truth, &m.estimate, boundaries)?;
                            per_sequence.push(SequenceRow {
                                sequence,
                                window_frames: frames,
                                setting,
                                trials,
                                boundaries,
                                scores: s,
                            });
                            scores.push(s);
                        }
                        let metric = |f: fn(&ClassificationScores) -> f64| -> Vec<f64> {
                            scores.iter().map(f).collect()
                        };
                        let (mut over, mut wrong) = (0usize, 0usize);
                        for s in &scores {
                            for t in 0..3 {
                                for p in 0..3 {
                                    if p != t {
                                        wrong += s.confusion[t][p];
                                        if p > t {
                                            over += s.confusion[t][p];
                                        }
                                    }
                                }
                            }
                        }
                        salt += 4;
                        averaged.push(AveragedRow {
                            window_frames: frames,
                            setting,
                            trials,
                            boundaries,
                            accuracy: interval(&metric(|s| s.accuracy), salt),
                            macro_f1: interval(&metric(|s| s.macro_f1), salt + 1),
                            sensitivity: interval(&metric(|s| s.sensitivity), salt + 2),
                            specificity: interval(&metric(|s| s.specificity), salt + 3),
                            over_predicted: if wrong > 0 {
                                over as f64 / wrong as f64
                            } else {
                                f64::NAN
                            },
                            windows: scores.iter().map(|s| s.windows).sum(),
                        });
                    }
                }
            }
        }
        let calibration = if args.calibrate {
            Some(calibrate(args, evaluated, window_frames, settings, counts)?)
        } else {
            None
        };
        Ok(Self {
            per_sequence,
            averaged,
            agreement,
            calibration,
            sweeps,
            confidence: args.confidence,
            calibration_name: args
                .calibration
                .as_deref()
                .map(crate::analysis::estimate::calibration_name),
        })
    }

    fn table(&self, evaluated: &[Evaluated]) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{} sequence(s); true error: mean over set A, estimate: first k of set B; mean over sequences [{:.0} % bootstrap interval]",
            evaluated.len(),
            100.0 * self.confidence
        );
        if let Some(name) = &self.calibration_name {
            let _ = writeln!(out, "estimate calibrated by {name}");
        }
        for e in evaluated {
            let _ = writeln!(
                out,
                "  {}: {} + {} trials, {} windows",
                e.input.name, e.trials_a, e.trials_b, e.by_window[0].0
            );
        }
        let several_windows = self
            .averaged
            .iter()
            .any(|r| r.window_frames != self.averaged[0].window_frames);
        for bounds in PAPER_CLASSIFIERS {
            let _ = writeln!(out);
            let _ = writeln!(out, "class boundaries {}", cm(&bounds));
            let _ = writeln!(
                out,
                "{:<14} {:>6} {:>6} {:>8} {:>22} {:>20} {:>12} {:>12} {:>6}",
                "setting",
                "frames",
                "trials",
                "windows",
                "accuracy",
                "F1",
                "sensitivity",
                "specificity",
                "over"
            );
            for r in self.averaged.iter().filter(|r| r.boundaries == bounds) {
                let _ = writeln!(
                    out,
                    "{:<14} {:>6} {:>6} {:>8} {:>6.1}% [{:>5.1}, {:>5.1}] {:>6.3} [{:.3}, {:.3}] {:>12.3} {:>12.3} {:>5.0}%",
                    r.setting.to_string(),
                    r.window_frames,
                    r.trials,
                    r.windows,
                    100.0 * r.accuracy.mean,
                    100.0 * r.accuracy.low,
                    100.0 * r.accuracy.high,
                    r.macro_f1.mean,
                    r.macro_f1.low,
                    r.macro_f1.high,
                    r.sensitivity.mean,
                    r.specificity.mean,
                    100.0 * r.over_predicted
                );
            }
        }
        let _ = writeln!(out);
        let _ = writeln!(
            out,
            "estimate vs truth per window: median ratio estimate/truth and Spearman's rank correlation"
        );
        for r in &self.agreement {
            let _ = writeln!(
                out,
                "agreement {:<14}{} trials {:>3}: ratio {:.2} [{:.2}, {:.2}] (all windows {:.2}), rank correlation {:.3} [{:.3}, {:.3}]",
                r.setting.to_string(),
                if several_windows {
                    format!(" frames {:>3}", r.window_frames)
                } else {
                    String::new()
                },
                r.trials,
                r.ratio.mean,
                r.ratio.low,
                r.ratio.high,
                r.pooled_ratio,
                r.rank_correlation.mean,
                r.rank_correlation.low,
                r.rank_correlation.high
            );
            let _ = writeln!(
                out,
                "          {:<14}{} high (≥ 10 cm) called low (< 5 cm): {:.1} % of the high windows{}",
                "",
                if several_windows { "           " } else { "" },
                100.0 * r.pooled_high_called_low,
                match &r.coverage {
                    Some((per, all)) => format!(
                        "; interval coverage {:.1} % (per sequence {})",
                        100.0 * all,
                        per.iter()
                            .map(|c| format!("{:.1} %", 100.0 * c))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                    None => String::new(),
                }
            );
        }
        if let Some((train, rows)) = &self.calibration {
            let _ = writeln!(out);
            let _ = writeln!(
                out,
                "calibration: one scale fitted on the first {train} sequence(s), scored on the other {}",
                evaluated.len() - train
            );
            for r in rows {
                let _ = writeln!(
                    out,
                    "calibrated {:<14} frames {:>3} trials {:>3} {:>12}: scale {:.3}, accuracy {:.1}% -> {:.1}%, F1 {:.3} -> {:.3}",
                    r.setting.to_string(),
                    r.window_frames,
                    r.trials,
                    cm(&r.boundaries),
                    r.scale,
                    100.0 * r.raw.0,
                    100.0 * r.calibrated.0,
                    r.raw.1,
                    r.calibrated.1
                );
            }
        }
        if !self.sweeps.is_empty() {
            let _ = writeln!(out);
            let _ = writeln!(
                out,
                "threshold sweep (all windows): the estimate as a detector of true error >= boundary"
            );
            for r in &self.sweeps {
                let s = &r.sweep;
                let _ = writeln!(
                    out,
                    "sweep {:<14} frames {:>3} trials {:>3} boundary {:>4.0} cm: {} positive / {} negative, ROC AUC {:.3}, average precision {:.3}, best F1 {:.3} at {:.1} cm",
                    r.setting.to_string(),
                    r.window_frames,
                    r.trials,
                    100.0 * s.boundary_m,
                    s.positives,
                    s.negatives,
                    s.roc_auc,
                    s.average_precision,
                    s.best_f1,
                    100.0 * s.best_f1_threshold_m
                );
            }
        }
        out
    }

    fn csv(&self, evaluated: &[Evaluated]) -> String {
        let mut out = String::from(
            "sequence,window_frames,medium_m,high_m,setting,trials,windows,accuracy,macro_f1,sensitivity,specificity\n",
        );
        for r in &self.per_sequence {
            let s = &r.scores;
            let _ = writeln!(
                out,
                "{},{},{},{},{},{},{},{},{},{},{}",
                csv_field(&evaluated[r.sequence].input.name),
                r.window_frames,
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
        for r in &self.averaged {
            let _ = writeln!(
                out,
                "mean,{},{},{},{},{},{},{},{},{},{}",
                r.window_frames,
                r.boundaries.medium,
                r.boundaries.high,
                r.setting,
                r.trials,
                r.windows,
                r.accuracy.mean,
                r.macro_f1.mean,
                r.sensitivity.mean,
                r.specificity.mean
            );
        }
        out
    }

    fn json(&self, evaluated: &[Evaluated]) -> String {
        let interval = |i: &MeanInterval| serde_json::json!({"mean": json_number(i.mean), "low": json_number(i.low), "high": json_number(i.high)});
        let results: Vec<serde_json::Value> = self
            .per_sequence
            .iter()
            .map(|r| {
                let s = &r.scores;
                serde_json::json!({
                    "sequence": r.sequence,
                    "window_frames": r.window_frames,
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
        let averaged: Vec<serde_json::Value> = self
            .averaged
            .iter()
            .map(|r| {
                serde_json::json!({
                    "window_frames": r.window_frames,
                    "boundaries_m": [r.boundaries.medium, r.boundaries.high],
                    "setting": r.setting.to_string(),
                    "trials": r.trials,
                    "windows": r.windows,
                    "accuracy": interval(&r.accuracy),
                    "macro_f1": interval(&r.macro_f1),
                    "sensitivity": interval(&r.sensitivity),
                    "specificity": interval(&r.specificity),
                    "over_predicted_share": json_number(r.over_predicted),
                })
            })
            .collect();
        let agreement: Vec<serde_json::Value> = self
            .agreement
            .iter()
            .map(|r| {
                serde_json::json!({
                    "window_frames": r.window_frames,
                    "setting": r.setting.to_string(),
                    "trials": r.trials,
                    "median_ratio": r.ratios.iter().map(|&v| json_number(v)).collect::<Vec<_>>(),
                    "spearman": r.spearman.iter().map(|&v| json_number(v)).collect::<Vec<_>>(),
                    "mean_median_ratio": interval(&r.ratio),
                    "mean_spearman": interval(&r.rank_correlation),
                    "pooled_median_ratio": json_number(r.pooled_ratio),
                    "high_called_low": r.high_called_low.iter().map(|&v| json_number(v)).collect::<Vec<_>>(),
                    "pooled_high_called_low": json_number(r.pooled_high_called_low),
                    "coverage": r.coverage.as_ref().map(|(_, all)| json_number(*all)),
                    "coverage_per_sequence": r.coverage.as_ref().map(|(per, _)| per.iter().map(|&v| json_number(v)).collect::<Vec<_>>()),
                })
            })
            .collect();
        let sequences: Vec<serde_json::Value> = evaluated
            .iter()
            .map(|e| {
                serde_json::json!({
                    "name": e.input.name,
                    "ground_truth": e.input.ground_truth.display().to_string(),
                    "trials_a": e.trials_a,
                    "trials_b": e.trials_b,
                    "truth_windows": e.by_window.iter().map(|(n, _)| n).collect::<Vec<_>>(),
                })
            })
            .collect();
        let first = &evaluated[0];
        let truth_classes: Vec<serde_json::Value> = PAPER_CLASSIFIERS
            .iter()
            .map(|b| {
                let mut n = [0usize; 3];
                for e in evaluated {
                    if let Some(m) = e.by_window[0].1.first() {
                        for &t in &m.truth {
                            n[b.classify(t).index().unwrap_or(0)] += 1;
                        }
                    }
                }
                serde_json::json!({
                    "boundaries_m": [b.medium, b.high], "low": n[0], "medium": n[1], "high": n[2],
                })
            })
            .collect();
        let mut doc = serde_json::json!({
            "version": 2,
            "sequences": sequences,
            "ground_truth": first.input.ground_truth.display().to_string(),
            "trials_a": first.trials_a,
            "trials_b": first.trials_b,
            "truth_windows": evaluated.iter().map(|e| e.by_window[0].0).sum::<usize>(),
            "truth_classes": truth_classes,
            "confidence": self.confidence,
            "results": results,
            "averaged": averaged,
            "agreement": agreement,
        });
        if let Some(name) = &self.calibration_name {
            doc["calibrated_by"] = serde_json::json!(name);
        }
        if let Some((train, rows)) = &self.calibration {
            doc["calibration"] = serde_json::json!({
                "train_sequences": train,
                "rows": rows.iter().map(|r| serde_json::json!({
                    "window_frames": r.window_frames,
                    "setting": r.setting.to_string(),
                    "trials": r.trials,
                    "boundaries_m": [r.boundaries.medium, r.boundaries.high],
                    "scale": json_number(r.scale),
                    "held_out_raw": {"accuracy": json_number(r.raw.0), "macro_f1": json_number(r.raw.1)},
                    "held_out_calibrated": {"accuracy": json_number(r.calibrated.0), "macro_f1": json_number(r.calibrated.1)},
                })).collect::<Vec<_>>(),
            });
        }
        if !self.sweeps.is_empty() {
            doc["sweeps"] = self
                .sweeps
                .iter()
                .map(|r| {
                    let s = &r.sweep;
                    serde_json::json!({
                        "window_frames": r.window_frames,
                        "setting": r.setting.to_string(),
                        "trials": r.trials,
                        "boundary_m": s.boundary_m,
                        "positives": s.positives,
                        "negatives": s.negatives,
                        "roc_auc": json_number(s.roc_auc),
                        "average_precision": json_number(s.average_precision),
                        "best_f1": json_number(s.best_f1),
                        "best_f1_threshold_m": json_number(s.best_f1_threshold_m),
                        "points": s.points.iter().map(|p| [json_number(p.threshold_m), json_number(p.fpr), json_number(p.tpr), json_number(p.precision)]).collect::<Vec<_>>(),
                    })
                })
                .collect();
        }
        doc.to_string() + "\n"
    }
}

/// A CSV field, quoted when it holds a comma or a quote.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}

/// `--calibrate`: per (window frames, setting, trials), the scale fitted on the pooled windows
/// of the training sequences, and the held-out sequences' mean accuracy and F1 without and
/// with it, per classifier.
fn calibrate(
    args: &Args,
    evaluated: &[Evaluated],
    window_frames: &[usize],
    settings: &[Setting],
    counts: &[usize],
) -> Result<(usize, Vec<CalibrationRow>)> {
    if evaluated.len() < 2 {
        bail!("--calibrate needs at least 2 sequences (a training and a held-out one)");
    }
    let train = args.train.unwrap_or(evaluated.len() / 2).max(1);
    if train >= evaluated.len() {
        bail!(
            "--train {train}: must leave at least one of the {} sequences held out",
            evaluated.len()
        );
    }
    let mut rows = Vec::new();
    for (w, &frames) in window_frames.iter().enumerate() {
        for &trials in counts {
            for &setting in settings {
                let windows = windows_of(evaluated, w, setting, trials);
                let (truth, estimate) = pooled(&windows[..train]);
                let scale = fit_scale(&truth, &estimate)?;
                for boundaries in PAPER_CLASSIFIERS {
                    let (mut raw, mut calibrated) = ((0.0, 0.0), (0.0, 0.0));
                    let held_out = &windows[train..];
                    for m in held_out {
                        let r = classification_scores(&m.truth, &m.estimate, boundaries)?;
                        let scaled: Vec<f64> = m.estimate.iter().map(|e| e * scale).collect();
                        let c = classification_scores(&m.truth, &scaled, boundaries)?;
                        raw = (raw.0 + r.accuracy, raw.1 + r.macro_f1);
                        calibrated = (calibrated.0 + c.accuracy, calibrated.1 + c.macro_f1);
                    }
                    let n = held_out.len() as f64;
                    rows.push(CalibrationRow {
                        window_frames: frames,
                        setting,
                        trials,
                        boundaries,
                        scale,
                        raw: (raw.0 / n, raw.1 / n),
                        calibrated: (calibrated.0 / n, calibrated.1 / n),
                    });
                }
            }
        }
    }
    Ok((train, rows))
}

fn cm(b: &Thresholds) -> String {
    format!("{} & {} cm", b.medium * 100.0, b.high * 100.0)
}

/// One point of Figure 5.
struct PlotRow {
    boundaries: Thresholds,
    setting: Setting,
    trials: usize,
    accuracy: f64,
    macro_f1: f64,
}

/// The paper's Figure 5: per class-boundary setting, accuracy (left) and F1 (right) against
/// the number of trials, one line per setting.
fn plot(path: &Path, rows: &[PlotRow], settings: &[Setting], counts: &[usize]) -> Result<()> {
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
            .flat_map(|r| [r.accuracy, r.macro_f1])
            .filter(|v| v.is_finite())
            .fold(1.0f64, f64::min);
        let y_min = ((lowest - 0.05) * 10.0).floor().max(0.0) / 10.0;
        for (row, bounds) in PAPER_CLASSIFIERS.iter().enumerate() {
            for (col, metric) in ["accuracy", "F1"].iter().enumerate() {
                let value = |r: &PlotRow| if col == 0 { r.accuracy } else { r.macro_f1 };
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
