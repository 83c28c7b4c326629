//! Fitting a [`Calibration`] on sequences with ground truth: one model per target and run
//! count, each with its features chosen by leave-one-sequence-out, and scored on sequences it
//! was not fitted on.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use sitar_core::calibration::{
    AgreementScores, CALIBRATION_FORMAT, CALIBRATION_VERSION, CalibrationModel, CandidateScores,
    Feature, FittedOn, FittedSequence, HeldOutScores, IntervalModel, ModelScores, RunCount, Target,
    WindowFeatures, design_row, is_informative, smooth_features,
};

use crate::calibration::{expected_features, live_windows, unit_of};
use crate::sync::seconds_to_ns;
use crate::{
    Calibration, Error, EstimateOptions, PairwiseValues, Thresholds, Trajectory,
    classification_scores, ground_truth_errors, median_ratio, quantile, spearman,
};

/// The default stretch exponent ([`CalibrationModel::spread_match`]).
pub const DEFAULT_SPREAD_MATCH: f64 = 0.45;
/// The default number of neighbouring windows on each side averaged into a window's features.
pub const DEFAULT_SMOOTHING_WINDOWS: usize = 3;
/// Candidates whose mean held-out Spearman's ρ is within this of the best are "within noise":
/// the one with the fewest features among them is kept.
pub const SELECTION_NOISE: f64 = 0.01;
/// True errors below this are taken as this in the logarithm (0.01 mm).
const MIN_TRUTH: f64 = 1e-5;

/// The motion feature sets a model may use, simplest first.
const MOTION_SETS: [&[Feature]; 4] = [
    &[Feature::PathM, Feature::RotationDeg],
    &[Feature::PathM, Feature::RotationDeg, Feature::DisplacementM],
    &[Feature::PathM, Feature::RotationDeg, Feature::JitterMps2],
    &[
        Feature::PathM,
        Feature::RotationDeg,
        Feature::DisplacementM,
        Feature::JitterMps2,
    ],
];

/// The candidate feature sets of a model for `runs`: the motion sets, and with several runs
/// the spread alone and the spread with each motion set.
pub fn candidate_features(runs: RunCount) -> Vec<Vec<Feature>> {
    let motion = MOTION_SETS.iter().map(|m| m.to_vec());
    match runs {
        RunCount::One => motion.collect(),
        RunCount::Several => std::iter::once(vec![Feature::Spread])
            .chain(motion.clone())
            .chain(motion.map(|m| std::iter::once(Feature::Spread).chain(m).collect()))
            .collect(),
    }
}

/// Windows with a true error: what the runs show for each (smoothed) and the truth.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct WindowSet {
    /// The true error per window.
    pub truth: Vec<f64>,
    /// The uncalibrated estimate (the spread) of the same windows; NaN where there is none.
    pub raw: Vec<f64>,
    /// The smoothed features of the same windows.
    pub features: Vec<WindowFeatures>,
}

impl WindowSet {
    fn len(&self) -> usize {
        self.truth.len()
    }

    fn extend(&mut self, other: &WindowSet) {
        self.truth.extend_from_slice(&other.truth);
        self.raw.extend_from_slice(&other.raw);
        self.features.extend_from_slice(&other.features);
    }
}

/// One sequence ready for fitting.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationSequence {
    /// Its name.
    pub name: String,
    /// Runs in set A and set B.
    pub sets: (usize, usize),
    /// The expected error: per window of set B's pairwise estimate, the mean error of set A
    /// against the ground truth; the spread and the median motion of set B.
    pub expected: WindowSet,
    /// Each run of set B in turn as the live run: its own error, its own motion, and the
    /// spread between it and the others of set B (its replays).
    pub live: Vec<WindowSet>,
}

/// Pairs each window start with the truth of the nearest key within `tolerance`.
fn matched(
    starts: impl Iterator<Item = i64>,
    truth: &[(i64, f64)],
    tolerance: i64,
) -> Vec<Option<f64>> {
    let keys: Vec<i64> = truth.iter().map(|&(k, _)| k).collect();
    starts
        .map(|s| crate::evaluate::nearest(&keys, s, tolerance).map(|i| truth[i].1))
        .collect()
}

