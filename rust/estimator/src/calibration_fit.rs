//! Fitting a [`Calibration`] on sequences with ground truth, and scoring it on sequences it
//! was not fitted on.

use nalgebra::{DMatrix, DVector};

use crate::calibration::{
    AgreementScores, CALIBRATION_FEATURES, CALIBRATION_FORMAT, CALIBRATION_VERSION,
    CalibrationModel, CalibrationScores, FEATURE_OFFSETS, FittedOn, FittedSequence, HeldOutScores,
    IntervalModel, WindowFeatures, design_row, smooth, unit_of, window_features,
};
use crate::sync::seconds_to_ns;
use crate::{
    Calibration, Error, EstimateOptions, PairwiseValues, Thresholds, Trajectory,
    classification_scores, ground_truth_errors, median_ratio, quantile, spearman,
};

/// The default stretch exponent ([`CalibrationModel::spread_match`]).
pub const DEFAULT_SPREAD_MATCH: f64 = 0.45;
/// The default number of neighbouring windows on each side averaged into a window's features.
pub const DEFAULT_SMOOTHING_WINDOWS: usize = 3;
/// True errors below this are taken as this in the logarithm (0.01 mm).
const MIN_TRUTH: f64 = 1e-5;

/// One sequence ready for fitting: per window with a true error, its smoothed features.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationSequence {
    /// Its name.
    pub name: String,
    /// Runs in set A and set B.
    pub sets: (usize, usize),
    /// The true error per window (mean RPE of set A against the ground truth).
    pub truth: Vec<f64>,
    /// The uncalibrated estimate of the same windows.
    pub raw: Vec<f64>,
    /// The smoothed features of the same windows.
    pub features: Vec<WindowFeatures>,
}

impl CalibrationSequence {
    /// The windows of one sequence: the true error from `set_a`, the estimate (with
    /// `opts.setting`) and the motion from `set_b`, features smoothed over
    /// `smoothing_windows` neighbours before the windows without a true error are left out.
    pub fn new(
        name: &str,
        ground_truth: &Trajectory,
        set_a: &[Trajectory],
        set_b: &[Trajectory],
        opts: &EstimateOptions,
        smoothing_windows: usize,
    ) -> Result<Self, Error> {
        let truth = ground_truth_errors(ground_truth, set_a, opts)?;
        let estimate = PairwiseValues::compute(set_b, opts)?.estimate(opts.setting);
        let features = smooth(&window_features(&estimate, set_b), smoothing_windows);
        let keys: Vec<i64> = truth.iter().map(|&(k, _)| k).collect();
        let tolerance = seconds_to_ns(opts.t_max_diff_s);
        let mut out = Self {
            name: name.to_owned(),
            sets: (set_a.len(), set_b.len()),
            truth: Vec::new(),
            raw: Vec::new(),
            features: Vec::new(),
        };
        for (window, f) in estimate.windows.iter().zip(features) {
            if let Some(i) = crate::evaluate::nearest(&keys, window.start, tolerance) {
                out.truth.push(truth[i].1);
                out.raw.push(window.error_m);
                out.features.push(f);
            }
        }
        if out.truth.is_empty() {
            return Err(Error::NoPairs(format!(
                "{name}: no estimate window matches a ground-truth window"
            )));
        }
        Ok(out)
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

/// Fits a calibration on `sequences` (at least one) and, with two or more, scores it by
/// leaving each sequence out in turn.
///
/// The model is the least-squares fit of ln(truth) on the features of every window of every
/// sequence, then stretched ([`CalibrationModel`]). The interval is *cross-conformal by
/// sequence*: each sequence's log residuals come from a model fitted on the other sequences,
/// so they include how much sequences differ, and the interval's bounds are the
/// (1 ∓ coverage)/2 quantiles of all of them (numpy's linear interpolation). Windows of a
/// sequence are not exchangeable (neighbours overlap), sequences are, roughly: that is why
/// the split is by sequence. With one sequence the residuals are in-sample (method
/// `in_sample`: its coverage on new sequences is not known).
pub fn fit_calibration(
    sequences: &[CalibrationSequence],
    opts: &FitOptions,
) -> Result<Calibration, Error> {
    check_options(sequences, opts)?;
    let mut calibration = fit_without_scores(sequences, opts)?;
    calibration.fitted_on.sequences = sequences
        .iter()
        .map(|s| FittedSequence {
            name: s.name.clone(),
            runs: s.sets.0 + s.sets.1,
            set_a: s.sets.0,
            set_b: s.sets.1,
            windows: s.truth.len(),
        })
        .collect();
    if sequences.len() >= 2 {
        calibration.scores = Some(leave_one_sequence_out(sequences, opts)?);
    }
    Ok(calibration)
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
        if s.truth.len() != s.features.len() || s.raw.len() != s.features.len() {
            return Err(Error::InvalidArgument(format!(
                "{}: {} true errors and {} estimates for {} windows",
                s.name,
                s.truth.len(),
                s.raw.len(),
                s.features.len()
            )));
        }
        if let Some(i) = s.truth.iter().position(|t| !t.is_finite()) {
            return Err(Error::InvalidArgument(format!(
                "{}: the true error of window {i} is not finite",
                s.name
            )));
        }
    }
    Ok(())
}

/// ln(truth), clamped below.
fn log_truth(t: f64) -> f64 {
    t.max(MIN_TRUTH).ln()
}

/// The stretched least-squares model on the windows of `sequences`.
fn fit_model(
    sequences: &[&CalibrationSequence],
    opts: &FitOptions,
) -> Result<CalibrationModel, Error> {
    let rows: Vec<([f64; 4], f64)> = sequences
        .iter()
        .flat_map(|s| {
            s.features
                .iter()
                .zip(&s.truth)
                .map(|(f, &t)| (design_row(f, &FEATURE_OFFSETS), log_truth(t)))
        })
        .filter(|(x, _)| x.iter().all(|v| v.is_finite()))
        .collect();
    if rows.len() < 8 {
        return Err(Error::InvalidArgument(format!(
            "{} windows with finite features: a calibration needs at least 8",
            rows.len()
        )));
    }
    let x = DMatrix::from_fn(rows.len(), 4, |r, c| rows[r].0[c]);
    let y = DVector::from_iterator(rows.len(), rows.iter().map(|r| r.1));
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
        kind: "log_linear".into(),
        features: CALIBRATION_FEATURES.iter().map(|s| s.to_string()).collect(),
        offsets: FEATURE_OFFSETS.to_vec(),
        smoothing_windows: opts.smoothing_windows,
        coefficients: w.iter().copied().collect(),
        spread_match: opts.spread_match,
        center,
        stretch: (truth_spread / fitted_spread).powf(opts.spread_match),
    })
}

