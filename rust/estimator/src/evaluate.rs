//! Evaluation of the estimate against ground truth (the paper's section 3.3, Table 2).
//!
//! Per sequence: the ground-truth average error per window comes from trial set A (RPE of
//! every trial against the ground truth, averaged per window); the estimate comes from the
//! first `k` trials of a disjoint set B. Both are classified by a 3-class classifier
//! (low < `medium` ≤ medium < `high` ≤ high, [`Thresholds`]) and scored with accuracy, macro F1 and the
//! per-class sensitivity and specificity averaged over classes.

use rayon::prelude::*;

use crate::calibration::ApplyCalibration;
use crate::sync::{associate_named, seconds_to_ns};
use crate::{
    Calibration, Error, EstimateOptions, PairwiseValues, RpeOptions, Setting, Thresholds,
    Trajectory, rpe,
};

/// The paper's three classifiers (Table 2): medium from 5 cm and high from 10 cm, 2 & 10 cm,
/// 2 & 5 cm.
pub const PAPER_CLASSIFIERS: [Thresholds; 3] = [
    Thresholds::DEFAULT_M,
    Thresholds::new(0.02, 0.10),
    Thresholds::new(0.02, 0.05),
];

/// The row or column of `error` in a confusion matrix: 0 low, 1 medium, 2 high.
fn class_index(boundaries: &Thresholds, error: f64) -> usize {
    // `classify` never answers Unknown.
    boundaries.classify(error).index().unwrap_or(0)
}

/// Scores of a classifier on one set of windows.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ClassificationScores {
    /// Share of windows classified correctly.
    pub accuracy: f64,
    /// Mean F1 over the classes present in the truth or the prediction (as scikit-learn's
    /// `f1_score(average="macro")`).
    pub macro_f1: f64,
    /// Mean sensitivity (recall) over the classes present in the truth.
    pub sensitivity: f64,
    /// Mean specificity over the classes present in the truth or the prediction (a class
    /// that occurs in neither would add a meaningless 1).
    pub specificity: f64,
    /// Number of windows scored.
    pub windows: usize,
    /// Confusion matrix `[truth][predicted]`.
    pub confusion: [[usize; 3]; 3],
}

/// Scores predicted errors against true errors (same windows, same order).
pub fn classification_scores(
    truth: &[f64],
    predicted: &[f64],
    boundaries: Thresholds,
) -> Result<ClassificationScores, Error> {
    if truth.len() != predicted.len() || truth.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "need equally many, non-zero true and predicted errors (got {} and {})",
            truth.len(),
            predicted.len()
        )));
    }
    let mut confusion = [[0usize; 3]; 3];
    for (t, p) in truth.iter().zip(predicted) {
        confusion[class_index(&boundaries, *t)][class_index(&boundaries, *p)] += 1;
    }
    let total = truth.len();
    let correct: usize = (0..3).map(|c| confusion[c][c]).sum();
    let (mut f1, mut f1_classes) = (0.0, 0);
    let (mut sensitivity, mut sensitivity_classes) = (0.0, 0);
    let (mut specificity, mut specificity_classes) = (0.0, 0);
    for (c, row) in confusion.iter().enumerate() {
        let tp = row[c];
        let fn_ = row.iter().sum::<usize>() - tp;
        let fp = (0..3).map(|t| confusion[t][c]).sum::<usize>() - tp;
        let tn = total - tp - fn_ - fp;
        if tp + fn_ + fp > 0 {
            f1 += 2.0 * tp as f64 / (2 * tp + fp + fn_) as f64;
            f1_classes += 1;
        }
        if tp + fn_ > 0 {
            sensitivity += tp as f64 / (tp + fn_) as f64;
            sensitivity_classes += 1;
        }
        if tp + fn_ + fp > 0 && tn + fp > 0 {
            specificity += tn as f64 / (tn + fp) as f64;
            specificity_classes += 1;
        }
    }
    let average = |sum: f64, count: usize| {
        if count == 0 {
            f64::NAN
        } else {
            sum / count as f64
        }
    };
    Ok(ClassificationScores {
        accuracy: correct as f64 / total as f64,
        macro_f1: average(f1, f1_classes),
        sensitivity: average(sensitivity, sensitivity_classes),
        specificity: average(specificity, specificity_classes),
        windows: total,
        confusion,
    })
}

