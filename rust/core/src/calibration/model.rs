//! The log-linear model of a calibration: from a window's features to its error, with an
//! interval.
//!
//! ```text
//! μ = w₀ + Σⱼ wⱼ·ln(featureⱼ + offsetⱼ)
//! ℓ = c + (μ − c)·k          value = e^ℓ          interval = [e^(ℓ+q_lo), e^(ℓ+q_hi)]
//! ```
//!
//! `w` is the least-squares fit of ln(true error); a least-squares fit pulls every prediction
//! toward the middle, so the rare high windows would be called medium: `k =
//! (σ(ln truth)/σ(μ))^spread_match` (with `c` the mean of μ) stretches the predictions part
//! of the way back to the truth's spread. `q_lo`, `q_hi` are quantiles of log residuals
//! measured on sequences the model was not fitted on.

use serde::{Deserialize, Serialize};

use super::features::{Feature, WindowFeatures};
use super::scores::ModelScores;

/// Which error a model estimates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Target {
    /// The error of one run, the live one (on the phone: the user's own walk), from its own
    /// motion and, with replays, how much they disagree with it.
    Live,
    /// The error expected at each place of the recording: the mean over runs.
    Expected,
}

impl Target {
    /// `live` or `expected`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Live => "live",
            Self::Expected => "expected",
        }
    }
}

/// How many runs a model is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunCount {
    /// One run alone.
    One,
    /// Two or more.
    Several,
}

impl RunCount {
    /// The model's count for `runs` runs.
    pub fn of(runs: usize) -> Self {
        if runs <= 1 { Self::One } else { Self::Several }
    }

    /// `one` or `several`.
    pub fn name(self) -> &'static str {
        match self {
            Self::One => "one",
            Self::Several => "several",
        }
    }
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

/// One model of a calibration (module docs): for one target and run count.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationModel {
    /// The error it estimates.
    pub target: Target,
    /// The runs it is for.
    pub runs: RunCount,
    /// `log_linear`.
    pub kind: String,
    /// Its features, in the order of its coefficients (after the intercept).
    pub features: Vec<Feature>,
    /// What is added to each feature before its logarithm ([`Feature::offset`]).
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
    /// The interval around the model's value.
    pub interval: IntervalModel,
    /// Whether the runs predict this error at all: leave-one-sequence-out Spearman at least
    /// [`super::INFORMATIVE_SPEARMAN`] (judged in sample with one sequence).
    #[serde(default = "yes")]
    pub informative: bool,
    /// How it and the other candidates scored on held-out sequences.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scores: Option<ModelScores>,
}

fn yes() -> bool {
    true
}

/// A window's calibrated value and interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prediction {
    /// The calibrated error.
    pub value: f64,
    /// Lower bound of the interval.
    pub lower: f64,
    /// Upper bound of the interval.
    pub upper: f64,
}

impl CalibrationModel {
    /// `[1, ln(f₁ + o₁), …]` of one window's features.
    pub fn design_row(&self, f: &WindowFeatures) -> Vec<f64> {
        design_row(&self.features, &self.offsets, f)
    }

    /// ℓ of one window's smoothed features.
    pub fn log_value(&self, f: &WindowFeatures) -> f64 {
        let mut mu = self.coefficients[0];
        for ((feature, offset), w) in self
            .features
            .iter()
            .zip(&self.offsets)
            .zip(&self.coefficients[1..])
        {
            mu += w * ln_feature(f.get(*feature), *offset);
        }
        self.center + (mu - self.center) * self.stretch
    }

    /// The calibrated value and interval of one window's smoothed features.
    pub fn predict(&self, f: &WindowFeatures) -> Prediction {
        let log = self.log_value(f);
        Prediction {
            value: log.exp(),
            lower: (log + self.interval.log_lower).exp(),
            upper: (log + self.interval.log_upper).exp(),
        }
    }

    /// Whether it reads the spread between runs.
    pub fn uses_spread(&self) -> bool {
        self.features.contains(&Feature::Spread)
    }
}

/// ln(max(v, 0) + offset).
pub fn ln_feature(v: f64, offset: f64) -> f64 {
    (v.max(0.0) + offset).ln()
}

/// `[1, ln(f₁ + o₁), …]` for `features` with `offsets`.
pub fn design_row(features: &[Feature], offsets: &[f64], f: &WindowFeatures) -> Vec<f64> {
    std::iter::once(1.0)
        .chain(
            features
                .iter()
                .zip(offsets)
                .map(|(feature, o)| ln_feature(f.get(*feature), *o)),
        )
        .collect()
}