/// The windows of `raw` and `features` (smoothed over all of them) that have a truth.
fn window_set(
    truth: &[Option<f64>],
    raw: &[f64],
    features: &[WindowFeatures],
    h: usize,
) -> WindowSet {
    let smoothed = smooth_features(features, h);
    let mut out = WindowSet::default();
    for ((t, r), f) in truth.iter().zip(raw).zip(smoothed) {
        if let Some(t) = t {
            out.truth.push(*t);
            out.raw.push(*r);
            out.features.push(f);
        }
    }
    out
}

impl CalibrationSequence {
    /// The windows of one sequence (module docs), features smoothed over `smoothing_windows`
    /// neighbours before the windows without a true error are left out. Set B needs at least
    /// two runs.
    pub fn new(
        name: &str,
        ground_truth: &Trajectory,
        set_a: &[Trajectory],
        set_b: &[Trajectory],
        opts: &EstimateOptions,
        smoothing_windows: usize,
    ) -> Result<Self, Error> {
        let tolerance = seconds_to_ns(opts.t_max_diff_s);
        let truth = ground_truth_errors(ground_truth, set_a, opts)?;
        let estimate = PairwiseValues::compute(set_b, opts)?.estimate(opts.setting);
        let raw: Vec<f64> = estimate.windows.iter().map(|w| w.error_m).collect();
        let expected = window_set(
            &matched(estimate.windows.iter().map(|w| w.start), &truth, tolerance),
            &raw,
            &expected_features(&estimate, set_b),
            smoothing_windows,
        );
        if expected.truth.is_empty() {
            return Err(Error::NoPairs(format!(
                "{name}: no estimate window matches a ground-truth window"
            )));
        }
        let live = (0..set_b.len())
            .into_par_iter()
            .map(|r| {
                let replays: Vec<Trajectory> = set_b
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != r)
                    .map(|(_, t)| t.clone())
                    .collect();
                let own = ground_truth_errors(ground_truth, std::slice::from_ref(&set_b[r]), opts)?;
                let windows = live_windows(&set_b[r], &replays, opts)?;
                let raw: Vec<f64> = windows.windows.iter().map(|w| w.error_m).collect();
                Ok(window_set(
                    &matched(windows.windows.iter().map(|w| w.start), &own, tolerance),
                    &raw,
                    &windows.features,
                    smoothing_windows,
                ))
            })
            .collect::<Result<Vec<_>, Error>>()?;
        Ok(Self {
            name: name.to_owned(),
            sets: (set_a.len(), set_b.len()),
            expected,
            live,
        })
    }

    /// The windows a model of `target` learns from: the expected windows, or every live
    /// run's windows one after the other.
    pub fn windows(&self, target: Target) -> WindowSet {
        match target {
            Target::Expected => self.expected.clone(),
            Target::Live => {
                let mut all = WindowSet::default();
                for run in &self.live {
                    all.extend(run);
                }
                all
            }
        }
    }
}

/// Options of [`fit_calibration`].
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// The share of windows the interval should hold (0.8).
    pub coverage: f64,
    /// [`CalibrationModel::spread_match`] ([`DEFAULT_SPREAD_MATCH`]).
    pub spread_match: f64,
    /// [`CalibrationModel::smoothing_windows`] ([`DEFAULT_SMOOTHING_WINDOWS`]); the sequences
    /// must have been made with the same.
    pub smoothing_windows: usize,
    /// The estimate's options the sequences were made with.
    pub estimate: EstimateOptions,
    /// Class boundaries of the scores.
    pub thresholds: Thresholds,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            coverage: 0.8,
            spread_match: DEFAULT_SPREAD_MATCH,
            smoothing_windows: DEFAULT_SMOOTHING_WINDOWS,
            estimate: EstimateOptions::default(),
            thresholds: Thresholds::DEFAULT_M,
        }
    }
}

/// The models a calibration holds, in file order.
pub const MODELS: [(Target, RunCount); 3] = [
    (Target::Live, RunCount::One),
    (Target::Live, RunCount::Several),
    (Target::Expected, RunCount::Several),
];

