//! # sitar-estimator
//!
//! Trajectory formats, evo-compatible association, alignment and APE/RPE metrics, and
//! SiTAR's pairwise, ground-truth-free pose error estimation (ISMAR 2023, section 3), with
//! the paper's evaluation protocol against ground truth.
//!
//! ## Quick start
//!
//! ```
//! use sitar_estimator::{estimate, parse_tum, EstimateOptions, Setting, Thresholds};
//!
//! // Three repeated "trials" of the same 30-frame walk, the third one drifting.
//! let make = |drift: f64| {
//!     let mut text = String::from("# t x y z qx qy qz qw\n");
//!     for i in 0..30 {
//!         let t = 1_000_000_000i64 + i * 33_333_333; // integer stamps: nanoseconds
//!         let x = i as f64 * 0.02 + drift * (i as f64).powi(2);
//!         text += &format!("{t} {x} 0 0 0 0 0 1\n");
//!     }
//!     parse_tum(&text, "trial.txt").unwrap()
//! };
//! let trials = [make(0.0), make(0.0), make(0.0001)];
//! let result = estimate(&trials, &EstimateOptions { setting: Setting::Median, ..Default::default() })?;
//! assert_eq!(result.windows.len(), 20); // one window per start frame with 10 frames after it
//! assert_eq!(result.windows[0].pairs, 3); // n(n-1)/2 pairs
//! assert!(result.to_legacy_csv().starts_with("start,error\n1000000000,"));
//! assert!(result.to_json(Thresholds::default()).contains("\"class\":\"low\""));
//! # Ok::<(), sitar_estimator::Error>(())
//! ```
//!
//! ## Trajectories and formats
//!
//! A [`Trajectory`] holds strictly increasing `i64` nanosecond stamps, positions and unit
//! quaternions (world-from-camera), and the [`TimeUnit`] it was read in, which output keeps.
//! [`read_tum`]/[`parse_tum`] read `t x y z qx qy qz qw` (`#` comments; all-integer stamps are
//! nanoseconds, otherwise decimal seconds, converted exactly; scientific notation accepted);
//! [`write_tum`] writes it back losslessly. [`read_euroc_csv`] reads EuRoC ground truth,
//! [`read_kitti`] KITTI poses (stamp = pose index). Every error names the file, line and
//! column; NaN/inf, a quaternion norm off by more than [`QUATERNION_NORM_TOLERANCE`], and
//! duplicate or decreasing stamps are errors.
//!
//! ## evo semantics
//!
//! * [`associate`] / [`associate_trajectories`]: evo's `associate_trajectories` — the shorter
//!   trajectory (the second on a tie of lengths) is walked, each stamp takes the nearest stamp
//!   of the other within `max_diff` (the earlier on an exact tie; indices may repeat).
//! * [`umeyama`] / [`align`] with [`Alignment`]: SE(3), Sim(3), scale only, origin; the
//!   reflection fix; rank-deficient covariance is [`Error::DegenerateAlignment`].
//! * [`rpe`] / [`ape`] with [`PoseRelation`] (translation part, angle in degrees/radians,
//!   full) and [`RpeOptions`] (delta in frames or metres, `all_pairs`); [`Statistics`] has
//!   rmse, mean, median, std, min, max and sse.
//!
//! Golden tests (`tests/golden.rs`, data from `scripts/golden/make_goldens.py`) check all of
//! this against evo, numpy and scipy to 1e-9.
//!
//! ## Pairwise estimation
//!
//! [`estimate`] follows ARCHITECTURE.md: for each pair `i < j` of trials (in the given order)
//! trial `i` is the reference; the pair is associated as evo does; an all-pairs RPE over
//! `delta` frames (10) gives one value per associated start frame, keyed by the reference's
//! start stamp; per key, a [`Setting`] (`mean`, `median`, `trim_mean_10..40`,
//! `mean_inliers`; default `trim_mean_30`) over every pair with that key is the estimate.
//! Each [`WindowEstimate`] also carries the pair count and the standard deviation of the
//! pair values (`spread_m`). `EstimateOptions::pose_relation` = `RotationAngleDeg` gives the
//! rotational estimate. [`PairwiseValues`] lets one computation serve several settings.
//!
//! Why it is fast: the translation RPE of window `k` is `‖R_Pk^T(p_{k+d} − p_k) −
//! R_Qk^T(q_{k+d} − q_k)‖`, so each trial's relative poses are computed once and shared by all
//! its pairs. Trials with identical stamps (trials replaying one recording) need no
//! association: per window key their relative poses are gathered once and every pair inside
//! the group is formed from that small, cache-resident set. Other pairs are associated once
//! per distinct pair of stamp lists and stored as contiguous runs plus the few windows a
//! dropped frame breaks. Windows are aggregated in parallel blocks with rank selection on
//! the values' bits (no sorting). 100 trials × 2820 poses take 0.35–0.45 CPU-seconds end to
//! end from files, at under 60 MB peak memory.
//!
//! ## Evaluation against ground truth
//!
//! [`evaluate`] runs the paper's section 3.3 protocol on one sequence: the ground-truth
//! per-window error is the mean RPE of trial set A against the ground truth
//! ([`ground_truth_errors`]); the estimate uses the first `k` trials of set B; both are
//! classified by 3-class classifiers ([`PAPER_CLASSIFIERS`]: 5 & 10, 2 & 10, 2 & 5 cm, each [`Thresholds`])
//! and scored ([`classification_scores`]: accuracy, macro F1, mean per-class sensitivity and
//! specificity) for every setting and trial count.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod align;
mod bootstrap;
mod error;
mod estimate;
mod evaluate;
mod formats;
mod metrics;
mod ranking;
mod statistics;
mod sync;
mod trajectory;

pub use align::{Alignment, Similarity, align, umeyama};
pub use bootstrap::{MeanInterval, bootstrap_mean};
pub use error::Error;
pub use estimate::{Estimate, EstimateOptions, PairwiseValues, WindowEstimate, estimate};
pub use evaluate::{
    ClassificationScores, Evaluation, EvaluationOptions, EvaluationRow, MatchedWindows,
    PAPER_CLASSIFIERS, classification_scores, evaluate, ground_truth_errors, matched_windows,
};
pub use formats::{
    parse_euroc_csv, parse_kitti, parse_tum, read_euroc_csv, read_kitti, read_tum, write_tum,
};
pub use metrics::{
    DeltaUnit, PoseErrors, PoseRelation, RigidPose, RpeOptions, ape, delta_pairs, rotation_angle,
    rpe,
};
pub use ranking::{
    MIN_FIT_ERROR_M, SweepPoint, ThresholdSweep, fit_scale, median_ratio, spearman, threshold_sweep,
};
/// The class rule and its defaults, shared with the phone and the backend.
pub use sitar_core::{DEFAULT_SETTING, ErrorClass, Thresholds};
pub use statistics::{
    Setting, Statistics, interquartile_range, mean, mean_inliers, median, quantile, trim_mean,
};
pub use sync::{associate, associate_trajectories, matching_time_indices, seconds_to_ns};
pub use trajectory::{QUATERNION_NORM_TOLERANCE, TimeUnit, Trajectory};
