//! The calibration file (`sitar calibrate` writes it): versioned JSON with what it was
//! fitted on, its models and whether the runs predict the error at all. Version 2 holds a
//! model per target and run count; version 1 (one model of the expected error from several
//! runs) is still read, as that one model.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::features::Feature;
use super::model::{CalibrationModel, IntervalModel, RunCount, Target};
use super::scores::{AgreementScores, HeldOutScores, ModelScores};
use crate::Error;

/// The `format` field of a calibration file.
pub const CALIBRATION_FORMAT: &str = "sitar-calibration";
/// The version of the calibration file this library writes.
pub const CALIBRATION_VERSION: u32 = 2;
/// Below this leave-one-sequence-out Spearman's ρ the runs are taken not to predict the
/// error: colours from such a model are a guess, and every consumer says so.
pub const INFORMATIVE_SPEARMAN: f64 = 0.3;
/// Whether a held-out Spearman's ρ says the runs predict the error: at least
/// [`INFORMATIVE_SPEARMAN`]; a ρ that could not be measured (NaN) is not held against them.
pub fn is_informative(spearman: f64) -> bool {
    spearman.is_nan() || spearman >= INFORMATIVE_SPEARMAN
}

/// The settings (statistics) a calibration may name.
const SETTINGS: [&str; 7] = [
    "mean",
    "median",
    "mean_inliers",
    "trim_mean_10",
    "trim_mean_20",
    "trim_mean_30",
    "trim_mean_40",
];
/// The pose relations a calibration may name.
const RELATIONS: [&str; 2] = ["trans_part", "angle_deg"];

/// A calibration: what it was fitted on and its models (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// Always [`CALIBRATION_FORMAT`].
    pub format: String,
    /// [`CALIBRATION_VERSION`] (a version-1 file is read as its one model).
    pub version: u32,
    /// The data and estimate settings it was fitted on.
    pub fitted_on: FittedOn,
    /// Whether every model's runs predict the error (each model says for itself too).
    pub informative: bool,
    /// One model per target and run count.
    pub models: Vec<CalibrationModel>,
}

/// What a calibration was fitted on; applying it to an estimate of another setting, window or
/// pose relation is refused.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FittedOn {
    /// The sequences with ground truth.
    pub sequences: Vec<FittedSequence>,
    /// The estimate's statistic (`trim_mean_30`, …).
    pub setting: String,
    /// The RPE delta in frames.
    pub window_frames: usize,
    /// The pose relation of the RPE (`trans_part`, `angle_deg`).
    pub pose_relation: String,
    /// The unit of the values (`m`, `deg`).
    pub unit: String,
    /// The share of windows the interval is fitted to hold.
    pub coverage: f64,
    /// Association tolerance, seconds.
    pub t_max_diff_s: f64,
}

/// One sequence a calibration was fitted on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FittedSequence {
    /// Its name (the folder).
    pub name: String,
    /// Runs used: set A and set B together.
    pub runs: usize,
    /// Runs in set A (the truth).
    pub set_a: usize,
    /// Runs in set B (the estimate).
    pub set_b: usize,
    /// Windows with both an estimate and a true error.
    pub windows: usize,
}

