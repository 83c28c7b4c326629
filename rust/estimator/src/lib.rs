//! # sitar-estimator
//!
//! Trajectory formats, evo-compatible association, alignment and APE/RPE metrics, and
//! SiTAR's pairwise, ground-truth-free pose error estimation.
//!
//! ```
//! use sitar_estimator::{estimate, parse_tum, EstimateOptions, Setting};
//!
//! // Three repeated "trials" of the same 30-frame walk, the third one drifting.
//! let make = |drift: f64| {
//!     let mut text = String::new();
//!     for i in 0..30 {
//!         let t = 1_000_000_000i64 + i * 33_333_333;
//!         let x = i as f64 * 0.02 + drift * (i as f64).powi(2);
//!         text += &format!("{t} {x} 0 0 0 0 0 1\n");
//!     }
//!     parse_tum(&text, "trial").unwrap()
//! };
//! let trials = [make(0.0), make(0.0), make(0.0001)];
//! let result = estimate(&trials, &EstimateOptions { setting: Setting::Median, ..Default::default() })?;
//! assert_eq!(result.windows.len(), 20);
//! assert!(result.to_legacy_csv().starts_with("start,error\n1000000000,"));
//! # Ok::<(), sitar_estimator::Error>(())
//! ```
#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod align;
mod error;
mod estimate;
mod evaluate;
mod formats;
mod metrics;
mod statistics;
mod sync;
mod trajectory;

pub use align::{Alignment, Similarity, align, umeyama};
pub use error::Error;
pub use estimate::{
    Estimate, EstimateOptions, PairwiseValues, Thresholds, WindowEstimate, estimate,
};
pub use evaluate::{
    ClassBoundaries, ClassificationScores, Evaluation, EvaluationOptions, EvaluationRow,
    classification_scores, evaluate, ground_truth_errors,
};
pub use formats::{
    parse_euroc_csv, parse_kitti, parse_tum, read_euroc_csv, read_kitti, read_tum, write_tum,
};
pub use metrics::{
    DeltaUnit, PoseErrors, PoseRelation, RigidPose, RpeOptions, ape, delta_pairs, rotation_angle,
    rpe,
};
pub use statistics::{
    Setting, Statistics, interquartile_range, mean, mean_inliers, median, quantile, trim_mean,
};
pub use sync::{associate, associate_trajectories, matching_time_indices, seconds_to_ns};
pub use trajectory::{QUATERNION_NORM_TOLERANCE, TimeUnit, Trajectory};