fn log_residuals(model: &CalibrationModel, s: &CalibrationSequence) -> Vec<f64> {
    s.features
        .iter()
        .zip(&s.truth)
        .map(|(f, &t)| log_truth(t) - model.log_value(f))
        .filter(|r| r.is_finite())
        .collect()
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
fn mean_scores(all: &[AgreementScores]) -> AgreementScores {
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

/// Each sequence scored raw and calibrated by a calibration fitted on the others.
pub fn leave_one_sequence_out(
    sequences: &[CalibrationSequence],
    opts: &FitOptions,
) -> Result<CalibrationScores, Error> {
    if sequences.len() < 2 {
        return Err(Error::InvalidArgument(
            "leaving one sequence out needs at least 2 sequences".into(),
        ));
    }
    let mut held_out = Vec::new();
    for (i, held) in sequences.iter().enumerate() {
        let others: Vec<CalibrationSequence> = sequences
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, s)| s.clone())
            .collect();
        // The held-out model is fitted exactly as the final one, its interval included
        // (cross-conformal over the others when there are two or more of them).
        let calibration = fit_without_scores(&others, opts)?;
        let predicted: Vec<(f64, f64, f64)> = held
            .features
            .iter()
            .map(|f| calibration.predict(f))
            .collect();
        let value: Vec<f64> = predicted.iter().map(|p| p.0).collect();
        let lower: Vec<f64> = predicted.iter().map(|p| p.1).collect();
        let upper: Vec<f64> = predicted.iter().map(|p| p.2).collect();
        held_out.push(HeldOutScores {
            name: held.name.clone(),
            raw: agreement_scores(&held.truth, &held.raw, None, opts.thresholds)?,
            calibrated: agreement_scores(
                &held.truth,
                &value,
                Some((&lower, &upper)),
                opts.thresholds,
            )?,
        });
    }
    let raw: Vec<AgreementScores> = held_out.iter().map(|h| h.raw).collect();
    let calibrated: Vec<AgreementScores> = held_out.iter().map(|h| h.calibrated).collect();
    Ok(CalibrationScores {
        method: "leave_one_sequence_out".into(),
        thresholds: [opts.thresholds.medium, opts.thresholds.high],
        sequences: held_out,
        raw: mean_scores(&raw),
        calibrated: mean_scores(&calibrated),
    })
}

/// [`fit_calibration`] without its own leave-one-out scores (the inner fits of the scoring).
fn fit_without_scores(
    sequences: &[CalibrationSequence],
    opts: &FitOptions,
) -> Result<Calibration, Error> {
    let all: Vec<&CalibrationSequence> = sequences.iter().collect();
    let model = fit_model(&all, opts)?;
    let mut residuals = Vec::new();
    if sequences.len() >= 2 {
        for (i, held) in sequences.iter().enumerate() {
            let others: Vec<&CalibrationSequence> = all
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, s)| *s)
                .collect();
            residuals.extend(log_residuals(&fit_model(&others, opts)?, held));
        }
    } else {
        residuals = log_residuals(&model, &sequences[0]);
    }
    let count = residuals.len();
    Ok(Calibration {
        format: CALIBRATION_FORMAT.into(),
        version: CALIBRATION_VERSION,
        fitted_on: FittedOn {
            sequences: Vec::new(),
            setting: opts.estimate.setting.to_string(),
            window_frames: opts.estimate.delta,
            pose_relation: opts.estimate.pose_relation.to_string(),
            unit: unit_of(opts.estimate.pose_relation).into(),
            coverage: opts.coverage,
            t_max_diff_s: opts.estimate.t_max_diff_s,
        },
        model,
        interval: IntervalModel {
            method: if sequences.len() >= 2 {
                "cross_conformal_by_sequence"
            } else {
                "in_sample"
            }
            .into(),
            log_lower: quantile(&mut residuals, (1.0 - opts.coverage) / 2.0),
            log_upper: quantile(&mut residuals, (1.0 + opts.coverage) / 2.0),
            residuals: count,
        },
        scores: None,
    })
}
