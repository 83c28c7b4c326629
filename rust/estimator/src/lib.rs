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
//!         let t = 1_000_000_000_000i64 + i * 33_333_333; // integers > 10^11: nanoseconds
//!         let x = i as f64 * 0.02 + drift * (i as f64).powi(2);
//!         text += &format!("{t} {x} 0 0 0 0 0 1\n");
//!     }
//!     parse_tum(&text, "trial.txt").unwrap()
//! };
//! let trials = [make(0.0), make(0.0), make(0.0001)];
//! let result = estimate(&trials, &EstimateOptions { setting: Setting::Median, ..Default::default() })?;
//! assert_eq!(result.windows.len(), 20); // one window per start frame with 10 frames after it
//! assert_eq!(result.windows[0].pairs, 3); // n(n-1)/2 pairs
//! assert!(result.to_legacy_csv().starts_with("start,error\n1000000000000,"));
//! assert!(result.to_json(Thresholds::default()).contains("\"class\":\"low\""));
//! # Ok::<(), sitar_estimator::Error>(())
//! ```
//!
//! ## Trajectories and formats
//!
//! A [`Trajectory`] holds `i64` nanosecond stamps, positions and unit quaternions
//! (world-from-camera), and the [`TimeUnit`] it was read in, which output keeps.
//! [`read_tum`]/[`parse_tum`] read `t x y z qx qy qz qw` by SiTAR's rules
//! ([`ReadOptions::SITAR`]): `#` comments; stamps that are all integer tokens, one of them
//! above [`NANOSECOND_STAMP_THRESHOLD`] (10¹¹: too large to be seconds since 1970), are
//! nanoseconds — ARCore's trials —, anything else is seconds, converted exactly (scientific
//! notation accepted); stamps must increase and quaternions be unit to
//! [`QUATERNION_NORM_TOLERANCE`]. [`parse_tum_with`] takes a [`ReadOptions`]: an explicit
//! [`TimeUnitRule`], or [`ReadOptions::EVO`], evo's reading (seconds, repeated and unsorted
//! stamps kept, any quaternion normalised) with a [`ReadReport`] of what it met.
//! [`write_tum`] writes it back losslessly. [`read_euroc_csv`] reads EuRoC ground truth,
//! [`read_kitti`] KITTI poses (stamp = pose index). Every reader skips a UTF-8 byte-order
//! mark and takes `\n`, `\r\n` and `\r` line ends; every error names the file, line and
//! column (NaN/inf, a control character such as NUL between fields, a bad column count).
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
//! ## Drift over path length (KITTI)
//!
//! [`drift`] is the KITTI odometry benchmark's metric as its devkit (`evaluate_odometry.cpp`)
//! defines it: segments of 100, 200, …, 800 m of ground-truth path ([`DriftOptions`]:
//! any lengths, a start every 10 poses), per segment the translational error in % and the
//! rotational error in deg/m of the segment's relative pose, averaged per length, per speed
//! bin and over every segment ([`Drift`]). The module docs of [`drift`] give the formulas and
//! every difference from the devkit.
//!
//! ```
//! use glam::{DQuat, DVec3};
//! use sitar_estimator::{drift, DriftOptions, TimeUnit, Trajectory};
//!
//! // A straight walk, a pose every 0.1 m, and an estimate 2 % too long.
//! let walk = |scale: f64| Trajectory {
//!     stamps: (0..200).map(|i| i * 100_000_000).collect(),
//!     positions: (0..200).map(|i| DVec3::new(0.1 * i as f64 * scale, 0.0, 0.0)).collect(),
//!     orientations: vec![DQuat::IDENTITY; 200],
//!     time_unit: TimeUnit::Nanoseconds,
//! };
//! let options = DriftOptions { lengths_m: vec![5.0, 10.0], ..DriftOptions::default() };
//! let result = drift(&walk(1.0), &walk(1.02), &options)?;
//! assert!((result.t_err_percent - 2.0).abs() < 0.05); // 2 % of a path just over L
//! assert_eq!(result.r_err_deg_per_m, 0.0);
//! assert_eq!(result.by_length.len(), 2);
//! # Ok::<(), sitar_estimator::Error>(())
//! ```
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
//! rotational estimate. [`PairwiseValues`] lets one computation serve several settings;
//! [`IncrementalEstimate`] grows trial by trial.
//!
//! Why it is fast: the translation RPE of window `k` is `‖R_Pk^T(p_{k+d} − p_k) −
//! R_Qk^T(q_{k+d} − q_k)‖`, so each trial's relative poses are computed once and shared by all
//! its pairs. Trials with identical stamps (trials replaying one recording) need no
//! association: per window key their relative poses are gathered once and every pair inside
//! the group is formed from that small, cache-resident set. Other pairs are associated once
//! per distinct pair of stamp lists and stored as contiguous runs plus the few windows a
//! dropped frame breaks. Windows are aggregated in parallel blocks with rank selection on
//! the values' bits (no sorting) and exact sums (below). 100 trials × 2820 poses take
//! about 0.45–0.6 CPU-seconds end to end from files (measured on a loaded 2-core machine).
//!
//! ## Exact, order-independent statistics
//!
//! Every window statistic is a function of the *multiset* of its pair values, never of the
//! order they were gathered in: order statistics come from rank selection, and every sum (the
//! mean, the trimmed middle, the inliers) is exact — a fixed-point superaccumulator over the
//! whole double range (64-bit digits in `i128` words, so additions never carry), rounded once,
//! correctly, when read. The spread (`spread_m`, numpy's population `std`) is
//! `sqrt((n·Σx² − (Σx)²) / n²)` with exact squares (the 106-bit square of each mantissa) and
//! the numerator computed exactly and rounded once: it matches exact rational arithmetic to
//! 2 ulps whatever the ratio of mean to spread (numpy itself is off by 6e-8 when the spread is
//! 1e-12 of the mean), and numpy's `std` on the golden trials to 4.4e-13 relative. Sums run
//! in registers (a u128 for values, two for squares, relative to the window's largest value)
//! and are flushed into the accumulator: about 6 ns per value, which doubled the CPU time of
//! the aggregation stage (0.16 → 0.31 s at 100 × 2820).
//! Golden data: `tests/data/golden_exact_sums.json` from Python's `fractions` and `math.fsum`
//! (`scripts/golden/make_exact_sums.py`).
//!
//! ## Incremental estimation
//!
//! [`IncrementalEstimate`] serves the backend's progressive results: `push` adds one trial,
//! `estimate()` gives the estimate over the trials so far, **bitwise equal** to
//! [`estimate`] on them (every window's start, end, pair count, error and spread; a proptest
//! checks it after every push for every setting, `trans_part` and `angle_deg`, identical
//! stamps, dropped frames and jittered stamps). Trials may arrive out of playback order:
//! `push_ordered(trial, place)` gives each its place, and the estimate equals [`estimate`]
//! on the trials sorted by place (a proptest pushes them in shuffled orders). Every trial's
//! stamps are keys from its arrival on (a key no reference has gets no window), and each
//! new pair takes the trial of the earlier place as its reference.
//!
//! * *Why it is exact:* both paths compute the same function of the same multiset per window
//!   (the previous section); the incremental one only gathers the multiset differently.
//! * *What a push of trial `j` does:* associates it with the `j` trials before it (once per
//!   distinct pair of stamp lists; new reference stamps re-index the keys, O(total poses)),
//!   computes only the new pairs' values (`j` per window) and, per window: sorts them
//!   (O(j log j)), adds them to the exact sums in registers (O(j)), appends them as a sorted
//!   run and moves the setting's cursors to their new ranks (O(steps × runs), steps ≤ j per
//!   cursor; measured 0.29 steps per new value). No push touches the values already stored,
//!   except merging young runs: the runs of a window are merged while the older is at most
//!   twice the newer (LSM-style, so at most log₂ m + 1 young runs), and a run of 512 values
//!   or more is frozen and never moved again (3.5 values moved by merges and one copy on
//!   freezing per value, 3.7 runs on
//!   average at 100 trials). Each window's statistic is recomputed from its state right after the push
//!   (while in cache), so `estimate()` only assembles, O(windows).
//! * *The state per window:* the count, the exact sum and sum of squares, and — for every
//!   setting but `mean` — the values as sorted runs with the cursors (median: 1; trimmed mean:
//!   `lowercut` and `uppercut` with the exact sum between them; mean of inliers: the two
//!   quartile ranks and the two fences with the sum between them). That is 8 bytes per pair
//!   value (up to 1.5× that in the young runs' spare capacity) plus about 2.4 KB per window
//!   (the accumulators) and 20 bytes per run and cursor; per trial, the poses (64 B each),
//!   the relative poses (24 B per pose, 56 B for rotations) and its key indices.
//!   [`IncrementalEstimate::memory_bytes`] reports all of it (capacities).
//! * *Measured* (`cargo bench -p sitar-estimator --bench incremental`, 100 trials × 2820
//!   poses, every third dropping frames, push + estimate after each trial from the 2nd on):
//!   see the crate README for the figures; the incremental path costs about 4× one one-shot
//!   estimate in CPU (the one-shot never stores its 14 M values: it computes them block by
//!   block in cache), against 33× for recomputing everything after each trial.
//!
//! ## Evaluation against ground truth
//!
//! [`evaluate`] runs the paper's section 3.3 protocol on one sequence: the ground-truth
//! per-window error is the mean RPE of trial set A against the ground truth
//! ([`ground_truth_errors`]); the estimate uses the first `k` trials of set B; both are
//! classified by 3-class classifiers ([`PAPER_CLASSIFIERS`]: 5 & 10, 2 & 10, 2 & 5 cm, each [`Thresholds`])
//! and scored ([`classification_scores`]: accuracy, macro F1, mean per-class sensitivity and
//! specificity) for every setting and trial count.
//!
//! ## Calibration
//!
//! The estimate measures how runs differ, not the error against ground truth. A
//! [`Calibration`] (made by [`fit_calibration`] on [`CalibrationSequence`]s with ground truth,
//! `sitar calibrate`; the file's types are `sitar_core::calibration`'s, so the phone reads
//! it too) maps what the runs alone show for a window — each run's own motion (path,
//! rotation, displacement, jitter) and, from two runs, their spread, each a moving mean over
//! neighbouring windows — to its true error with log-linear models, one per target and run
//! count, and gives an interval that holds the true error with a stated coverage on
//! sequences it was not fitted on (cross-conformal by sequence).
//! [`ApplyCalibration::apply`] turns a pairwise [`Estimate`] into the expected error;
//! [`estimate_live`] gives the error of one live run, alone or with replays: `error_m`
//! calibrated, [`WindowInterval`] with the raw value and the bounds, JSON keys `raw_m`,
//! `lower_m`, `upper_m`, `calibration`, `target`, `runs` and `informative`. The model, the
//! choices and the figures on three real systems: the user guide
//! (`docs/src/science/calibration.md`, `docs/src/science/real-runs.md`).
#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod align;
mod bag_writer;
mod bootstrap;
mod calibration;
mod calibration_fit;
mod direction;
mod drift;
mod error;
mod estimate;
mod evaluate;
mod exact;
mod formats;
mod incremental;
mod metrics;
mod pairwise;
mod pose_messages;
mod ranking;
mod relative_lengths;
mod ros1;
mod rosbag;
mod rpg_align;
mod sorted_runs;
mod statistics;
mod sync;
mod tf;
mod trajectory;