/// Fits a calibration on `sequences` (at least one): for each model of [`MODELS`], every
/// candidate feature set ([`candidate_features`]) is scored by leaving each sequence out in
/// turn (with two or more sequences), and the one with the fewest features whose mean
/// held-out Spearman's ρ is within [`SELECTION_NOISE`] of the best is kept; with one
/// sequence the richest candidate is kept and judged in sample.
///
/// A model is the least-squares fit of ln(truth) on the log features of every window of
/// every sequence, then stretched ([`CalibrationModel`]). Its interval is *cross-conformal by
/// sequence*: each sequence's log residuals come from a model fitted on the other sequences,
/// so they include how much sequences differ, and the bounds are the (1 ∓ coverage)/2
/// quantiles of all of them (numpy's linear interpolation). Windows of a sequence are not
/// exchangeable (neighbours overlap), sequences are, roughly: that is why the split is by
/// sequence. With one sequence the residuals are in-sample (method `in_sample`).
pub fn fit_calibration(
    sequences: &[CalibrationSequence],
    opts: &FitOptions,
) -> Result<Calibration, Error> {
    check_options(sequences, opts)?;
    let models = MODELS
        .par_iter()
        .map(|&(target, runs)| fit_chosen_model(sequences, target, runs, opts))
        .collect::<Result<Vec<_>, Error>>()?;
    Ok(Calibration {
        format: CALIBRATION_FORMAT.into(),
        version: CALIBRATION_VERSION,
        fitted_on: fitted_on(sequences, opts),
        informative: models.iter().all(|m| m.informative),
        models,
    })
}

fn fitted_on(sequences: &[CalibrationSequence], opts: &FitOptions) -> FittedOn {
    FittedOn {
        sequences: sequences
            .iter()
            .map(|s| FittedSequence {
                name: s.name.clone(),
                runs: s.sets.0 + s.sets.1,
                set_a: s.sets.0,
                set_b: s.sets.1,
                windows: s.expected.len(),
            })
            .collect(),
        setting: opts.estimate.setting.to_string(),
        window_frames: opts.estimate.delta,
        pose_relation: opts.estimate.pose_relation.to_string(),
        unit: unit_of(opts.estimate.pose_relation).into(),
        coverage: opts.coverage,
        t_max_diff_s: opts.estimate.t_max_diff_s,
    }
}

fn check_options(sequences: &[CalibrationSequence], opts: &FitOptions) -> Result<(), Error> {
    if sequences.is_empty() {
        return Err(Error::InvalidArgument(
            "a calibration needs at least one sequence with ground truth".into(),
        ));
    }
    if !(opts.coverage > 0.0 && opts.coverage < 1.0) {
        return Err(Error::InvalidArgument(format!(
            "coverage {} is not between 0 and 1",
            opts.coverage
        )));
    }
    if !(opts.spread_match.is_finite() && (0.0..=1.0).contains(&opts.spread_match)) {
        return Err(Error::InvalidArgument(format!(
            "spread match {} is not between 0 and 1",
            opts.spread_match
        )));
    }
    for s in sequences {
        for (what, set) in
            std::iter::once(("expected", &s.expected)).chain(s.live.iter().map(|l| ("live", l)))
        {
            if set.truth.len() != set.features.len() || set.raw.len() != set.features.len() {
                return Err(Error::InvalidArgument(format!(
                    "{} ({what}): {} true errors and {} estimates for {} windows",
                    s.name,
                    set.truth.len(),
                    set.raw.len(),
                    set.features.len()
                )));
            }
            if let Some(i) = set.truth.iter().position(|t| !t.is_finite()) {
                return Err(Error::InvalidArgument(format!(
                    "{} ({what}): the true error of window {i} is not finite",
                    s.name
                )));
            }
        }
    }
    Ok(())
}

/// ln(truth), clamped below.
fn log_truth(t: f64) -> f64 {
    t.max(MIN_TRUTH).ln()
}

/// The model of `target` and `runs`, its features chosen among the candidates.
fn fit_chosen_model(
    sequences: &[CalibrationSequence],
    target: Target,
    runs: RunCount,
    opts: &FitOptions,
) -> Result<CalibrationModel, Error> {
    let sets: Vec<(String, WindowSet)> = sequences
        .iter()
        .map(|s| (s.name.clone(), s.windows(target)))
        .collect();
    let candidates = candidate_features(runs);
    if sets.len() < 2 {
        let features = candidates.last().cloned().unwrap_or_default();
        let mut model = fit_without_scores(&sets, &features, target, runs, opts)?;
        let mut scores = held_out_scores(&model, &sets[0].1, opts.thresholds)?;
        if runs == RunCount::One {
            scores.raw = None;
        }
        model.informative = is_informative(scores.calibrated.spearman);
        model.scores = Some(ModelScores {
            method: "in_sample".into(),
            truth: truth_name(target).into(),
            thresholds: [opts.thresholds.medium, opts.thresholds.high],
            raw: scores.raw,
            calibrated: scores.calibrated,
            sequences: vec![HeldOutScores {
                name: sets[0].0.clone(),
                ..scores
            }],
            candidates: Vec::new(),
        });
        return Ok(model);
    }
    let scored = candidates
        .par_iter()
        .map(|features| leave_one_sequence_out(&sets, features, target, runs, opts))
        .collect::<Result<Vec<_>, Error>>()?;
    let chosen = choose(
        &scored
            .iter()
            .map(|s| (s.0.len(), s.1.calibrated.spearman))
            .collect::<Vec<_>>(),
    );
    let mut model = fit_without_scores(&sets, &scored[chosen].0, target, runs, opts)?;
    let (_, mut scores) = scored[chosen].clone();
    model.informative = is_informative(scores.calibrated.spearman);
    scores.candidates = scored
        .iter()
        .enumerate()
        .map(|(i, (features, s))| CandidateScores {
            features: features.clone(),
            scores: s.calibrated,
            chosen: i == chosen,
        })
        .collect();
    model.scores = Some(scores);
    Ok(model)
}

