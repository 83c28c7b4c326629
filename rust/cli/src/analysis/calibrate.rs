//! `sitar calibrate`: fits, on runs with ground truth, the calibration that turns the
//! estimate into the error it estimates, with an interval of stated coverage.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use sitar_estimator::{
    AgreementScores, CalibrationModel, CalibrationSequence, DEFAULT_SMOOTHING_WINDOWS,
    DEFAULT_SPREAD_MATCH, EstimateOptions, Feature, FitOptions, INFORMATIVE_SPEARMAN, PoseRelation,
    RunCount, SELECTION_NOISE, Setting, Target, Thresholds, fit_calibration,
};

use crate::analysis::sequences::{SequenceInput, sequence_inputs};
use crate::io::input::{self, Format};
use crate::io::output::emit;

/// Fits a calibration of the estimate on sequences with ground truth.
///
/// Per window, models from what the runs alone show (each run's own motion: path length,
/// rotation, straight-line displacement, jitter; with two or more runs how much they
/// disagree), each averaged with its neighbouring windows, to the window's true error, with
/// an interval [lower, upper] that holds it in --coverage of the windows of a sequence the
/// model was not fitted on (cross-conformal by sequence). Three models: the error of a live
/// run from that run alone, the same with replays (each run of set B in turn is the live run,
/// its own error the truth, the others its replays), and the expected error from several
/// runs (the mean RPE of set A against the ground truth, as `sitar evaluate` defines it).
/// Each model's features are chosen by leaving each sequence out in turn: every candidate's
/// scores are printed, and the one with the fewest features within 0.01 of the best
/// Spearman's ρ is kept. Where the runs do not predict the error (held-out ρ below 0.3) a
/// line starting `warning:` says so. Writes the calibration as versioned JSON for `sitar
/// estimate --calibration`, `sitar evaluate --calibration`, `sitar serve --calibration
/// NAME=FILE` and the phone (`sitar_session_set_calibration`).
///
/// A calibration belongs to one SLAM system on one device: fit it on runs of the system and
/// device whose estimates it will calibrate.
///
/// SEQUENCE: a directory with ground_truth.txt and runs/ (natural order; the first ⌈N/2⌉
/// runs are set A, the rest set B) or trials/ + trials-b/, or a directory of such.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar calibrate data/real-runs/euroc-vio -o euroc-vio.json\n  sitar calibrate MH_04 MH_05 V1_02 --coverage 0.9 --split 3 -o calibration.json\n  sitar estimate trials/ --calibration euroc-vio.json --format json"
)]
pub struct Args {
    /// Sequence directories (ground_truth.txt with runs/ or trials/ + trials-b/), or directories of them.
    #[arg(value_name = "SEQUENCE", required = true)]
    sequences: Vec<PathBuf>,
    /// Where to write the calibration (JSON).
    #[arg(short = 'o', long, value_name = "FILE")]
    output: PathBuf,
    /// The share of windows the interval should hold.
    #[arg(long, default_value_t = 0.8)]
    coverage: f64,
    /// Statistic of the estimate it calibrates.
    #[arg(long, default_value = sitar_core::DEFAULT_SETTING, value_parser = parse_setting)]
    setting: Setting,
    /// RPE delta in frames (the window).
    #[arg(short = 'd', long, default_value_t = 10)]
    delta: usize,
    /// Pose relation: trans_part (metres) or angle_deg.
    #[arg(short = 'r', long = "pose_relation", alias = "pose-relation", default_value = "trans_part", value_parser = parse_relation)]
    pose_relation: PoseRelation,
    /// Runs in set A (the truth) of each runs/ folder [default: half, rounded up].
    #[arg(long, value_name = "K")]
    split: Option<usize>,
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
    /// How far the predictions are stretched toward the truth's spread (0: least squares, 1: all the way).
    #[arg(long = "spread_match", alias = "spread-match", default_value_t = DEFAULT_SPREAD_MATCH)]
    spread_match: f64,
    /// Neighbouring windows on each side averaged into a window's features.
    #[arg(long, default_value_t = DEFAULT_SMOOTHING_WINDOWS)]
    smoothing: usize,
    /// Class boundaries of the printed scores: medium from (m).
    #[arg(long = "medium", default_value_t = Thresholds::DEFAULT_M.medium)]
    medium_m: f64,
    /// Class boundaries of the printed scores: high from (m).
    #[arg(long = "high", default_value_t = Thresholds::DEFAULT_M.high)]
    high_m: f64,
}

fn parse_setting(s: &str) -> Result<Setting, String> {
    s.parse().map_err(|e: sitar_estimator::Error| e.to_string())
}

