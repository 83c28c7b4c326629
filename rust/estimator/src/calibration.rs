//! A calibration of the estimate: a model, fitted on runs with ground truth, from what the
//! runs alone give for a window to the window's true error, with an interval that holds the
//! true error with a stated coverage (the file `sitar calibrate` writes).
//!
//! The model is log-linear in three window features, each a moving mean over the window and
//! its `smoothing_windows` neighbours on either side (windows overlap by all but one frame,
//! so the truth is smooth while the pairwise statistic is noisy):
//!
//! ```text
//! μ = w₀ + w₁·ln(statistic + 1 mm) + w₂·ln(path_m + 1 mm) + w₃·ln(rotation_deg + 0.1°)
//! ℓ = c + (μ − c)·k          value = e^ℓ          interval = [e^(ℓ+q_lo), e^(ℓ+q_hi)]
//! ```
//!
//! `w` is the least-squares fit of ln(true error); a least-squares fit pulls every prediction
//! toward the middle, so the rare high windows would be called medium: `k =
//! (σ(ln truth)/σ(μ))^spread_match` (with `c` the mean of μ) stretches the predictions part
//! of the way back to the truth's spread. `q_lo`, `q_hi` are residual quantiles measured on
//! sequences the model was not fitted on (see [`crate::fit_calibration`]).

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::{Error, Estimate, PoseRelation, Setting, Trajectory, WindowInterval};

/// The `format` field of a calibration file.
pub const CALIBRATION_FORMAT: &str = "sitar-calibration";
/// The version of the calibration file this library writes and reads.
pub const CALIBRATION_VERSION: u32 = 1;
/// The features of the model, in the order of its coefficients (after the intercept).
pub const CALIBRATION_FEATURES: [&str; 3] = ["ln_statistic", "ln_path_m", "ln_rotation_deg"];
/// What is added to each feature before its logarithm: 1 mm (or 0.001 of the estimate's
/// unit), 1 mm of path, 0.1° of rotation.
pub const FEATURE_OFFSETS: [f64; 3] = [1e-3, 1e-3, 0.1];
/// The largest number of trials whose motion is looked at per window (they replay one
/// recording: their motion differs by the error alone), which bounds the cost of applying.
const MOTION_TRIALS: usize = 15;

/// A calibration file (versioned JSON): what it was fitted on, the model, the interval and
/// its leave-one-sequence-out scores.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// Always [`CALIBRATION_FORMAT`].
    pub format: String,
    /// [`CALIBRATION_VERSION`].
    pub version: u32,
    /// The data and estimate settings it was fitted on.
    pub fitted_on: FittedOn,
    /// The model from features to the true error.
    pub model: CalibrationModel,
    /// The interval around the model's value.
    pub interval: IntervalModel,
    /// Leave-one-sequence-out scores (absent with a single sequence).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scores: Option<CalibrationScores>,
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
    /// Runs in set A (the truth).
    pub set_a: usize,
    /// Runs in set B (the estimate).
    pub set_b: usize,
    /// Windows with both an estimate and a true error.
    pub windows: usize,
}

/// The log-linear model (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationModel {
    /// `log_linear`.
    pub kind: String,
    /// [`CALIBRATION_FEATURES`].
    pub features: Vec<String>,
    /// [`FEATURE_OFFSETS`].
    pub offsets: Vec<f64>,
    /// Neighbouring windows on each side averaged into a window's features.
    pub smoothing_windows: usize,
    /// Intercept, then one coefficient per feature.
    pub coefficients: Vec<f64>,
    /// The exponent of the stretch toward the truth's spread (0: plain least squares, 1: the
    /// predictions' spread equals the truth's).
    pub spread_match: f64,
    /// `c`: the mean of the fitted log values.
    pub center: f64,
    /// `k`: the stretch applied around `center`.
    pub stretch: f64,
}

