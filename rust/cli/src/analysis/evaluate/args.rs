//! `sitar evaluate`'s command line.

use std::path::PathBuf;

use anyhow::Result;
use sitar_estimator::Setting;

use crate::io::input::Format;

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
///
/// --truth own scores against each run's own error instead: every run of the first k of
/// set B in turn is the live run (the user's own walk), estimated alone (k = 1, with a
/// calibration) or with the others as its replays, against its own RPE to the ground truth.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar simulate --out eval --sequences 8 --trials 100 --seconds 30 --tracker ransac\n  sitar evaluate eval --trial_counts 5,10,20,30,100 --calibrate --sweep\n  sitar evaluate --ground_truth sim/ground_truth.txt --trials_a sim/trials --trials_b sim/trials-b"
)]
pub struct Args {
    /// Sequence directories (each with ground_truth.txt and runs/ or trials/ + trials-b/), or directories of them.
    #[arg(value_name = "SEQUENCE", conflicts_with_all = ["ground_truth", "trials_a", "trials_b"])]
    pub(super) sequences: Vec<PathBuf>,
    /// Ground-truth trajectory (one sequence given by its parts).
    #[arg(long = "ground_truth", alias = "ground-truth", value_name = "GT", requires_all = ["trials_a", "trials_b"])]
    pub(super) ground_truth: Option<PathBuf>,
    /// Directory of trials (*.txt) giving the true average error per window (set A).
    #[arg(long = "trials_a", alias = "trials-a", value_name = "DIR")]
    pub(super) trials_a: Option<PathBuf>,
    /// Directory of other trials (*.txt) to estimate from (set B), used in natural order.
    #[arg(long = "trials_b", alias = "trials-b", value_name = "DIR")]
    pub(super) trials_b: Option<PathBuf>,
    /// Numbers of set-B trials to estimate from [default: 5,10,20,…,100 up to the size of B].
    #[arg(
        long = "trial_counts",
        alias = "trial-counts",
        value_delimiter = ',',
        value_name = "K,..."
    )]
    pub(super) trial_counts: Option<Vec<usize>>,
    /// Settings to evaluate [default: all seven].
    #[arg(long, value_delimiter = ',', value_parser = parse_setting, value_name = "SETTING,...")]
    pub(super) settings: Option<Vec<Setting>>,
    /// RPE delta in frames (the sub-trajectory length).
    #[arg(short = 'd', long, default_value_t = 10)]
    pub(super) delta: usize,
    /// Sweep the sub-trajectory length: evaluate with each of these deltas (frames) instead of --delta.
    #[arg(
        long = "window_frames",
        alias = "window-frames",
        value_delimiter = ',',
        value_name = "F,..."
    )]
    pub(super) window_frames: Option<Vec<usize>>,
    /// Largest time difference (s) for associating poses.
    #[arg(long = "t_max_diff", alias = "t-max-diff", default_value_t = 0.01)]
    pub(super) t_max_diff: f64,
    /// Format of the trajectory files.
    #[arg(
        short = 'i',
        long = "input_format",
        alias = "input-format",
        value_enum,
        default_value_t
    )]
    pub(super) input_format: Format,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Report::Table)]
    pub(super) format: Report,
    /// Write the report to this file instead of stdout.
    #[arg(short = 'o', long)]
    pub(super) output: Option<PathBuf>,
    /// Where to draw the accuracy/F1 plot (SVG).
    #[arg(long, default_value = "evaluation.svg")]
    pub(super) plot: PathBuf,
    /// Do not draw the plot.
    #[arg(long = "no_plot", alias = "no-plot")]
    pub(super) no_plot: bool,
    /// Fit one scale factor on the first --train sequences and report its effect on the rest.
    #[arg(long)]
    pub(super) calibrate: bool,
    /// Training sequences for --calibrate [default: half of them].
    #[arg(long, value_name = "N")]
    pub(super) train: Option<usize>,
    /// Sweep the estimate threshold (ROC and precision-recall) for true boundaries 2, 5, 10 cm.
    #[arg(long)]
    pub(super) sweep: bool,
    /// Bootstrap resamples of the sequences for the intervals.
    #[arg(long, default_value_t = 2000)]
    pub(super) bootstrap: usize,
    /// Confidence level of the intervals.
    #[arg(long, default_value_t = 0.95)]
    pub(super) confidence: f64,
    /// Runs in set A (the truth) of each runs/ folder [default: half, rounded up].
    #[arg(long, value_name = "K")]
    pub(super) split: Option<usize>,
    /// Score the estimate calibrated by this file (`sitar calibrate`); its setting and window
    /// are the ones evaluated.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["window_frames", "calibrate"])]
    pub(super) calibration: Option<PathBuf>,
    /// The truth scored against: expected (the mean error of set A) or own (each live run's
    /// own error).
    #[arg(long, value_enum, default_value_t = Truth::Expected)]
    pub(super) truth: Truth,
}

/// What the estimate is scored against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum Truth {
    /// The mean error of set A at each window (the paper's protocol).
    Expected,
    /// Each run's own error, the run estimated as the live one.
    Own,
}

/// Report format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum Report {
    /// Aligned text tables.
    Table,
    /// One row per (sequence or mean, window frames, boundaries, setting, trials).
    Csv,
    /// One JSON document.
    Json,
}

pub(super) fn parse_setting(s: &str) -> Result<Setting, String> {
    s.parse().map_err(|e: sitar_estimator::Error| e.to_string())
}