/// Ground-truth average error per window: for every trial, the RPE (translation part,
/// `opts.delta` frames, all pairs) against `ground_truth` after evo's association, keyed by
/// the ground truth's start stamp; then the mean over trials per key. Sorted by key.
pub fn ground_truth_errors(
    ground_truth: &Trajectory,
    trials: &[Trajectory],
    opts: &EstimateOptions,
) -> Result<Vec<(i64, f64)>, Error> {
    if trials.is_empty() {
        return Err(Error::InvalidArgument(
            "need at least one trial for the ground-truth error".into(),
        ));
    }
    // Published ground truth may repeat a stamp (TUM fr2_xyz does 8 times): association keeps
    // both poses, as evo does. Going back in time is still refused.
    ground_truth.validate_poses()?;
    if let Some(i) = ground_truth.stamps.windows(2).position(|w| w[1] < w[0]) {
        return Err(Error::InvalidTrajectory(format!(
            "ground truth: stamp {} is below stamp {i}",
            i + 1
        )));
    }
    for (i, trial) in trials.iter().enumerate() {
        trial
            .validate()
            .map_err(|e| Error::InvalidArgument(format!("trial {i}: {e}")))?;
    }
    let rpe_opts = RpeOptions {
        pose_relation: opts.pose_relation,
        delta: opts.delta as f64,
        ..RpeOptions::default()
    };
    let per_trial = trials
        .par_iter()
        .enumerate()
        .map(|(index, trial)| {
            let name = format!("trial {index}");
            let (ids_gt, ids_trial) = associate_named(
                ground_truth,
                trial,
                opts.t_max_diff_s,
                0.0,
                ("ground truth", &name),
            )?;
            let (gt, est) = (
                ground_truth.reduce_to_ids(&ids_gt),
                trial.reduce_to_ids(&ids_trial),
            );
            let result = rpe(&gt, &est, &rpe_opts)?;
            Ok(result
                .pairs
                .iter()
                .zip(result.errors)
                .map(|(&(i, _), e)| (gt.stamps[i], e))
                .collect::<Vec<_>>())
        })
        .collect::<Result<Vec<_>, Error>>()?;
    let mut all: Vec<(i64, f64)> = per_trial.into_iter().flatten().collect();
    all.sort_by_key(|&(key, _)| key);
    let mut out: Vec<(i64, f64)> = Vec::new();
    let mut start = 0;
    while start < all.len() {
        let key = all[start].0;
        let end = start + all[start..].partition_point(|&(k, _)| k == key);
        let values: Vec<f64> = all[start..end].iter().map(|&(_, e)| e).collect();
        out.push((key, crate::mean(&values)));
        start = end;
    }
    Ok(out)
}

/// Options of [`evaluate`].
#[derive(Debug, Clone, PartialEq)]
pub struct EvaluationOptions {
    /// Numbers of B trials to estimate from (the paper: 5, 10, 20, …, 100); counts larger than
    /// the set are skipped.
    pub trial_counts: Vec<usize>,
    /// Settings to evaluate (default: all seven).
    pub settings: Vec<Setting>,
    /// Classifiers (default: the paper's three).
    pub boundaries: Vec<Thresholds>,
    /// Delta, association tolerance and pose relation (the setting field is unused).
    pub estimate: EstimateOptions,
}

impl Default for EvaluationOptions {
    fn default() -> Self {
        Self {
            trial_counts: vec![5, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100],
            settings: Setting::ALL.to_vec(),
            boundaries: PAPER_CLASSIFIERS.to_vec(),
            estimate: EstimateOptions::default(),
        }
    }
}