/// The interval: quantiles of the log residuals (ln truth − ℓ).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntervalModel {
    /// How the residuals were gathered (`cross_conformal_by_sequence`: each training
    /// sequence's residuals under a model fitted on the other training sequences;
    /// `in_sample` with one sequence).
    pub method: String,
    /// The (1 − coverage)/2 quantile.
    pub log_lower: f64,
    /// The (1 + coverage)/2 quantile.
    pub log_upper: f64,
    /// Number of residuals the quantiles come from.
    pub residuals: usize,
}

/// Scores of the raw and the calibrated estimate on held-out sequences.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationScores {
    /// `leave_one_sequence_out`.
    pub method: String,
    /// The class boundaries of accuracy and F1 (medium, high).
    pub thresholds: [f64; 2],
    /// One entry per held-out sequence.
    pub sequences: Vec<HeldOutScores>,
    /// The raw estimate, averaged over sequences.
    pub raw: AgreementScores,
    /// The calibrated estimate, averaged over sequences.
    pub calibrated: AgreementScores,
}

/// One held-out sequence's scores.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeldOutScores {
    /// The sequence.
    pub name: String,
    /// The uncalibrated estimate.
    pub raw: AgreementScores,
    /// The calibrated estimate, by a calibration fitted on the other sequences.
    pub calibrated: AgreementScores,
}

/// How an estimate agrees with the truth on a set of windows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AgreementScores {
    /// Share of windows whose class is right.
    pub accuracy: f64,
    /// Macro F1 over the three classes.
    pub macro_f1: f64,
    /// Spearman's rank correlation with the truth.
    pub spearman: f64,
    /// Median of estimate/truth.
    pub median_ratio: f64,
    /// Share of the truly high windows that the estimate calls low (NaN without high ones).
    pub high_called_low: f64,
    /// Share of windows whose interval holds the truth (absent for the raw estimate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coverage: Option<f64>,
}

/// The three features of one window, before smoothing.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WindowFeatures {
    /// The estimate's statistic.
    pub statistic: f64,
    /// Path length of the window on the trials (median over trials), metres.
    pub path_m: f64,
    /// Rotation between the window's first and last pose (median over trials), degrees.
    pub rotation_deg: f64,
}

