//! Calibrations: from what the runs alone show for a window to the window's error, with an
//! interval of stated coverage (`sitar calibrate` fits them; this module reads and applies
//! them, so the phone can colour a walk the moment it stops).
//!
//! Per window, a calibration reads the run's own motion — path length, rotation,
//! straight-line displacement, jitter ([`WindowMotion`]) — each averaged with its
//! neighbouring windows, and with two or more runs how much they disagree (the spread). Its
//! models ([`CalibrationModel`]) are log-linear, one per [`Target`] and [`RunCount`]: the
//! error of a live run from one run alone or with replays, and the error expected at each
//! place from several runs. [`Calibration::estimate_walk`] applies the one-run model to a
//! walk; the estimator applies the others to replays.
//!
//! A calibration records whether the runs predict the error at all
//! ([`Calibration::informative`]; leave-one-sequence-out Spearman below
//! [`INFORMATIVE_SPEARMAN`] is not): where they do not, the colours are a guess and every
//! consumer says so.

mod features;
mod file;
mod model;
mod motion;
mod scores;
mod walk;

pub use features::{Feature, WindowFeatures, smooth_features};
pub use file::{
    CALIBRATION_FORMAT, CALIBRATION_VERSION, Calibration, FittedOn, FittedSequence,
    INFORMATIVE_SPEARMAN, is_informative,
};
pub use model::{
    CalibrationModel, IntervalModel, Prediction, RunCount, Target, design_row, ln_feature,
};
pub use motion::{WindowMotion, rotation_angle, run_motion, smooth_columns, window_motion};
pub use scores::{AgreementScores, CandidateScores, HeldOutScores, ModelScores};
pub use walk::{SOURCE_REPLAYS, SOURCE_WALK};