/// One line of the evaluation table.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct EvaluationRow {
    /// The statistic.
    #[serde(serialize_with = "serialize_display")]
    pub setting: Setting,
    /// Number of B trials used.
    pub trials: usize,
    /// The classifier.
    pub boundaries: Thresholds,
    /// Its scores.
    pub scores: ClassificationScores,
}

fn serialize_display<S: serde::Serializer>(
    value: &Setting,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    serializer.collect_str(value)
}

/// The result of [`evaluate`].
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Evaluation {
    /// Ground-truth windows (from set A).
    pub ground_truth_windows: usize,
    /// One row per (trial count, setting, classifier).
    pub rows: Vec<EvaluationRow>,
}

impl Evaluation {
    /// The evaluation as JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"))
    }
}

/// The windows of one sequence scored for one setting and trial count: the true error and
/// the estimate of every estimate window matched to a ground-truth window.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MatchedWindows {
    /// The statistic.
    #[serde(serialize_with = "serialize_display")]
    pub setting: Setting,
    /// Number of B trials used.
    pub trials: usize,
    /// Start stamps (ns) of the matched ground-truth windows.
    pub starts: Vec<i64>,
    /// True error per window (mean RPE of set A against the ground truth), metres.
    pub truth: Vec<f64>,
    /// The estimate per window, metres (calibrated by [`calibrated_matched_windows`]).
    pub estimate: Vec<f64>,
    /// The calibrated interval's bounds per window (empty without a calibration).
    pub lower: Vec<f64>,
    /// See `lower`.
    pub upper: Vec<f64>,
}

impl MatchedWindows {
    fn empty(setting: Setting, trials: usize) -> Self {
        Self {
            setting,
            trials,
            starts: Vec::new(),
            truth: Vec::new(),
            estimate: Vec::new(),
            lower: Vec::new(),
            upper: Vec::new(),
        }
    }

    /// Adds every window of `estimate` whose start is within `tolerance` of a key of `truth`
    /// (sorted `(start, error)`), with the truth of the nearest.
    fn add(&mut self, estimate: &crate::Estimate, truth: &[(i64, f64)], tolerance: i64) {
        let keys: Vec<i64> = truth.iter().map(|&(k, _)| k).collect();
        for window in &estimate.windows {
            if let Some(index) = nearest(&keys, window.start, tolerance) {
                self.starts.push(truth[index].0);
                self.truth.push(truth[index].1);
                self.estimate.push(window.error_m);
                if let Some(interval) = window.interval {
                    self.lower.push(interval.lower_m);
                    self.upper.push(interval.upper_m);
                }
            }
        }
    }
}

/// The protocol's matched windows for every trial count and setting of `opts` (counts
/// outside 2..=|B| are skipped). Estimate windows are matched to the ground-truth window with
/// the nearest start stamp within `t_max_diff_s`; unmatched windows are left out.
pub fn matched_windows(
    ground_truth: &Trajectory,
    trials_a: &[Trajectory],
    trials_b: &[Trajectory],
    opts: &EvaluationOptions,
) -> Result<(usize, Vec<MatchedWindows>), Error> {
    matched_windows_with(ground_truth, trials_a, trials_b, opts, None)
}

/// [`matched_windows`] of the estimate calibrated by `calibration` (applied to the first `k`
/// trials of set B before windows are matched), with each window's interval. Settings other
/// than the calibration's, or another window or pose relation, are refused.
pub fn calibrated_matched_windows(
    ground_truth: &Trajectory,
    trials_a: &[Trajectory],
    trials_b: &[Trajectory],
    opts: &EvaluationOptions,
    calibration: &Calibration,
) -> Result<(usize, Vec<MatchedWindows>), Error> {
    for &setting in &opts.settings {
        calibration.check_estimate(setting, opts.estimate.delta, opts.estimate.pose_relation)?;
    }
    matched_windows_with(ground_truth, trials_a, trials_b, opts, Some(calibration))
}

