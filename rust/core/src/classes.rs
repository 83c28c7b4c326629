//! The one error-class rule of the whole system, and the defaults every crate shares.
//!
//! The phone colours a sub-trajectory, the estimator labels a results window, the
//! evaluation scores a classifier, the backend decides adaptive stopping and draws the
//! report: all of them classify an error with [`Thresholds::classify`] — high at or above
//! `high`, medium at or above `medium`, else low — so the rule is written once.

use serde::{Deserialize, Serialize};

/// The error class of a sub-trajectory (numbers as in the C ABI).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default, Serialize, Deserialize,
)]
#[serde(rename_all = "lowercase")]
#[repr(i32)]
pub enum ErrorClass {
    /// No result within the lookup tolerance.
    #[default]
    Unknown = 0,
    /// Below the medium threshold.
    Low = 1,
    /// At or above the medium threshold, below high.
    Medium = 2,
    /// At or above the high threshold.
    High = 3,
}

impl ErrorClass {
    /// The three classes an error can have, lowest first.
    pub const KNOWN: [ErrorClass; 3] = [ErrorClass::Low, ErrorClass::Medium, ErrorClass::High];

    /// `"unknown"`, `"low"`, `"medium"` or `"high"`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Unknown => "unknown",
            Self::Low => "low",
            Self::Medium => "medium",
            Self::High => "high",
        }
    }

    /// The inverse of [`ErrorClass::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "unknown" => Some(Self::Unknown),
            "low" => Some(Self::Low),
            "medium" => Some(Self::Medium),
            "high" => Some(Self::High),
            _ => None,
        }
    }

    /// 0 (low), 1 (medium) or 2 (high): the row or column of a confusion matrix;
    /// `None` for [`ErrorClass::Unknown`].
    pub fn index(&self) -> Option<usize> {
        match self {
            Self::Unknown => None,
            Self::Low => Some(0),
            Self::Medium => Some(1),
            Self::High => Some(2),
        }
    }
}

/// The two class boundaries, in the unit of the errors they classify (metres for the
/// translation part, degrees for the rotation angle).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Thresholds {
    /// Errors at or above this are at least medium.
    pub medium: f64,
    /// Errors at or above this are high.
    pub high: f64,
}

impl Thresholds {
    /// The paper's classes for the translation part: medium from 5 cm, high from 10 cm.
    pub const DEFAULT_M: Thresholds = Thresholds {
        medium: 0.05,
        high: 0.10,
    };

    /// Classes for the rotation angle (`angle_deg`): medium from 2°, high from 4°. A rotation
    /// error of θ moves a surface d metres away by about θ·d; at 1.5 m (the distance the
    /// phone's depth samples typically see indoors) the metric boundaries 5 cm and 10 cm
    /// are 1.9° and 3.8°, rounded here to 2° and 4°.
    pub const DEFAULT_DEG: Thresholds = Thresholds {
        medium: 2.0,
        high: 4.0,
    };

    /// Classes with both boundaries given.
    pub const fn new(medium: f64, high: f64) -> Thresholds {
        Thresholds { medium, high }
    }

    /// High at or above `high`, medium at or above `medium`, else low. NaN is low (it is
    /// at or above nothing); callers that can meet NaN check for it first.
    pub fn classify(&self, error: f64) -> ErrorClass {
        if error >= self.high {
            ErrorClass::High
        } else if error >= self.medium {
            ErrorClass::Medium
        } else {
            ErrorClass::Low
        }
    }
}

impl Default for Thresholds {
    fn default() -> Self {
        Self::DEFAULT_M
    }
}

/// The statistic every crate uses when none is asked for: scipy's `trim_mean` cutting 30 %
/// from each end, the paper's best setting.
pub const DEFAULT_SETTING: &str = "trim_mean_30";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boundaries_are_inclusive_from_below() {
        let t = Thresholds::DEFAULT_M;
        assert_eq!(t.classify(0.10), ErrorClass::High);
        assert_eq!(t.classify(0.0999), ErrorClass::Medium);
        assert_eq!(t.classify(0.05), ErrorClass::Medium);
        assert_eq!(t.classify(0.049), ErrorClass::Low);
        assert_eq!(t.classify(f64::NAN), ErrorClass::Low);
        assert_eq!(Thresholds::new(0.2, 0.5).classify(0.3), ErrorClass::Medium);
        assert_eq!(Thresholds::default(), Thresholds::DEFAULT_M);
        // The degree boundaries are the metric ones seen from 1.5 m, to a tenth of a degree.
        for (deg, m) in [
            (Thresholds::DEFAULT_DEG.medium, 0.05),
            (Thresholds::DEFAULT_DEG.high, 0.10),
        ] {
            assert!(
                (deg - (m / 1.5f64).atan().to_degrees()).abs() < 0.2,
                "{deg}"
            );
        }
    }

    #[test]
    fn names_and_indices_round_trip() {
        for class in ErrorClass::KNOWN {
            assert_eq!(ErrorClass::from_name(class.name()), Some(class));
            assert_eq!(ErrorClass::KNOWN[class.index().unwrap()], class);
        }
        assert_eq!(ErrorClass::Unknown.index(), None);
        assert_eq!(ErrorClass::from_name("severe"), None);
    }
}