fn parse_relation(s: &str) -> Result<PoseRelation, String> {
    match s.parse() {
        Ok(r @ (PoseRelation::TranslationPart | PoseRelation::RotationAngleDeg)) => Ok(r),
        Ok(_) => Err("a calibration is fitted for trans_part or angle_deg".into()),
        Err(e) => Err(e.to_string()),
    }
}

pub fn run(args: Args) -> Result<()> {
    if !(args.coverage > 0.0 && args.coverage < 1.0) {
        bail!("--coverage must be between 0 and 1, got {}", args.coverage);
    }
    if args.delta == 0 {
        bail!("--delta must be at least 1 frame");
    }
    if args.smoothing > 1000 {
        bail!("--smoothing must be at most 1000 windows");
    }
    let inputs = sequence_inputs(&args.sequences, args.split)?;
    let estimate = EstimateOptions {
        setting: args.setting,
        delta: args.delta,
        t_max_diff_s: args.t_max_diff,
        pose_relation: args.pose_relation,
    };
    let sequences: Vec<CalibrationSequence> = inputs
        .par_iter()
        .map(|input| read_sequence(input, &args, &estimate))
        .collect::<Result<_>>()?;
    let options = FitOptions {
        coverage: args.coverage,
        spread_match: args.spread_match,
        smoothing_windows: args.smoothing,
        estimate,
        thresholds: Thresholds::new(args.medium_m, args.high_m),
    };
    let calibration = fit_calibration(&sequences, &options)?;
    std::fs::write(&args.output, calibration.to_json())
        .with_context(|| format!("{}: cannot write the calibration", args.output.display()))?;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "calibration of {} {} (window {} frames) on {} sequence(s), {} windows of the expected error",
        calibration.fitted_on.setting,
        calibration.fitted_on.pose_relation,
        calibration.fitted_on.window_frames,
        sequences.len(),
        sequences
            .iter()
            .map(|s| s.expected.truth.len())
            .sum::<usize>(),
    );
    let classes = format!(
        "classes at {} & {} {}",
        fmt_boundary(args.medium_m, args.pose_relation),
        fmt_boundary(args.high_m, args.pose_relation),
        unit_name(args.pose_relation)
    );
    for model in &calibration.models {
        out.push_str(&model_report(model, args.coverage, &classes));
    }
    if sequences.len() < 2 {
        let _ = writeln!(
            out,
            "one sequence: features not chosen, scores in sample, and the interval's coverage on other sequences is not known"
        );
    }
    for model in calibration.models.iter().filter(|m| !m.informative) {
        let rho = model
            .scores
            .as_ref()
            .map_or(f64::NAN, |s| s.calibrated.spearman);
        let _ = writeln!(
            out,
            "warning: {} cannot be told from the runs (Spearman's ρ {rho:.2} on held-out sequences, below {INFORMATIVE_SPEARMAN}): the runs make much the same error where they err, so colours from this model are a guess; the calibration says \"informative\": false and every estimate made with it says so",
            model_name(model),
        );
    }
    let _ = writeln!(out, "wrote {}", args.output.display());
    emit(None, &out)
}

/// One model: its features, interval, the candidates' held-out scores and its own per
/// sequence.
fn model_report(model: &CalibrationModel, coverage: f64, classes: &str) -> String {
    let mut out = String::new();
    let what = model_name(model);
    let _ = writeln!(
        out,
        "\n{what}: {} (interval {:.0} %: ×{:.2} … ×{:.2} of the value, {})",
        feature_names(&model.features),
        100.0 * coverage,
        model.interval.log_lower.exp(),
        model.interval.log_upper.exp(),
        model.interval.method,
    );
    let Some(scores) = &model.scores else {
        return out;
    };
    let truth = if scores.truth == "own" {
        "each run of set B in turn as the live run, against its own error"
    } else {
        "against the mean error of set A"
    };
    if !scores.candidates.is_empty() {
        let _ = writeln!(
            out,
            "  candidates, leave one sequence out ({truth}; {classes}; kept: the fewest features within {SELECTION_NOISE} of the best ρ):"
        );
        let _ = writeln!(
            out,
            "    {:<58} {:>8} {:>8} {:>8} {:>9} {:>8}",
            "features", "Spearman", "macro F1", "accuracy", "est/truth", "coverage"
        );
        for c in &scores.candidates {
            let s = &c.scores;
            let _ = writeln!(
                out,
                "  {} {:<58} {:>8.3} {:>8.3} {:>8.3} {:>9.3} {:>7.1}%",
                if c.chosen { "*" } else { " " },
                feature_names(&c.features),
                s.spearman,
                s.macro_f1,
                s.accuracy,
                s.median_ratio,
                100.0 * s.coverage.unwrap_or(f64::NAN)
            );
        }
    }
    let _ = writeln!(
        out,
        "  kept, per sequence ({}):",
        scores.method.replace('_', " ")
    );
    let none = AgreementScores {
        accuracy: f64::NAN,
        macro_f1: f64::NAN,
        spearman: f64::NAN,
        median_ratio: f64::NAN,
        high_called_low: f64::NAN,
        coverage: None,
        high_upper_low: None,
    };
    let table = score_table(
        scores
            .sequences
            .iter()
            .map(|s| {
                (
                    s.name.as_str(),
                    s.raw.as_ref().unwrap_or(&none),
                    &s.calibrated,
                )
            })
            .chain([(
                "mean",
                scores.raw.as_ref().unwrap_or(&none),
                &scores.calibrated,
            )]),
    );
    for line in table.lines() {
        let _ = writeln!(out, "  {line}");
    }
    out
}

