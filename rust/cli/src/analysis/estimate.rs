//! `sitar estimate`: per-window pose error from repeated trials, without ground truth.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use sitar_estimator::{
    ApplyCalibration, Calibration, Estimate, EstimateOptions, PoseRelation, Setting, Thresholds,
    Trajectory, estimate, estimate_live, live_spread, matching_time_indices, seconds_to_ns,
};

use crate::figures::figure::{ErrorFigure, Sample};
use crate::figures::plot::PlotArgs;
use crate::io::input::{self, Format, progress_bar};
use crate::io::output::{OutputFormat, emit};
use crate::io::source::StampUnit;
use crate::results::compare::{file_name, unit};

/// Estimates each window's pose error from repeated trials, without ground truth.
///
/// All n(n−1)/2 pairwise RPEs of the trials (translation, delta 10 frames, every start), then
/// a robust statistic per window. Writes the legacy CSV `start,error` (start in the trials'
/// time unit, error in metres) or JSON with the pair count, spread and class of each window;
/// --plot also draws the estimate over time and on the first trial's path as SVG.
///
/// With a calibration (`sitar calibrate`) the error is the calibrated one, with an interval,
/// and the JSON says which error it is (`"target"`). Several trials give the error expected
/// at each place (`"target": "expected"`). One trial alone gives that run's own error from
/// its own motion (`"target": "live"`, `"runs": 1`); --live RUN gives the error of RUN with
/// the trials as its replays (its own motion and how much they disagree with it).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar estimate trials/trajectory_*.txt\n  sitar estimate trials/ --setting median --format json -o results.json\n  sitar estimate trials/ --plot estimate.svg --plot-mode xz"
)]
pub struct Args {
    /// Trial trajectory files, at least 2 (1 with a calibration), taken in the order given; a
    /// directory stands for its *.txt files in natural order. With --live: its replays.
    #[arg(required_unless_present = "live", value_name = "TRIAL")]
    trials: Vec<PathBuf>,
    /// Estimate the error of this run (the live one: the user's own walk), with the trials as
    /// its replays: windows keyed by its stamps, the spread between it and each replay.
    #[arg(long, value_name = "RUN")]
    live: Option<PathBuf>,
    /// Statistic per window: mean, median, trim_mean_10|20|30|40 or mean_inliers.
    #[arg(long, default_value = sitar_core::DEFAULT_SETTING, value_parser = parse_setting)]
    setting: Setting,
    /// RPE delta in frames (the sub-trajectory length).
    #[arg(short = 'd', long, default_value_t = 10)]
    delta: usize,
    /// Largest time difference (s) for associating two trials' poses.
    #[arg(long = "t_max_diff", alias = "t-max-diff", default_value_t = 0.01)]
    t_max_diff: f64,
    /// Pose relation of the RPE: trans (metres), angle_deg or angle_rad (rotational estimate).
    #[arg(short = 'r', long = "pose_relation", alias = "pose-relation", default_value = "trans_part", value_parser = parse_relation)]
    pose_relation: PoseRelation,
    /// Format of the trial files.
    #[arg(
        short = 'i',
        long = "input_format",
        alias = "input-format",
        value_enum,
        default_value_t
    )]
    input_format: Format,
    /// Unit of TUM stamps: auto (integers above 10^11 are ARCore's nanoseconds, anything
    /// else seconds), s or ns.
    #[arg(long = "time_unit", alias = "time-unit", value_enum, default_value_t = StampUnit::Auto)]
    time_unit: StampUnit,
    /// Output format: csv (legacy `start,error`) or json.
    #[arg(long, value_enum, default_value_t)]
    format: OutputFormat,
    /// JSON classes: errors at or above this are "medium" (m).
    #[arg(long = "medium", default_value_t = Thresholds::DEFAULT_M.medium)]
    medium_m: f64,
    /// JSON classes: errors at or above this are "high" (m).
    #[arg(long = "high", default_value_t = Thresholds::DEFAULT_M.high)]
    high_m: f64,
    /// Write the result to this file instead of stdout.
    #[arg(short = 'o', long)]
    output: Option<PathBuf>,
    /// Calibrate the estimate with this file (made by `sitar calibrate`): JSON windows gain
    /// `raw_m` (the uncalibrated value), `lower_m` and `upper_m`; `error_m`, `class` and the
    /// CSV's error are the calibrated value. Refused if it was fitted for another setting,
    /// window or pose relation.
    #[arg(long, value_name = "FILE")]
    calibration: Option<PathBuf>,
    #[command(flatten)]
    plot: PlotArgs,
}

fn parse_setting(s: &str) -> Result<Setting, String> {
    s.parse().map_err(|e: sitar_estimator::Error| e.to_string())
}

fn parse_relation(s: &str) -> Result<PoseRelation, String> {
    match s.parse() {
        Ok(
            r @ (PoseRelation::TranslationPart
            | PoseRelation::RotationAngleDeg
            | PoseRelation::RotationAngleRad),
        ) => Ok(r),
        Ok(_) => Err("the estimate supports trans_part, angle_deg and angle_rad".into()),
        Err(e) => Err(e.to_string()),
    }
}