/// `own` for a live run's error, `expected` otherwise.
fn truth_name(target: Target) -> &'static str {
    match target {
        Target::Live => "own",
        Target::Expected => "expected",
    }
}

/// The index of the candidate kept among `(features, mean ρ)`: the fewest features among those
/// within [`SELECTION_NOISE`] of the best ρ, the higher ρ on a tie. NaN scores never win.
pub fn choose(candidates: &[(usize, f64)]) -> usize {
    let best = candidates
        .iter()
        .map(|c| c.1)
        .filter(|r| r.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    (0..candidates.len())
        .filter(|&i| !best.is_finite() || candidates[i].1 >= best - SELECTION_NOISE)
        .min_by(|&a, &b| {
            let (fa, ra) = candidates[a];
            let (fb, rb) = candidates[b];
            fa.cmp(&fb).then(rb.total_cmp(&ra))
        })
        .unwrap_or(0)
}

/// Rows of ln features and ln truth over `sets`, non-finite rows left out.
fn rows<'a>(
    sets: impl Iterator<Item = &'a WindowSet>,
    features: &[Feature],
) -> (Vec<Vec<f64>>, Vec<f64>) {
    let offsets: Vec<f64> = features.iter().map(|f| f.offset()).collect();
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for set in sets {
        for (f, &t) in set.features.iter().zip(&set.truth) {
            let row = design_row(features, &offsets, f);
            if row.iter().all(|v| v.is_finite()) && !features_missing(features, f) {
                x.push(row);
                y.push(log_truth(t));
            }
        }
    }
    (x, y)
}

/// Whether a feature the model reads is NaN (no spread from one run).
fn features_missing(features: &[Feature], f: &WindowFeatures) -> bool {
    features.iter().any(|&feature| f.get(feature).is_nan())
}

/// The stretched least-squares model of `features` on `sets` (its interval left empty).
fn fit_model<'a>(
    sets: impl Iterator<Item = &'a WindowSet>,
    features: &[Feature],
    target: Target,
    runs: RunCount,
    opts: &FitOptions,
) -> Result<CalibrationModel, Error> {
    let (rows, y) = rows(sets, features);
    let p = features.len() + 1;
    if rows.len() < 2 * p + 4 {
        return Err(Error::InvalidArgument(format!(
            "{} windows with finite features: a model of {} features needs at least {}",
            rows.len(),
            features.len(),
            2 * p + 4
        )));
    }
    let x = DMatrix::from_fn(rows.len(), p, |r, c| rows[r][c]);
    let y = DVector::from_vec(y);
    let w = x
        .clone()
        .svd(true, true)
        .solve(&y, 1e-12)
        .map_err(|e| Error::InvalidArgument(format!("least squares failed: {e}")))?;
    let fitted = &x * &w;
    let center = fitted.mean();
    let spread = |v: &DVector<f64>| {
        let m = v.mean();
        (v.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / v.len() as f64).sqrt()
    };
    let (truth_spread, fitted_spread) = (spread(&y), spread(&fitted));
    // NaN (a non-finite feature) fails too.
    if fitted_spread.is_nan() || fitted_spread <= 0.0 {
        return Err(Error::InvalidArgument(
            "the features do not vary: nothing to fit".into(),
        ));
    }
    Ok(CalibrationModel {
        target,
        runs,
        kind: "log_linear".into(),
        features: features.to_vec(),
        offsets: features.iter().map(|f| f.offset()).collect(),
        smoothing_windows: opts.smoothing_windows,
        coefficients: w.iter().copied().collect(),
        spread_match: opts.spread_match,
        center,
        stretch: (truth_spread / fitted_spread).powf(opts.spread_match),
        interval: IntervalModel {
            method: String::new(),
            log_lower: 0.0,
            log_upper: 0.0,
            residuals: 0,
        },
        informative: true,
        scores: None,
    })
}

