//! What `sitar rpe` and `sitar ape` share: reading REF and EST, association, alignment.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use sitar_estimator::{
    Alignment, PoseErrors, PoseRelation, Similarity, Statistics, TimeUnit, Trajectory, align,
    associate_trajectories,
};

use crate::input::{self, Format};
use crate::output::{OutputFormat, json_number};
use crate::plot::{ErrorFigure, Sample};

/// Arguments common to `rpe` and `ape` (evo's names; `_` spellings accepted too).
#[derive(clap::Args, Debug)]
pub struct PairArgs {
    /// Reference trajectory file.
    pub reference: PathBuf,
    /// Estimated trajectory file.
    pub estimate: PathBuf,
    /// Format of both input files.
    #[arg(short = 'i', long, value_enum, default_value_t)]
    pub input_format: Format,
    /// Largest time difference (s) for associating poses by nearest stamp.
    #[arg(long = "t-max-diff", alias = "t_max_diff", default_value_t = 0.01)]
    pub t_max_diff: f64,
    /// Time offset (s) added to the estimate's stamps before association.
    #[arg(
        long = "t-offset",
        alias = "t_offset",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub t_offset: f64,
    /// Align the estimate to the reference (Umeyama SE(3); Sim(3) with --correct-scale).
    #[arg(short = 'a', long)]
    pub align: bool,
    /// Correct the scale (alone: scale only; with --align: Sim(3)).
    #[arg(short = 's', long = "correct-scale", alias = "correct_scale")]
    pub correct_scale: bool,
    /// Move the estimate's first pose onto the reference's first pose.
    #[arg(long = "align-origin", alias = "align_origin", conflicts_with_all = ["align", "correct_scale"])]
    pub align_origin: bool,
    /// Pose relation: trans (translation part, m), angle_deg, angle_rad or full.
    #[arg(short = 'r', long = "pose-relation", alias = "pose_relation", default_value = "trans", value_parser = parse_relation)]
    pub pose_relation: PoseRelation,
    /// Output format.
    #[arg(long, value_enum, default_value_t)]
    pub format: OutputFormat,
    /// Write the result to this file instead of stdout.
    #[arg(short = 'o', long)]
    pub output: Option<PathBuf>,
}

fn parse_relation(s: &str) -> Result<PoseRelation, String> {
    s.parse().map_err(|e: sitar_estimator::Error| e.to_string())
}

/// Associated (and aligned) trajectories.
pub struct Prepared {
    pub reference: Trajectory,
    pub estimate: Trajectory,
    pub alignment: Alignment,
    pub transform: Option<Similarity>,
}

impl PairArgs {
    fn alignment(&self) -> Alignment {
        match (self.align, self.correct_scale, self.align_origin) {
            (true, true, _) => Alignment::Sim3,
            (true, false, _) => Alignment::Se3,
            (false, true, _) => Alignment::ScaleOnly,
            (false, false, true) => Alignment::Origin,
            (false, false, false) => Alignment::None,
        }
    }

    /// Reads, associates and aligns, as evo's `evo_ape`/`evo_rpe` do before the metric.
    pub fn prepare(&self) -> Result<Prepared> {
        if !(self.t_max_diff.is_finite() && self.t_max_diff >= 0.0) {
            bail!(
                "--t-max-diff must be a non-negative number of seconds, got {}",
                self.t_max_diff
            );
        }
        let reference = input::read(&self.reference, self.input_format)?;
        let estimate = input::read(&self.estimate, self.input_format)?;
        let (reference, mut estimate) =
            associate_trajectories(&reference, &estimate, self.t_max_diff, self.t_offset)
                .with_context(|| {
                    format!(
                        "associating {} with {}",
                        self.reference.display(),
                        self.estimate.display()
                    )
                })?;
        let alignment = self.alignment();
        let transform = match alignment {
            Alignment::None => None,
            a => Some(align(&mut estimate, &reference, a).context("aligning the estimate")?),
        };
        Ok(Prepared {
            reference,
            estimate,
            alignment,
            transform,
        })
    }
}