/// Version 1: one model of the expected error from several runs.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CalibrationV1 {
    format: String,
    version: u32,
    fitted_on: FittedOn,
    model: ModelV1,
    interval: IntervalModel,
    #[serde(default)]
    scores: Option<ScoresV1>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelV1 {
    kind: String,
    features: Vec<Feature>,
    offsets: Vec<f64>,
    smoothing_windows: usize,
    coefficients: Vec<f64>,
    spread_match: f64,
    center: f64,
    stretch: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScoresV1 {
    method: String,
    thresholds: [f64; 2],
    sequences: Vec<HeldOutV1>,
    raw: AgreementScores,
    calibrated: AgreementScores,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HeldOutV1 {
    name: String,
    raw: AgreementScores,
    calibrated: AgreementScores,
}

impl From<CalibrationV1> for Calibration {
    fn from(v1: CalibrationV1) -> Self {
        let m = v1.model;
        let scores = v1.scores.map(|s| ModelScores {
            method: s.method,
            truth: "expected".into(),
            thresholds: s.thresholds,
            sequences: s
                .sequences
                .into_iter()
                .map(|h| HeldOutScores {
                    name: h.name,
                    raw: Some(h.raw),
                    calibrated: h.calibrated,
                })
                .collect(),
            raw: Some(s.raw),
            calibrated: s.calibrated,
            candidates: Vec::new(),
        });
        let informative = scores
            .as_ref()
            .is_none_or(|s| is_informative(s.calibrated.spearman));
        Self {
            format: v1.format,
            version: v1.version,
            fitted_on: v1.fitted_on,
            informative,
            models: vec![CalibrationModel {
                target: Target::Expected,
                runs: RunCount::Several,
                kind: m.kind,
                features: m.features,
                offsets: m.offsets,
                smoothing_windows: m.smoothing_windows,
                coefficients: m.coefficients,
                spread_match: m.spread_match,
                center: m.center,
                stretch: m.stretch,
                interval: v1.interval,
                informative,
                scores,
            }],
        }
    }
}

/// Just the version, to pick the reader.
#[derive(Deserialize)]
struct Version {
    version: u32,
}

impl Calibration {
    /// Reads a calibration file; errors name the file and what is wrong.
    pub fn read(path: &Path) -> Result<Self, Error> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::from_json(&text, &path.display().to_string())
    }

    /// Parses and checks a calibration of version 1 or 2 (`source` names it in errors).
    pub fn from_json(text: &str, source: &str) -> Result<Self, Error> {
        let syntax = |e: serde_json::Error| {
            Error::parse(
                source,
                e.line(),
                "(document)",
                format!("not a calibration file: {e}"),
            )
        };
        let version = serde_json::from_str::<Version>(text)
            .map_err(syntax)?
            .version;
        let calibration: Self = match version {
            1 => serde_json::from_str::<CalibrationV1>(text)
                .map_err(syntax)?
                .into(),
            CALIBRATION_VERSION => serde_json::from_str(text).map_err(syntax)?,
            other => {
                return Err(Error::parse(
                    source,
                    0,
                    "version",
                    format!(
                        "version {other} is not a version this build reads (1 or {CALIBRATION_VERSION})"
                    ),
                ));
            }
        };
        calibration
            .validate()
            .map_err(|(field, message)| Error::parse(source, 0, &field, message))?;
        Ok(calibration)
    }

    /// The calibration as pretty JSON (a newline at the end), always version 2.
    pub fn to_json(&self) -> String {
        let mut out = self.clone();
        out.version = CALIBRATION_VERSION;
        serde_json::to_string_pretty(&out).unwrap_or_default() + "\n"
    }

    fn validate(&self) -> Result<(), (String, String)> {
        let bad = |field: &str, message: String| Err((field.to_owned(), message));
        if self.format != CALIBRATION_FORMAT {
            return bad(
                "format",
                format!(
                    "format is {:?}, expected {CALIBRATION_FORMAT:?}",
                    self.format
                ),
            );
        }
        let f = &self.fitted_on;
        if !(f.coverage > 0.0 && f.coverage < 1.0) {
            return bad(
                "fitted_on.coverage",
                format!("fitted_on.coverage {} is not between 0 and 1", f.coverage),
            );
        }
        if !SETTINGS.contains(&f.setting.as_str()) {
            return bad(
                "fitted_on.setting",
                format!(
                    "fitted_on.setting {:?} is not one of {}",
                    f.setting,
                    SETTINGS.join(", ")
                ),
            );
        }
        if !RELATIONS.contains(&f.pose_relation.as_str()) {
            return bad(
                "fitted_on.pose_relation",
                format!(
                    "fitted_on.pose_relation {:?} is not trans_part or angle_deg",
                    f.pose_relation
                ),
            );
        }
        if f.window_frames == 0 {
            return bad(
                "fitted_on.window_frames",
                "fitted_on.window_frames must be at least 1".into(),
            );
        }
        if self.models.is_empty() {
            return bad("models", "a calibration needs at least one model".into());
        }
        for (i, m) in self.models.iter().enumerate() {
            let key = |k: &str| format!("models[{i}].{k}");
            let bad = |k: &str, message: &str| Err((key(k), format!("{}: {message}", key(k))));
            if m.kind != "log_linear" {
                return bad("kind", &format!("{:?} is not log_linear", m.kind));
            }
            if m.runs == RunCount::One && (m.target != Target::Live || m.uses_spread()) {
                return bad(
                    "runs",
                    "a model for one run estimates a live run's error, without the spread",
                );
            }
            if m.offsets.len() != m.features.len()
                || m.offsets.iter().any(|o| !(o.is_finite() && *o > 0.0))
            {
                return bad("offsets", "must be one positive number per feature");
            }
            if m.coefficients.len() != m.features.len() + 1
                || m.coefficients.iter().any(|c| !c.is_finite())
            {
                return bad(
                    "coefficients",
                    "must be finite numbers: the intercept and one per feature",
                );
            }
            if !(m.center.is_finite() && m.stretch.is_finite() && m.stretch > 0.0) {
                return bad("center", "center must be finite and stretch positive");
            }
            if m.smoothing_windows > 1000 {
                return bad("smoothing_windows", "is over 1000");
            }
            let iv = &m.interval;
            if !(iv.log_lower.is_finite()
                && iv.log_upper.is_finite()
                && iv.log_lower <= iv.log_upper)
            {
                return bad(
                    "interval.log_lower",
                    "must be finite and at most interval.log_upper",
                );
            }
            if self.models[..i]
                .iter()
                .any(|o| (o.target, o.runs) == (m.target, m.runs))
            {
                return bad("target", "a second model for the same target and runs");
            }
        }
        Ok(())
    }

    /// Refuses an estimate of another window, pose relation or (when the model reads the
    /// spread, `setting` given) setting than the one this calibration was fitted for, naming
    /// both.
    pub fn check(
        &self,
        setting: Option<&str>,
        window_frames: usize,
        pose_relation: &str,
    ) -> Result<(), Error> {
        let f = &self.fitted_on;
        let setting_differs = setting.is_some_and(|s| s != f.setting);
        if setting_differs || f.window_frames != window_frames || f.pose_relation != pose_relation {
            return Err(Error::arg(
                "calibration",
                format!(
                    "the calibration was fitted for setting {}, {} window frames, pose relation {}; the estimate is setting {}, {} window frames, pose relation {}",
                    f.setting,
                    f.window_frames,
                    f.pose_relation,
                    setting.unwrap_or("(none: one run)"),
                    window_frames,
                    pose_relation
                ),
            ));
        }
        Ok(())
    }

    /// The model for `target` from `runs` runs (one run is always a live run), or an error
    /// that says what the calibration lacks.
    pub fn model(&self, target: Target, runs: usize) -> Result<&CalibrationModel, Error> {
        let (target, count) = match RunCount::of(runs) {
            RunCount::One => (Target::Live, RunCount::One),
            RunCount::Several => (target, RunCount::Several),
        };
        self.models
            .iter()
            .find(|m| (m.target, m.runs) == (target, count))
            .ok_or_else(|| {
                Error::arg(
                    "calibration",
                    format!(
                        "the calibration has no model for the {} error from {} run(s) (it has {}): fit it again with `sitar calibrate`",
                        target.name(),
                        runs,
                        self.models
                            .iter()
                            .map(|m| format!("{} from {}", m.target.name(), m.runs.name()))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })
    }
}