fn log_residuals(model: &CalibrationModel, set: &WindowSet) -> Vec<f64> {
    set.features
        .iter()
        .zip(&set.truth)
        .filter(|(f, _)| !features_missing(&model.features, f))
        .map(|(f, &t)| log_truth(t) - model.log_value(f))
        .filter(|r| r.is_finite())
        .collect()
}

/// The model on all of `sets` with its cross-conformal interval (in sample with one set).
fn fit_without_scores(
    sets: &[(String, WindowSet)],
    features: &[Feature],
    target: Target,
    runs: RunCount,
    opts: &FitOptions,
) -> Result<CalibrationModel, Error> {
    let mut model = fit_model(sets.iter().map(|s| &s.1), features, target, runs, opts)?;
    let mut residuals = Vec::new();
    if sets.len() >= 2 {
        for (i, held) in sets.iter().enumerate() {
            let others = sets
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, s)| &s.1);
            residuals.extend(log_residuals(
                &fit_model(others, features, target, runs, opts)?,
                &held.1,
            ));
        }
    } else {
        residuals = log_residuals(&model, &sets[0].1);
    }
    let count = residuals.len();
    model.interval = IntervalModel {
        method: if sets.len() >= 2 {
            "cross_conformal_by_sequence"
        } else {
            "in_sample"
        }
        .into(),
        log_lower: quantile(&mut residuals, (1.0 - opts.coverage) / 2.0),
        log_upper: quantile(&mut residuals, (1.0 + opts.coverage) / 2.0),
        residuals: count,
    };
    Ok(model)
}

/// How `model` and the raw spread score on `set`.
fn held_out_scores(
    model: &CalibrationModel,
    set: &WindowSet,
    thresholds: Thresholds,
) -> Result<HeldOutScores, Error> {
    let (mut truth, mut value, mut lower, mut upper) = (vec![], vec![], vec![], vec![]);
    for (f, &t) in set.features.iter().zip(&set.truth) {
        if features_missing(&model.features, f) {
            continue;
        }
        let p = model.predict(f);
        truth.push(t);
        value.push(p.value);
        lower.push(p.lower);
        upper.push(p.upper);
    }
    let with_raw: (Vec<f64>, Vec<f64>) = set
        .truth
        .iter()
        .zip(&set.raw)
        .filter(|(_, r)| r.is_finite())
        .map(|(t, r)| (*t, *r))
        .unzip();
    Ok(HeldOutScores {
        name: String::new(),
        raw: if with_raw.0.is_empty() {
            None
        } else {
            Some(agreement_scores(
                &with_raw.0,
                &with_raw.1,
                None,
                thresholds,
            )?)
        },
        calibrated: agreement_scores(&truth, &value, Some((&lower, &upper)), thresholds)?,
    })
}

/// The share of the truly high windows (`truth ≥ thresholds.high`) whose `values` are low
/// (`< thresholds.medium`): the failure the product exists to prevent. NaN without high ones.
pub fn high_called_low(truth: &[f64], values: &[f64], thresholds: Thresholds) -> f64 {
    let high: Vec<usize> = (0..truth.len())
        .filter(|&i| truth[i] >= thresholds.high)
        .collect();
    if high.is_empty() {
        return f64::NAN;
    }
    let low = high
        .iter()
        .filter(|&&i| values[i] < thresholds.medium)
        .count();
    low as f64 / high.len() as f64
}

/// How `estimate` agrees with `truth`; `interval` gives coverage.
pub fn agreement_scores(
    truth: &[f64],
    estimate: &[f64],
    interval: Option<(&[f64], &[f64])>,
    thresholds: Thresholds,
) -> Result<AgreementScores, Error> {
    let classes = classification_scores(truth, estimate, thresholds)?;
    Ok(AgreementScores {
        accuracy: classes.accuracy,
        macro_f1: classes.macro_f1,
        spearman: spearman(truth, estimate)?,
        median_ratio: median_ratio(truth, estimate)?,
        high_called_low: high_called_low(truth, estimate, thresholds),
        high_upper_low: interval.map(|(_, upper)| high_called_low(truth, upper, thresholds)),
        coverage: interval.map(|(lower, upper)| {
            let held = (0..truth.len())
                .filter(|&i| lower[i] <= truth[i] && truth[i] <= upper[i])
                .count();
            held as f64 / truth.len() as f64
        }),
    })
}

