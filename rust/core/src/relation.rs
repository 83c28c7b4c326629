//! Which part of the relative pose error the results measure, and in which unit.

use serde::{Deserialize, Serialize};

/// The part of the relative pose error an estimate measures (evo's `-r` names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseRelation {
    /// Norm of the translation part, in metres (`"trans_part"`, the paper's and the default).
    #[default]
    TransPart,
    /// Rotation angle of the error pose, in degrees (`"angle_deg"`).
    AngleDeg,
}

impl PoseRelation {
    /// Every relation the phone understands.
    pub const ALL: [PoseRelation; 2] = [PoseRelation::TransPart, PoseRelation::AngleDeg];

    /// `"trans_part"` or `"angle_deg"`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::TransPart => "trans_part",
            Self::AngleDeg => "angle_deg",
        }
    }

    /// The inverse of [`PoseRelation::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|r| r.name() == name)
    }

    /// The unit of its errors.
    pub fn unit(&self) -> ErrorUnit {
        match self {
            Self::TransPart => ErrorUnit::Metres,
            Self::AngleDeg => ErrorUnit::Degrees,
        }
    }
}

impl std::fmt::Display for PoseRelation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The unit of an error estimate, as the results JSON names it (`"unit"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum ErrorUnit {
    /// Metres (`"m"`): the translation part.
    #[default]
    Metres,
    /// Degrees (`"deg"`): the rotation angle.
    Degrees,
}

impl ErrorUnit {
    /// `"m"` or `"deg"`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Metres => "m",
            Self::Degrees => "deg",
        }
    }

    /// The inverse of [`ErrorUnit::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "m" => Some(Self::Metres),
            "deg" => Some(Self::Degrees),
            _ => None,
        }
    }

    /// The key of a window's error in the results JSON: `"error_m"` or `"error_deg"`.
    pub fn error_key(&self) -> &'static str {
        match self {
            Self::Metres => "error_m",
            Self::Degrees => "error_deg",
        }
    }

    /// The keys of a calibrated window's uncalibrated value and interval in the results
    /// JSON, `[raw, lower, upper]`: `["raw_m", "lower_m", "upper_m"]` or `["raw_deg",
    /// "lower_deg", "upper_deg"]`.
    pub fn interval_keys(&self) -> [&'static str; 3] {
        match self {
            Self::Metres => ["raw_m", "lower_m", "upper_m"],
            Self::Degrees => ["raw_deg", "lower_deg", "upper_deg"],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_match_serde() {
        for r in PoseRelation::ALL {
            assert_eq!(PoseRelation::from_name(r.name()), Some(r));
            assert_eq!(
                serde_json::to_string(&r).unwrap(),
                format!("\"{}\"", r.name())
            );
            assert_eq!(ErrorUnit::from_name(r.unit().name()), Some(r.unit()));
        }
        assert_eq!(PoseRelation::from_name("angle_rad"), None);
        assert_eq!(PoseRelation::AngleDeg.unit().error_key(), "error_deg");
        assert_eq!(
            ErrorUnit::Degrees.interval_keys(),
            ["raw_deg", "lower_deg", "upper_deg"]
        );
        assert_eq!(PoseRelation::default().unit(), ErrorUnit::Metres);
    }
}
