//! `sitar estimate`: per-window pose error from repeated trials, without ground truth.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use sitar_estimator::{EstimateOptions, PoseRelation, Setting, Thresholds, estimate};

use crate::input::{self, Format, progress_bar};
use crate::output::{OutputFormat, emit};

/// Estimates each window's pose error from repeated trials, without ground truth.
///
/// All n(n−1)/2 pairwise RPEs of the trials (translation, delta 10 frames, every start), then
/// a robust statistic per window. Writes the legacy CSV `start,error` (start in the trials'
/// time unit, error in metres) or JSON with the pair count, spread and class of each window.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar estimate trials/trajectory_*.txt\n  sitar estimate trials/ --setting median --format json -o results.json"
)]
pub struct Args {
    /// Trial trajectory files, at least 2, taken in the order given; a directory stands for
    /// its *.txt files in natural order.
    #[arg(required = true, value_name = "TRIAL")]
    trials: Vec<PathBuf>,
    /// Statistic per window: mean, median, trim_mean_10|20|30|40 or mean_inliers.
    #[arg(long, default_value = "trim_mean_30", value_parser = parse_setting)]
    setting: Setting,
    /// RPE delta in frames (the sub-trajectory length).
    #[arg(short = 'd', long, default_value_t = 10)]
    delta: usize,
    /// Largest time difference (s) for associating two trials' poses.
    #[arg(long = "t-max-diff", alias = "t_max_diff", default_value_t = 0.01)]
    t_max_diff: f64,
    /// Pose relation of the RPE: trans (metres), angle_deg or angle_rad (rotational estimate).
    #[arg(short = 'r', long = "pose-relation", alias = "pose_relation", default_value = "trans", value_parser = parse_relation)]
    pose_relation: PoseRelation,
    /// Format of the trial files.
    #[arg(short = 'i', long, value_enum, default_value_t)]
    input_format: Format,
    /// Output format: csv (legacy `start,error`) or json.
    #[arg(long, value_enum, default_value_t)]
    format: OutputFormat,
    /// JSON classes: errors at or above this are "medium" (m).
    #[arg(long = "medium", default_value_t = 0.05)]
    medium_m: f64,
    /// JSON classes: errors at or above this are "high" (m).
    #[arg(long = "high", default_value_t = 0.10)]
    high_m: f64,
    /// Write the result to this file instead of stdout.
    #[arg(short = 'o', long)]
    output: Option<PathBuf>,
}

fn parse_setting(s: &str) -> Result<Setting, String> {
    s.parse().map_err(|e: sitar_estimator::Error| e.to_string())
}

fn parse_relation(s: &str) -> Result<PoseRelation, String> {
    match s.parse() {
        Ok(PoseRelation::FullTransformation) => {
            Err("the estimate supports trans, angle_deg and angle_rad".into())
        }
        Ok(r) => Ok(r),
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
    if files.len() < 2 {
        bail!("the estimate needs at least 2 trials, got {}", files.len());
    }
    let bar = progress_bar(files.len() as u64, "reading trials");
    let trials = input::read_all(&files, args.input_format, &bar)?;
    bar.finish_and_clear();
    let options = EstimateOptions {
        setting: args.setting,
        delta: args.delta,
        t_max_diff_s: args.t_max_diff,
        pose_relation: args.pose_relation,
    };
    let result = estimate(&trials, &options).context("estimating")?;
    let text = match args.format {
        OutputFormat::Csv => result.to_legacy_csv(),
        OutputFormat::Json => {
            result.to_json(Thresholds {
                medium_m: args.medium_m,
                high_m: args.high_m,
            }) + "\n"
        }
    };
    emit(args.output.as_deref(), &text)
}