pub use align::{Alignment, GravityAxis, Similarity, align, align_first, position_yaw, umeyama};
pub use bag_writer::{PoseTopic, mcap_bag, ros1_bag, rosbag2_metadata};
pub use bootstrap::{MeanInterval, bootstrap_mean};
pub use calibration::{
    ApplyCalibration, LiveWindows, estimate_live, expected_features, live_spread, live_windows,
    motion_at,
};
pub use calibration_fit::{
    CalibrationSequence, DEFAULT_SMOOTHING_WINDOWS, DEFAULT_SPREAD_MATCH, FitOptions, MODELS,
    SELECTION_NOISE, WindowSet, agreement_scores, candidate_features, choose, fit_calibration,
    fit_features, high_called_low, mean_scores, score_features,
};
pub use direction::{
    DirectionComponents, DirectionRelation, ape_by_direction, direction_components, headings,
    swing_twist,
};
pub use drift::{
    Drift, DriftBin, DriftOptions, DriftSegment, KITTI_FRAME_INTERVAL_S, KITTI_LENGTHS_M,
    KITTI_SPEED_STEP_M_S, KITTI_STEP, MIN_SEGMENTS_PER_BIN, SPEED_BINS, SegmentDuration, drift,
};
pub use error::Error;
pub use estimate::{
    CalibratedAs, Estimate, EstimateOptions, PairwiseValues, WindowEstimate, WindowInterval,
    estimate,
};
pub use evaluate::{
    ClassificationScores, Evaluation, EvaluationOptions, EvaluationRow, MatchedWindows,
    PAPER_CLASSIFIERS, calibrated_matched_windows, classification_scores, evaluate,
    ground_truth_errors, matched_windows, own_error_matched_windows,
};
pub use formats::{
    NANOSECOND_STAMP_THRESHOLD, ReadOptions, ReadReport, StampOrder, TimeUnitRule, parse_euroc_csv,
    parse_euroc_csv_with, parse_kitti, parse_tum, parse_tum_with, read_euroc_csv,
    read_euroc_csv_with, read_kitti, read_tum, read_tum_with, write_tum,
};
pub use incremental::IncrementalEstimate;
pub use metrics::{
    DeltaUnit, PoseErrors, PoseRelation, RigidPose, RpeOptions, ape, delta_pairs, rpe,
};
pub use pose_messages::{Encoding, PoseMessage, StampedPoseValue, TopicMessages};
pub use ranking::{
    MIN_FIT_ERROR_M, SweepPoint, ThresholdSweep, fit_scale, median_ratio, spearman, threshold_sweep,
};
pub use relative_lengths::{
    RPG_DEFAULT_PERCENTS, RPG_LENGTH_TOLERANCE, RelativeAtLength, RelativeSample,
    cumulative_path_length, lengths_from_percents, relative_errors,
};
pub use ros1::{decode_ros1_pose, read_ros1_bag, read_ros1_bag_topics};
pub use rosbag::{
    BagTrajectory, decode_pose, decode_pose_as, read_mcap, read_mcap_from, read_mcap_topics,
    topic_trajectory,
};
pub use rpg_align::{
    RPG_MAX_DIFF_NS, RpgAlignType, RpgAlignment, absolute_translation_errors, rpg_align,
    rpg_associate,
};
/// The calibration file and its models, shared with the phone and the backend.
pub use sitar_core::calibration::{
    AgreementScores, CALIBRATION_FORMAT, CALIBRATION_VERSION, Calibration, CalibrationModel,
    CandidateScores, Feature, FittedOn, FittedSequence, HeldOutScores, INFORMATIVE_SPEARMAN,
    IntervalModel, ModelScores, Prediction, RunCount, Target, WindowFeatures, WindowMotion,
    smooth_features,
};
/// The class rule and its defaults, shared with the phone and the backend.
pub use sitar_core::{DEFAULT_SETTING, ErrorClass, Thresholds};
pub use statistics::{
    Setting, Statistics, interquartile_range, mean, mean_inliers, median, quantile, trim_mean,
};
pub use sync::{
    associate, associate_trajectories, match_trajectories, matching_time_indices,
    matching_time_indices_seconds, seconds_to_ns,
};
pub use tf::{
    TF_LOOKUP_STEP_NS, TF_MESSAGE_TYPE, TfBuffer, TfId, TfTransform, decode_tf_message,
    tf_trajectory,
};
pub use trajectory::{
    Plane, QUATERNION_NORM_TOLERANCE, TimeUnit, Trajectory, euler_sxyz, pairwise_sum,
    rotation_angle,
};