/// The mean of each score over sequences.
pub fn mean_scores(all: &[AgreementScores]) -> AgreementScores {
    let mean = |f: &dyn Fn(&AgreementScores) -> f64| {
        let values: Vec<f64> = all.iter().map(f).filter(|v| v.is_finite()).collect();
        crate::mean(&values)
    };
    AgreementScores {
        accuracy: mean(&|s| s.accuracy),
        macro_f1: mean(&|s| s.macro_f1),
        spearman: mean(&|s| s.spearman),
        median_ratio: mean(&|s| s.median_ratio),
        high_called_low: mean(&|s| s.high_called_low),
        coverage: all
            .iter()
            .all(|s| s.coverage.is_some())
            .then(|| mean(&|s| s.coverage.unwrap_or(f64::NAN))),
        high_upper_low: all
            .iter()
            .all(|s| s.high_upper_low.is_some())
            .then(|| mean(&|s| s.high_upper_low.unwrap_or(f64::NAN))),
    }
}

/// Each set scored by the model of `features` fitted (interval included) on the others.
fn leave_one_sequence_out(
    sets: &[(String, WindowSet)],
    features: &[Feature],
    target: Target,
    runs: RunCount,
    opts: &FitOptions,
) -> Result<(Vec<Feature>, ModelScores), Error> {
    let mut held_out = Vec::new();
    for (i, (name, held)) in sets.iter().enumerate() {
        let others: Vec<(String, WindowSet)> = sets
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, s)| s.clone())
            .collect();
        let model = fit_without_scores(&others, features, target, runs, opts)?;
        held_out.push(HeldOutScores {
            name: name.clone(),
            ..held_out_scores(&model, held, opts.thresholds)?
        });
    }
    if runs == RunCount::One {
        // One run has no spread to compare with.
        held_out.iter_mut().for_each(|h| h.raw = None);
    }
    let raw: Vec<AgreementScores> = held_out.iter().filter_map(|h| h.raw).collect();
    let calibrated: Vec<AgreementScores> = held_out.iter().map(|h| h.calibrated).collect();
    Ok((
        features.to_vec(),
        ModelScores {
            method: "leave_one_sequence_out".into(),
            truth: truth_name(target).into(),
            thresholds: [opts.thresholds.medium, opts.thresholds.high],
            raw: (!raw.is_empty() && raw.len() == held_out.len()).then(|| mean_scores(&raw)),
            calibrated: mean_scores(&calibrated),
            sequences: held_out,
            candidates: Vec::new(),
        },
    ))
}

/// The model of `target` and `runs` with the given `features` on all of `sequences`, its
/// interval cross-conformal by sequence (in sample with one), without scores: what
/// [`fit_calibration`] keeps once it has chosen the features.
pub fn fit_features(
    sequences: &[CalibrationSequence],
    features: &[Feature],
    target: Target,
    runs: RunCount,
    opts: &FitOptions,
) -> Result<CalibrationModel, Error> {
    check_options(sequences, opts)?;
    let sets: Vec<(String, WindowSet)> = sequences
        .iter()
        .map(|s| (s.name.clone(), s.windows(target)))
        .collect();
    fit_without_scores(&sets, features, target, runs, opts)
}

/// The leave-one-sequence-out scores of one model of `target` and `runs` with `features`
/// (what [`fit_calibration`] computes for every candidate).
pub fn score_features(
    sequences: &[CalibrationSequence],
    features: &[Feature],
    target: Target,
    runs: RunCount,
    opts: &FitOptions,
) -> Result<ModelScores, Error> {
    check_options(sequences, opts)?;
    let sets: Vec<(String, WindowSet)> = sequences
        .iter()
        .map(|s| (s.name.clone(), s.windows(target)))
        .collect();
    if sets.len() < 2 {
        return Err(Error::InvalidArgument(
            "leaving one sequence out needs at least 2 sequences".into(),
        ));
    }
    Ok(leave_one_sequence_out(&sets, features, target, runs, opts)?.1)
}