fn matched_windows_with(
    ground_truth: &Trajectory,
    trials_a: &[Trajectory],
    trials_b: &[Trajectory],
    opts: &EvaluationOptions,
    calibration: Option<&Calibration>,
) -> Result<(usize, Vec<MatchedWindows>), Error> {
    let truth = ground_truth_errors(ground_truth, trials_a, &opts.estimate)?;
    let tolerance = seconds_to_ns(opts.estimate.t_max_diff_s);
    let mut out = Vec::new();
    for &count in &opts.trial_counts {
        if count < 2 || count > trials_b.len() {
            continue;
        }
        let values = PairwiseValues::compute(&trials_b[..count], &opts.estimate)?;
        for &setting in &opts.settings {
            let mut estimate = values.estimate(setting);
            if let Some(calibration) = calibration {
                calibration.apply(&mut estimate, &trials_b[..count], "")?;
            }
            let mut matched = MatchedWindows::empty(setting, count);
            matched.add(&estimate, &truth, tolerance);
            if matched.estimate.is_empty() {
                return Err(Error::NoPairs(
                    "no estimate window matches a ground-truth window".into(),
                ));
            }
            out.push(matched);
        }
    }
    if out.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "no trial count in {:?} is between 2 and the {} trials of set B",
            opts.trial_counts,
            trials_b.len()
        )));
    }
    Ok((truth.len(), out))
}

/// The matched windows against **each run's own error** (`sitar evaluate --truth own`): for
/// every trial count `k` of `opts` (1 ..= |B|; 1 only with a calibration), every run `r` of
/// set B in turn is the live run, with the `k − 1` runs after it (cyclically) as its
/// replays; its windows (keyed by its stamps) are estimated by `calibration` (alone when
/// `k = 1`) or, without one, by the spread between it and its replays, and matched to its own
/// RPE against the ground truth. The runs' windows are pooled per (k, setting). Returns the
/// number of ground-truth windows of the first run with the matched windows.
pub fn own_error_matched_windows(
    ground_truth: &Trajectory,
    trials_b: &[Trajectory],
    opts: &EvaluationOptions,
    calibration: Option<&Calibration>,
) -> Result<(usize, Vec<MatchedWindows>), Error> {
    let tolerance = seconds_to_ns(opts.estimate.t_max_diff_s);
    let own: Vec<Vec<(i64, f64)>> = trials_b
        .par_iter()
        .map(|run| ground_truth_errors(ground_truth, std::slice::from_ref(run), &opts.estimate))
        .collect::<Result<_, _>>()?;
    let minimum = if calibration.is_some() { 1 } else { 2 };
    let mut out = Vec::new();
    for &count in &opts.trial_counts {
        if count < minimum || count > trials_b.len() {
            continue;
        }
        for &setting in &opts.settings {
            let estimate_opts = EstimateOptions {
                setting,
                ..opts.estimate
            };
            let per_run = (0..trials_b.len())
                .into_par_iter()
                .map(|r| {
                    let replays: Vec<Trajectory> = (1..count)
                        .map(|j| trials_b[(r + j) % trials_b.len()].clone())
                        .collect();
                    let estimate = match calibration {
                        Some(c) => {
                            crate::estimate_live(c, &trials_b[r], &replays, &estimate_opts, "")?
                        }
                        None => crate::live_spread(&trials_b[r], &replays, &estimate_opts)?,
                    };
                    Ok((r, estimate))
                })
                .collect::<Result<Vec<_>, Error>>()?;
            let mut matched = MatchedWindows::empty(setting, count);
            for (r, estimate) in per_run {
                matched.add(&estimate, &own[r], tolerance);
            }
            if matched.estimate.is_empty() {
                return Err(Error::NoPairs(
                    "no window of a live run matches a window of its own error".into(),
                ));
            }
            out.push(matched);
        }
    }
    if out.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "no trial count in {:?} is between {minimum} and the {} runs of set B",
            opts.trial_counts,
            trials_b.len()
        )));
    }
    Ok((own.first().map_or(0, Vec::len), out))
}