/// The unit of an estimate's values for a pose relation, as [`Estimate::to_json`] names it.
pub(crate) fn unit_of(relation: PoseRelation) -> &'static str {
    match relation {
        PoseRelation::TranslationPart => "m",
        PoseRelation::RotationAngleDeg => "deg",
        PoseRelation::RotationAngleRad => "rad",
        _ => "unit-less",
    }
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

    /// Parses and checks a calibration (`source` names it in errors).
    pub fn from_json(text: &str, source: &str) -> Result<Self, Error> {
        let calibration: Self = serde_json::from_str(text).map_err(|e| Error::Parse {
            file: source.to_owned(),
            line: e.line(),
            column: e.column(),
            message: format!("not a calibration file: {e}"),
        })?;
        calibration
            .validate()
            .map_err(|message| Error::InvalidArgument(format!("{source}: {message}")))?;
        Ok(calibration)
    }

    /// The calibration as pretty JSON (a newline at the end).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("plain data serializes") + "\n"
    }

    fn validate(&self) -> Result<(), String> {
        if self.format != CALIBRATION_FORMAT {
            return Err(format!(
                "format is {:?}, expected {CALIBRATION_FORMAT:?}",
                self.format
            ));
        }
        if self.version != CALIBRATION_VERSION {
            return Err(format!(
                "version {} is not the version this build reads ({CALIBRATION_VERSION})",
                self.version
            ));
        }
        let m = &self.model;
        if m.kind != "log_linear" {
            return Err(format!("model.kind {:?} is not log_linear", m.kind));
        }
        if m.features != CALIBRATION_FEATURES {
            return Err(format!(
                "model.features {:?} are not {CALIBRATION_FEATURES:?}",
                m.features
            ));
        }
        if m.offsets.len() != 3 || m.offsets.iter().any(|o| !(o.is_finite() && *o > 0.0)) {
            return Err("model.offsets must be 3 positive numbers".into());
        }
        if m.coefficients.len() != 4 || m.coefficients.iter().any(|c| !c.is_finite()) {
            return Err("model.coefficients must be 4 finite numbers".into());
        }
        if !(m.center.is_finite() && m.stretch.is_finite() && m.stretch > 0.0) {
            return Err("model.center must be finite and model.stretch positive".into());
        }
        if m.smoothing_windows > 1000 {
            return Err("model.smoothing_windows is over 1000".into());
        }
        let i = &self.interval;
        if !(i.log_lower.is_finite() && i.log_upper.is_finite() && i.log_lower <= i.log_upper) {
            return Err("interval.log_lower must be finite and at most interval.log_upper".into());
        }
        let f = &self.fitted_on;
        if !(f.coverage > 0.0 && f.coverage < 1.0) {
            return Err(format!(
                "fitted_on.coverage {} is not between 0 and 1",
                f.coverage
            ));
        }
        f.setting
            .parse::<Setting>()
            .map_err(|e| format!("fitted_on.setting: {e}"))?;
        f.pose_relation
            .parse::<PoseRelation>()
            .map_err(|e| format!("fitted_on.pose_relation: {e}"))?;
        if f.window_frames == 0 {
            return Err("fitted_on.window_frames must be at least 1".into());
        }
        Ok(())
    }

    /// Refuses an estimate of another setting, window or pose relation than the one this
    /// calibration was fitted for, naming both.
    pub fn check(
        &self,
        setting: Setting,
        window_frames: usize,
        pose_relation: PoseRelation,
    ) -> Result<(), Error> {
        let f = &self.fitted_on;
        let theirs = (
            setting.to_string(),
            window_frames,
            pose_relation.to_string(),
        );
        if (
            f.setting.as_str(),
            f.window_frames,
            f.pose_relation.as_str(),
        ) != (theirs.0.as_str(), theirs.1, theirs.2.as_str())
        {
            return Err(Error::InvalidArgument(format!(
                "the calibration was fitted for setting {}, {} window frames, pose relation {}; the estimate is setting {}, {} window frames, pose relation {}",
                f.setting, f.window_frames, f.pose_relation, theirs.0, theirs.1, theirs.2
            )));
        }
        Ok(())
    }

    /// Calibrates `estimate` in place: each window's `error_m` becomes the calibrated value,
    /// its `interval` holds the raw value and the bounds, and the estimate is named `name`.
    /// `trials` are the trials the estimate comes from (their motion is a feature).
    pub fn apply(
        &self,
        estimate: &mut Estimate,
        trials: &[Trajectory],
        name: &str,
    ) -> Result<(), Error> {
        self.check(estimate.setting, estimate.delta, estimate.pose_relation)?;
        let features = window_features(estimate, trials);
        let smoothed = smooth(&features, self.model.smoothing_windows);
        for (window, f) in estimate.windows.iter_mut().zip(&smoothed) {
            let (value, lower, upper) = self.predict(f);
            window.interval = Some(WindowInterval {
                raw_m: window.error_m,
                lower_m: lower,
                upper_m: upper,
            });
            window.error_m = value;
        }
        estimate.calibration = Some(name.to_owned());
        Ok(())
    }

    /// The calibrated value and interval `(value, lower, upper)` of one window's smoothed
    /// features.
    pub fn predict(&self, features: &WindowFeatures) -> (f64, f64, f64) {
        let log = self.model.log_value(features);
        (
            log.exp(),
            (log + self.interval.log_lower).exp(),
            (log + self.interval.log_upper).exp(),
        )
    }
}

impl CalibrationModel {
    /// ℓ of one window's smoothed features.
    pub(crate) fn log_value(&self, f: &WindowFeatures) -> f64 {
        let mu = self
            .coefficients
            .iter()
            .zip(design_row(f, &self.offsets))
            .map(|(w, z)| w * z)
            .sum::<f64>();
        self.center + (mu - self.center) * self.stretch
    }
}