pub fn run(args: Args) -> Result<()> {
    if !(args.medium_m.is_finite() && args.high_m.is_finite() && args.medium_m <= args.high_m) {
        bail!(
            "--medium ({}) must not exceed --high ({})",
            args.medium_m,
            args.high_m
        );
    }
    let files = input::expand_trials(&args.trials)?;
    let runs = files.len() + usize::from(args.live.is_some());
    // Read and checked before the trials, so a wrong file fails at once (the setting matters
    // only with two or more runs).
    let calibration = match &args.calibration {
        Some(path) => {
            let calibration = Calibration::read(path)?;
            let setting = args.setting.to_string();
            calibration
                .check(
                    (runs > 1).then_some(setting.as_str()),
                    args.delta,
                    &args.pose_relation.to_string(),
                )
                .with_context(|| format!("{}", path.display()))?;
            Some((calibration, calibration_name(path)))
        }
        None => None,
    };
    if runs < 2 && calibration.is_none() {
        bail!(
            "one run: the estimate measures how runs differ, and one run has no spread to measure; give at least 2 trials, or a calibration (--calibration, made by `sitar calibrate`) to estimate the error of one run from its own motion"
        );
    }
    let bar = progress_bar(files.len() as u64, "reading trials");
    let trials = input::read_all_with(&files, args.input_format, args.time_unit.rule(), &bar)?;
    bar.finish_and_clear();
    let options = EstimateOptions {
        setting: args.setting,
        delta: args.delta,
        t_max_diff_s: args.t_max_diff,
        pose_relation: args.pose_relation,
    };
    // The live run: given with --live, or the one run given.
    let live = match &args.live {
        Some(path) => Some((
            path.clone(),
            input::read_with(path, args.input_format, args.time_unit.rule())?,
        )),
        None if trials.len() == 1 => Some((files[0].clone(), trials[0].clone())),
        None => None,
    };
    let replays: &[Trajectory] = if args.live.is_some() { &trials } else { &[] };
    let (result, first_file, first) = match (&live, &calibration) {
        (Some((path, run)), Some((calibration, name))) => (
            estimate_live(calibration, run, replays, &options, name)
                .with_context(|| format!("estimating the error of {}", path.display()))?,
            path.as_path(),
            run,
        ),
        (Some((path, run)), None) => (
            live_spread(run, replays, &options).context("--live needs at least one TRIAL")?,
            path.as_path(),
            run,
        ),
        (None, calibration) => {
            let mut result = estimate(&trials, &options).context("estimating")?;
            if let Some((calibration, name)) = calibration {
                calibration.apply(&mut result, &trials, name)?;
            }
            (result, files[0].as_path(), &trials[0])
        }
    };
    if let Some(path) = &args.plot.plot {
        let figure = error_figure(&args, first_file, first, &result);
        crate::figures::canvas::write_error_figure(path, args.plot.plot_mode, &figure)?;
    }
    let text = match args.format {
        OutputFormat::Csv => result.to_legacy_csv(),
        OutputFormat::Json => result.to_json(Thresholds::new(args.medium_m, args.high_m)) + "\n",
    };
    emit(args.output.as_deref(), &text)
}

/// A calibration's name in the output: its file name without `.json`.
pub fn calibration_name(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "calibration".into());
    name.strip_suffix(".json").unwrap_or(&name).to_owned()
}

/// The `--plot` figure: each window's estimate at its start, on the first trial's path (the
/// reference of all its pairs). A window starting where the first trial has no pose within
/// --t-max-diff (a frame it dropped) is drawn over time only.
fn error_figure(
    args: &Args,
    first_file: &Path,
    first: &Trajectory,
    result: &Estimate,
) -> ErrorFigure {
    let starts: Vec<i64> = result.windows.iter().map(|w| w.start).collect();
    let (windows, poses) =
        matching_time_indices(&starts, &first.stamps, seconds_to_ns(args.t_max_diff), 0);
    let mut positions = vec![None; starts.len()];
    for (w, p) in windows.into_iter().zip(poses) {
        positions[w] = Some(first.positions[p].to_array());
    }
    let first_stamp = first
        .stamps
        .first()
        .copied()
        .into_iter()
        .chain(starts.first().copied())
        .min()
        .unwrap_or(0);
    let indices = args.input_format == Format::Kitti;
    ErrorFigure {
        title: format!(
            "estimated error of {} trials ({}, {}, delta {} frames)",
            result.trials, result.setting, result.pose_relation, args.delta
        ),
        metric: "estimated error",
        unit: unit(args.pose_relation).to_owned(),
        x_label: if indices {
            "pose index from the first".into()
        } else {
            "t − t₀ (s)".into()
        },
        lines: Vec::new(),
        std_band: None,
        reference_name: String::new(),
        reference: Vec::new(),
        trajectory_name: format!("first trial {}", file_name(first_file)),
        trajectory: first.positions.iter().map(|p| p.to_array()).collect(),
        samples: result
            .windows
            .iter()
            .zip(positions)
            .map(|(w, position)| {
                let offset = w.start.saturating_sub(first_stamp) as f64;
                Sample {
                    x: if indices { offset } else { offset * 1e-9 },
                    position,
                    error: w.error_m,
                }
            })
            .collect(),
        colour_range: None,
    }
}
