//! The features a calibration model reads per window: their names in the file, the offsets
//! added before the logarithm, and a window's values (smoothed over neighbouring windows).

use serde::{Deserialize, Serialize};

use super::motion::WindowMotion;

/// A feature of a window, as a calibration model names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Feature {
    /// How much the runs disagree: the pairwise statistic over all pairs (expected error),
    /// or over the live run and each replay (a live run's error). In the estimate's unit.
    #[serde(rename = "ln_spread", alias = "ln_statistic")]
    Spread,
    /// Path length over the window, metres.
    #[serde(rename = "ln_path_m")]
    PathM,
    /// Rotation between the window's first and last pose, degrees.
    #[serde(rename = "ln_rotation_deg")]
    RotationDeg,
    /// Straight-line displacement over the window, metres.
    #[serde(rename = "ln_displacement_m")]
    DisplacementM,
    /// Mean change of velocity per second over the window, m/s².
    #[serde(rename = "ln_jitter_mps2")]
    JitterMps2,
}

impl Feature {
    /// Every feature, in the order the fit considers them.
    pub const ALL: [Feature; 5] = [
        Feature::Spread,
        Feature::PathM,
        Feature::RotationDeg,
        Feature::DisplacementM,
        Feature::JitterMps2,
    ];

    /// The name in a calibration file.
    pub fn name(self) -> &'static str {
        match self {
            Self::Spread => "ln_spread",
            Self::PathM => "ln_path_m",
            Self::RotationDeg => "ln_rotation_deg",
            Self::DisplacementM => "ln_displacement_m",
            Self::JitterMps2 => "ln_jitter_mps2",
        }
    }

    /// What is added before the logarithm: 1 mm (or 0.001 of the estimate's unit) of spread,
    /// 1 mm of path or displacement, 0.1° of rotation, 0.01 m/s² of jitter.
    pub fn offset(self) -> f64 {
        match self {
            Self::Spread | Self::PathM | Self::DisplacementM => 1e-3,
            Self::RotationDeg => 0.1,
            Self::JitterMps2 => 1e-2,
        }
    }
}

/// A window's features before the logarithm (smoothed or not). `spread` is NaN where the runs
/// give none (one run).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowFeatures {
    /// [`Feature::Spread`].
    pub spread: f64,
    /// The run's (or the runs' median) motion.
    pub motion: WindowMotion,
}

impl WindowFeatures {
    /// One run's window: its motion and no spread.
    pub fn of_motion(motion: WindowMotion) -> Self {
        Self {
            spread: f64::NAN,
            motion,
        }
    }

    /// The value of one feature.
    pub fn get(&self, feature: Feature) -> f64 {
        match feature {
            Feature::Spread => self.spread,
            Feature::PathM => self.motion.path_m,
            Feature::RotationDeg => self.motion.rotation_deg,
            Feature::DisplacementM => self.motion.displacement_m,
            Feature::JitterMps2 => self.motion.jitter_mps2,
        }
    }

    /// As a row of five columns in [`Feature::ALL`] order (for smoothing).
    pub fn to_row(&self) -> [f64; 5] {
        Feature::ALL.map(|f| self.get(f))
    }

    /// Back from [`WindowFeatures::to_row`].
    pub fn from_row(row: [f64; 5]) -> Self {
        Self {
            spread: row[0],
            motion: WindowMotion {
                path_m: row[1],
                rotation_deg: row[2],
                displacement_m: row[3],
                jitter_mps2: row[4],
            },
        }
    }
}

/// Moving mean of every feature over each window and `h` neighbours on either side
/// ([`super::smooth_columns`]).
pub fn smooth_features(features: &[WindowFeatures], h: usize) -> Vec<WindowFeatures> {
    let rows: Vec<[f64; 5]> = features.iter().map(WindowFeatures::to_row).collect();
    super::motion::smooth_columns(&rows, h)
        .into_iter()
        .map(WindowFeatures::from_row)
        .collect()
}