/// `[1, ln(statistic + o₀), ln(path + o₁), ln(rotation + o₂)]`.
pub(crate) fn design_row(f: &WindowFeatures, offsets: &[f64]) -> [f64; 4] {
    let ln = |v: f64, o: f64| (v.max(0.0) + o).ln();
    [
        1.0,
        ln(f.statistic, offsets[0]),
        ln(f.path_m, offsets[1]),
        ln(f.rotation_deg, offsets[2]),
    ]
}

/// The unsmoothed features of every window of `estimate`, in its window order: the statistic,
/// and the path length and rotation of the window's `delta` frames, each the median over the
/// first [`MOTION_TRIALS`] trials that have the window's start stamp. A window no trial
/// starts at (it cannot happen for windows the estimate made from these trials) takes the
/// motion of the nearest window that has one.
pub fn window_features(estimate: &Estimate, trials: &[Trajectory]) -> Vec<WindowFeatures> {
    let delta = estimate.delta;
    let mut out: Vec<Option<WindowFeatures>> = Vec::with_capacity(estimate.windows.len());
    let (mut paths, mut rotations) = (Vec::new(), Vec::new());
    for window in &estimate.windows {
        paths.clear();
        rotations.clear();
        for trial in trials {
            if paths.len() == MOTION_TRIALS {
                break;
            }
            let Ok(k) = trial.stamps.binary_search(&window.start) else {
                continue;
            };
            if k + delta >= trial.stamps.len() {
                continue;
            }
            let path: f64 = (k..k + delta)
                .map(|i| (trial.positions[i + 1] - trial.positions[i]).length())
                .sum();
            let turn = trial.orientations[k].inverse() * trial.orientations[k + delta];
            paths.push(path);
            rotations.push(crate::rotation_angle(turn).to_degrees());
        }
        out.push((!paths.is_empty()).then(|| WindowFeatures {
            statistic: window.error_m,
            path_m: crate::median(&mut paths),
            rotation_deg: crate::median(&mut rotations),
        }));
    }
    fill_from_nearest(&out, &estimate.windows)
}

fn fill_from_nearest(
    found: &[Option<WindowFeatures>],
    windows: &[crate::WindowEstimate],
) -> Vec<WindowFeatures> {
    let known: Vec<usize> = (0..found.len()).filter(|&i| found[i].is_some()).collect();
    (0..found.len())
        .map(|i| match found[i] {
            Some(f) => f,
            None => {
                let at = known.partition_point(|&k| k < i);
                let nearest = [at.checked_sub(1), (at < known.len()).then_some(at)]
                    .into_iter()
                    .flatten()
                    .map(|j| known[j])
                    .min_by_key(|&k| k.abs_diff(i));
                let motion = nearest.and_then(|k| found[k]).unwrap_or_default();
                WindowFeatures {
                    statistic: windows[i].error_m,
                    ..motion
                }
            }
        })
        .collect()
}

/// Moving mean over each window and `h` neighbours on either side, the ends padded with the
/// first and last window (`scipy.ndimage.uniform_filter1d(size=2h+1, mode="nearest")`).
pub fn smooth(features: &[WindowFeatures], h: usize) -> Vec<WindowFeatures> {
    let n = features.len();
    if n == 0 || h == 0 {
        return features.to_vec();
    }
    let width = (2 * h + 1) as f64;
    (0..n)
        .map(|i| {
            let mut sum = [0.0f64; 3];
            for offset in 0..=2 * h {
                let j = (i + offset).saturating_sub(h).min(n - 1);
                let f = &features[j];
                sum[0] += f.statistic;
                sum[1] += f.path_m;
                sum[2] += f.rotation_deg;
            }
            WindowFeatures {
                statistic: sum[0] / width,
                path_m: sum[1] / width,
                rotation_deg: sum[2] / width,
            }
        })
        .collect()
}