/// Runs the paper's evaluation protocol on one sequence ([`matched_windows`], then
/// [`classification_scores`] per classifier).
pub fn evaluate(
    ground_truth: &Trajectory,
    trials_a: &[Trajectory],
    trials_b: &[Trajectory],
    opts: &EvaluationOptions,
) -> Result<Evaluation, Error> {
    let (ground_truth_windows, matched) = matched_windows(ground_truth, trials_a, trials_b, opts)?;
    let mut rows = Vec::new();
    for m in &matched {
        for &boundaries in &opts.boundaries {
            rows.push(EvaluationRow {
                setting: m.setting,
                trials: m.trials,
                boundaries,
                scores: classification_scores(&m.truth, &m.estimate, boundaries)?,
            });
        }
    }
    Ok(Evaluation {
        ground_truth_windows,
        rows,
    })
}

/// Index of the nearest key within `tolerance` (earlier on a tie).
pub(crate) fn nearest(keys: &[i64], stamp: i64, tolerance: i64) -> Option<usize> {
    let upper = keys.partition_point(|&k| k <= stamp);
    let candidates = [upper.checked_sub(1), (upper < keys.len()).then_some(upper)];
    candidates
        .into_iter()
        .flatten()
        .map(|i| (i, (keys[i] - stamp).abs()))
        .filter(|&(_, d)| d <= tolerance)
        .min_by_key(|&(i, d)| (d, i))
        .map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed_scores() {
        let b = Thresholds::DEFAULT_M;
        // truth:     low low low low medium medium high
        // predicted: low low low medium medium low high
        let truth = [0.01, 0.02, 0.03, 0.04, 0.06, 0.07, 0.2];
        let predicted = [0.01, 0.02, 0.03, 0.06, 0.08, 0.01, 0.15];
        let s = classification_scores(&truth, &predicted, b).unwrap();
        assert_eq!(s.confusion, [[3, 1, 0], [1, 1, 0], [0, 0, 1]]);
        assert!((s.accuracy - 5.0 / 7.0).abs() < 1e-15);
        // F1: low 2·3/(6+1+1) = 0.75, medium 2/(2+1+1) = 0.5, high 1.
        assert!((s.macro_f1 - (0.75 + 0.5 + 1.0) / 3.0).abs() < 1e-15);
        // Sensitivity: 3/4, 1/2, 1. Specificity: low 2/3 (tn 2, fp 1), medium 4/5, high 6/6.
        assert!((s.sensitivity - (0.75 + 0.5 + 1.0) / 3.0).abs() < 1e-15);
        assert!((s.specificity - (2.0 / 3.0 + 0.8 + 1.0) / 3.0).abs() < 1e-15);
        let perfect = classification_scores(&truth, &truth, b).unwrap();
        assert_eq!(
            (
                perfect.accuracy,
                perfect.macro_f1,
                perfect.sensitivity,
                perfect.specificity
            ),
            (1.0, 1.0, 1.0, 1.0)
        );
        assert!(classification_scores(&[], &[], b).is_err());
        // No high window in truth or prediction: high is left out of every average.
        let two_class = classification_scores(&[0.01, 0.06], &[0.01, 0.01], b).unwrap();
        assert!((two_class.specificity - (0.0 + 1.0) / 2.0).abs() < 1e-15);
        assert!((two_class.sensitivity - (1.0 + 0.0) / 2.0).abs() < 1e-15);
        assert_eq!(class_index(&b, 0.05), 1);
        assert_eq!(class_index(&b, 0.0999), 1);
        assert_eq!(class_index(&b, 0.1), 2);
    }

    #[test]
    fn nearest_key() {
        assert_eq!(nearest(&[10, 20, 30], 24, 5), Some(1));
        assert_eq!(nearest(&[10, 20, 30], 25, 5), Some(1));
        assert_eq!(nearest(&[10, 20, 30], 26, 5), Some(2));
        assert_eq!(nearest(&[10, 20, 30], 36, 5), None);
    }
}