/// What a model estimates from what, in words.
fn model_name(model: &CalibrationModel) -> &'static str {
    match (model.target, model.runs) {
        (Target::Live, RunCount::One) => "the error of a live run, from that run alone",
        (Target::Live, _) => "the error of a live run, with replays",
        (Target::Expected, _) => "the expected error, from several runs",
    }
}

/// `ln_path_m + ln_rotation_deg` as `path + rotation`.
fn feature_names(features: &[Feature]) -> String {
    features
        .iter()
        .map(|f| match f {
            Feature::Spread => "spread",
            Feature::PathM => "path",
            Feature::RotationDeg => "rotation",
            Feature::DisplacementM => "displacement",
            Feature::JitterMps2 => "jitter",
        })
        .collect::<Vec<_>>()
        .join(" + ")
}

/// One sequence read and turned into calibration windows.
fn read_sequence(
    input: &SequenceInput,
    args: &Args,
    estimate: &EstimateOptions,
) -> Result<CalibrationSequence> {
    let hidden = indicatif::ProgressBar::hidden();
    let gt = input::read(&input.ground_truth, args.input_format)?;
    let set_a = input::read_all(&input.set_a, args.input_format, &hidden)?;
    let set_b = input::read_all(&input.set_b, args.input_format, &hidden)?;
    // Named by the folder alone (MH_04), the path as given if it has none.
    let name = std::path::Path::new(&input.name)
        .file_name()
        .map_or_else(|| input.name.clone(), |n| n.to_string_lossy().into_owned());
    CalibrationSequence::new(&name, &gt, &set_a, &set_b, estimate, args.smoothing).with_context(
        || {
            format!(
                "{} (set A from {}, set B from {})",
                input.name,
                input.dir_a.display(),
                input.dir_b.display()
            )
        },
    )
}

fn unit_name(relation: PoseRelation) -> &'static str {
    if relation == PoseRelation::TranslationPart {
        "cm"
    } else {
        "deg"
    }
}

fn fmt_boundary(value: f64, relation: PoseRelation) -> String {
    if relation == PoseRelation::TranslationPart {
        format!("{}", value * 100.0)
    } else {
        format!("{value}")
    }
}

/// The raw and calibrated scores side by side, one row per sequence.
pub fn score_table<'a>(
    rows: impl Iterator<Item = (&'a str, &'a AgreementScores, &'a AgreementScores)>,
) -> String {
    let mut out = format!(
        "  {:<12} {:>17} {:>17} {:>17} {:>17} {:>17} {:>9} {:>9}\n",
        "sequence",
        "accuracy",
        "macro F1",
        "Spearman",
        "est/truth",
        "high→low",
        "upper",
        "coverage"
    );
    let _ = writeln!(
        out,
        "  {:<12} {:>17} {:>17} {:>17} {:>17} {:>17} {:>9} {:>9}",
        "", "raw → cal", "raw → cal", "raw → cal", "raw → cal", "raw → cal", "high→low", ""
    );
    // No raw value (one run has no spread): a dash.
    let pair = |a: f64, b: f64| {
        if a.is_nan() {
            format!("{:>7} → {b:<7.3}", "–")
        } else {
            format!("{a:>7.3} → {b:<7.3}")
        }
    };
    for (name, raw, cal) in rows {
        let chars = name.chars().count();
        let short: String = name.chars().skip(chars.saturating_sub(12)).collect();
        let _ = writeln!(
            out,
            "  {:<12} {:>17} {:>17} {:>17} {:>17} {:>17} {:>9.3} {:>8.1}%",
            short,
            pair(raw.accuracy, cal.accuracy),
            pair(raw.macro_f1, cal.macro_f1),
            pair(raw.spearman, cal.spearman),
            pair(raw.median_ratio, cal.median_ratio),
            pair(raw.high_called_low, cal.high_called_low),
            cal.high_upper_low.unwrap_or(f64::NAN),
            100.0 * cal.coverage.unwrap_or(f64::NAN)
        );
    }
    out
}