/// The JSON document of an APE/RPE result.
pub fn result_json(
    metric: &str,
    args: &PairArgs,
    prepared: &Prepared,
    errors: &PoseErrors,
    extra: serde_json::Map<String, serde_json::Value>,
) -> String {
    let reference = &prepared.reference;
    let rows: Vec<serde_json::Value> = errors
        .pairs
        .iter()
        .zip(&errors.errors)
        .map(|(&(i, j), &e)| {
            if metric == "ape" {
                serde_json::json!({ "t": reference.stamps[i], "error": json_number(e) })
            } else {
                serde_json::json!({
                    "start": reference.stamps[i],
                    "end": reference.stamps[j],
                    "error": json_number(e),
                })
            }
        })
        .collect();
    let stats = statistics_json(&errors.statistics());
    let transform = prepared.transform.map(|t| {
        let r = t.rotation.transpose().to_cols_array_2d();
        serde_json::json!({
            "rotation": r,
            "translation": [t.translation.x, t.translation.y, t.translation.z],
            "scale": t.scale,
        })
    });
    let mut doc = serde_json::json!({
        "version": 1,
        "metric": metric,
        "reference": args.reference.display().to_string(),
        "estimate": args.estimate.display().to_string(),
        "pose_relation": args.pose_relation.to_string(),
        "unit": unit(args.pose_relation),
        "alignment": alignment_name(prepared.alignment),
        "transform": transform,
        "time_unit": time_unit_name(reference.time_unit),
        "associated_poses": reference.len(),
        "statistics": stats,
        "errors": rows,
    });
    if let Some(object) = doc.as_object_mut() {
        object.extend(extra);
    }
    doc.to_string()
}

/// The `--plot` figure of an APE/RPE result: each error at the reference pose (APE) or the
/// window's first reference pose (RPE), on the associated reference trajectory.
pub fn error_figure(
    metric: &'static str,
    args: &PairArgs,
    prepared: &Prepared,
    errors: &PoseErrors,
) -> ErrorFigure {
    let reference = &prepared.reference;
    let stats = errors.statistics();
    ErrorFigure {
        title: format!(
            "{metric} of {} w.r.t. {} ({}, alignment {})",
            file_name(&args.estimate),
            file_name(&args.reference),
            args.pose_relation,
            alignment_name(prepared.alignment)
        ),
        metric,
        unit: unit(args.pose_relation),
        first_stamp: reference.stamps.first().copied().unwrap_or(0),
        stamps_are_indices: args.input_format == Format::Kitti,
        lines: vec![
            ("rmse", stats.rmse),
            ("mean", stats.mean),
            ("median", stats.median),
        ],
        trajectory_name: format!("reference {}", file_name(&args.reference)),
        trajectory: reference.positions.iter().map(|p| p.to_array()).collect(),
        samples: errors
            .pairs
            .iter()
            .zip(&errors.errors)
            .map(|(&(i, _), &error)| Sample {
                stamp: reference.stamps[i],
                position: Some(reference.positions[i].to_array()),
                error,
            })
            .collect(),
    }
}

/// A path's file name, for figure titles (the whole path if it has none).
pub fn file_name(path: &std::path::Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

fn statistics_json(s: &Statistics) -> serde_json::Value {
    serde_json::json!({
        "rmse": json_number(s.rmse),
        "mean": json_number(s.mean),
        "median": json_number(s.median),
        "std": json_number(s.std),
        "min": json_number(s.min),
        "max": json_number(s.max),
        "sse": json_number(s.sse),
    })
}

/// The unit of an error value.
pub fn unit(relation: PoseRelation) -> &'static str {
    match relation {
        PoseRelation::TranslationPart => "m",
        PoseRelation::RotationAngleDeg => "deg",
        PoseRelation::RotationAngleRad => "rad",
        PoseRelation::FullTransformation => "",
    }
}

fn alignment_name(a: Alignment) -> &'static str {
    match a {
        Alignment::None => "none",
        Alignment::Se3 => "se3",
        Alignment::Sim3 => "sim3",
        Alignment::ScaleOnly => "scale",
        Alignment::Origin => "origin",
    }
}

/// "ns" or "s".
pub fn time_unit_name(unit: TimeUnit) -> &'static str {
    match unit {
        TimeUnit::Nanoseconds => "ns",
        TimeUnit::Seconds => "s",
    }
}
