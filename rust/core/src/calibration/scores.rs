//! How a calibration's models scored on sequences they were not fitted on: the figures a
//! calibration file keeps and `sitar calibrate` prints.

use serde::{Deserialize, Serialize};

use super::features::Feature;

/// How an estimate agrees with the truth on a set of windows. A score that does not exist
/// (no truly high window, a constant estimate) is NaN, `null` in the file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AgreementScores {
    /// Share of windows whose class is right.
    #[serde(with = "nan_as_null")]
    pub accuracy: f64,
    /// Macro F1 over the three classes.
    #[serde(with = "nan_as_null")]
    pub macro_f1: f64,
    /// Spearman's rank correlation with the truth.
    #[serde(with = "nan_as_null")]
    pub spearman: f64,
    /// Median of estimate/truth.
    #[serde(with = "nan_as_null")]
    pub median_ratio: f64,
    /// Share of the truly high windows that the estimate calls low.
    #[serde(with = "nan_as_null")]
    pub high_called_low: f64,
    /// Share of windows whose interval holds the truth (absent for the raw estimate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coverage: Option<f64>,
    /// Share of the truly high windows whose upper bound is low: what `classify_by = upper`
    /// still misses (absent for the raw estimate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub high_upper_low: Option<f64>,
}

/// One held-out sequence's scores.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeldOutScores {
    /// The sequence.
    pub name: String,
    /// The uncalibrated estimate (the spread), where there is one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raw: Option<AgreementScores>,
    /// The calibrated estimate, by a calibration fitted on the other sequences.
    pub calibrated: AgreementScores,
}

/// One candidate feature set of a model and its mean held-out scores.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CandidateScores {
    /// Its features.
    pub features: Vec<Feature>,
    /// Its scores, averaged over held-out sequences.
    pub scores: AgreementScores,
    /// Whether it is the model kept.
    pub chosen: bool,
}

/// A model's scores.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelScores {
    /// `leave_one_sequence_out`, or `in_sample` with one sequence.
    pub method: String,
    /// The truth scored against: `own` (each run's own error) or `expected` (the mean error
    /// of set A).
    pub truth: String,
    /// The class boundaries of accuracy and F1 (medium, high).
    pub thresholds: [f64; 2],
    /// One entry per held-out sequence, for the model kept.
    pub sequences: Vec<HeldOutScores>,
    /// The raw estimate, averaged over sequences, where there is one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raw: Option<AgreementScores>,
    /// The model kept, averaged over sequences.
    pub calibrated: AgreementScores,
    /// Every candidate feature set tried, the kept one marked.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub candidates: Vec<CandidateScores>,
}

/// NaN written as `null` and read back as NaN (JSON has no NaN).
mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(value: &f64, serializer: S) -> Result<S::Ok, S::Error> {
        if value.is_finite() {
            serializer.serialize_f64(*value)
        } else {
            serializer.serialize_none()
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(deserializer)?.unwrap_or(f64::NAN))
    }
}
