//! How well an estimate follows the truth beyond class agreement: the estimate/truth ratio,
//! rank correlation, a fitted scale factor, and ROC / precision–recall curves of the
//! estimate as a detector of windows at or above a true-error boundary.
//!
//! Each function equals its scipy or scikit-learn counterpart (`scipy.stats.spearmanr`,
//! `sklearn.metrics.roc_curve`, `roc_auc_score`, `precision_recall_curve`,
//! `average_precision_score`) on the golden cases of `sitar-cli`'s tests.

use crate::Error;

fn check(truth: &[f64], estimate: &[f64]) -> Result<(), Error> {
    if truth.len() != estimate.len() || truth.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "need equally many, non-zero true and estimated errors (got {} and {})",
            truth.len(),
            estimate.len()
        )));
    }
    if let Some(i) = truth.iter().chain(estimate).position(|v| !v.is_finite()) {
        return Err(Error::InvalidArgument(format!(
            "value {i} of the true and estimated errors is not finite"
        )));
    }
    Ok(())
}

/// Median of `estimate / truth` over windows with a positive true error (the median of an
/// even count is the mean of the middle two, as numpy's).
pub fn median_ratio(truth: &[f64], estimate: &[f64]) -> Result<f64, Error> {
    check(truth, estimate)?;
    let mut ratios: Vec<f64> = truth
        .iter()
        .zip(estimate)
        .filter(|(t, _)| **t > 0.0)
        .map(|(t, e)| e / t)
        .collect();
    if ratios.is_empty() {
        return Err(Error::InvalidArgument(
            "no window has a positive true error".into(),
        ));
    }
    ratios.sort_by(f64::total_cmp);
    Ok(crate::bootstrap::sorted_quantile(&ratios, 0.5))
}

/// Ranks from 1, ties sharing their average rank (scipy's `rankdata(method="average")`).
fn ranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut ranks = vec![0.0; values.len()];
    let mut start = 0;
    while start < order.len() {
        let mut end = start + 1;
        while end < order.len() && values[order[end]] == values[order[start]] {
            end += 1;
        }
        // Positions start..end (0-based) share the mean of ranks start+1 ..= end.
        let rank = (start + end + 1) as f64 / 2.0;
        for &i in &order[start..end] {
            ranks[i] = rank;
        }
        start = end;
    }
    ranks
}

/// Spearman's rank correlation (Pearson's r of the average ranks, as `scipy.stats.spearmanr`);
/// NaN when either side is constant.
pub fn spearman(truth: &[f64], estimate: &[f64]) -> Result<f64, Error> {
    check(truth, estimate)?;
    let (a, b) = (ranks(truth), ranks(estimate));
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut cov, mut va, mut vb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(&b) {
        cov += (x - ma) * (y - mb);
        va += (x - ma) * (x - ma);
        vb += (y - mb) * (y - mb);
    }
    Ok(cov / (va * vb).sqrt())
}

/// Errors below this (metres) are rounding noise — trials that coast identically give pair
/// errors of 0 or 1e-17 depending on the arithmetic — and are left out of [`fit_scale`].
pub const MIN_FIT_ERROR_M: f64 = 1e-6;

/// The one scale factor `c` that best turns estimates into true errors in log space:
/// `exp(mean(ln truth − ln estimate))` over windows where both are at least
/// [`MIN_FIT_ERROR_M`].
pub fn fit_scale(truth: &[f64], estimate: &[f64]) -> Result<f64, Error> {
    check(truth, estimate)?;
    let logs: Vec<f64> = truth
        .iter()
        .zip(estimate)
        .filter(|(t, e)| **t >= MIN_FIT_ERROR_M && **e >= MIN_FIT_ERROR_M)
        .map(|(t, e)| t.ln() - e.ln())
        .collect();
    if logs.is_empty() {
        return Err(Error::InvalidArgument(
            "no window has true and estimated errors of at least a micrometre".into(),
        ));
    }
    Ok((logs.iter().sum::<f64>() / logs.len() as f64).exp())
}

/// One point of a threshold sweep: windows with an estimate ≥ `threshold_m` are called
/// positive (at or above the true-error boundary).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SweepPoint {
    /// The estimate threshold (metres).
    pub threshold_m: f64,
    /// True-positive rate (recall).
    pub tpr: f64,
    /// False-positive rate.
    pub fpr: f64,
    /// Precision (1 when nothing is called positive, as scikit-learn).
    pub precision: f64,
}

/// The estimate as a detector of windows whose true error is at least `boundary_m`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ThresholdSweep {
    /// The true-error boundary (metres).
    pub boundary_m: f64,
    /// Windows at or above it in truth.
    pub positives: usize,
    /// Windows below it.
    pub negatives: usize,
    /// Area under the ROC curve (`roc_auc_score`); NaN without positives or negatives.
    pub roc_auc: f64,
    /// Average precision (`average_precision_score`); NaN without positives.
    pub average_precision: f64,
    /// The threshold with the highest F1 among the sweep's points, and that F1.
    pub best_f1_threshold_m: f64,
    /// That F1.
    pub best_f1: f64,
    /// One point per distinct estimate, highest threshold first (as `roc_curve` with
    /// `drop_intermediate=False`, without its leading infinite threshold).
    pub points: Vec<SweepPoint>,
}

/// Sweeps the estimate threshold over every distinct estimate for the true boundary
/// `boundary_m`.
pub fn threshold_sweep(
    truth: &[f64],
    estimate: &[f64],
    boundary_m: f64,
) -> Result<ThresholdSweep, Error> {
    check(truth, estimate)?;
    let positive: Vec<bool> = truth.iter().map(|&t| t >= boundary_m).collect();
    let positives = positive.iter().filter(|&&p| p).count();
    let negatives = positive.len() - positives;
    let mut order: Vec<usize> = (0..estimate.len()).collect();
    order.sort_by(|&a, &b| estimate[b].total_cmp(&estimate[a]));
    let (mut tp, mut fp) = (0usize, 0usize);
    let mut points = Vec::new();
    let (mut auc, mut ap) = (0.0, 0.0);
    let (mut last_tpr, mut last_fpr, mut last_recall) = (0.0, 0.0, 0.0);
    let (mut best_f1, mut best_threshold) = (f64::NAN, f64::NAN);
    let mut i = 0;
    while i < order.len() {
        let threshold = estimate[order[i]];
        while i < order.len() && estimate[order[i]] == threshold {
            if positive[order[i]] {
                tp += 1;
            } else {
                fp += 1;
            }
            i += 1;
        }
        let tpr = if positives > 0 {
            tp as f64 / positives as f64
        } else {
            f64::NAN
        };
        let fpr = if negatives > 0 {
            fp as f64 / negatives as f64
        } else {
            f64::NAN
        };
        let precision = tp as f64 / (tp + fp) as f64;
        // Trapezoids under the ROC curve; rectangles of precision over recall steps.
        auc += (fpr - last_fpr) * (tpr + last_tpr) / 2.0;
        ap += (tpr - last_recall) * precision;
        let f1 = if tp > 0 {
            2.0 * tp as f64 / (2 * tp + fp + (positives - tp)) as f64
        } else {
            0.0
        };
        if best_f1.is_nan() || f1 > best_f1 {
            best_f1 = f1;
            best_threshold = threshold;
        }
        (last_tpr, last_fpr, last_recall) = (tpr, fpr, tpr);
        points.push(SweepPoint {
            threshold_m: threshold,
            tpr,
            fpr,
            precision,
        });
    }
    let roc_auc = if positives > 0 && negatives > 0 {
        auc
    } else {
        f64::NAN
    };
    Ok(ThresholdSweep {
        boundary_m,
        positives,
        negatives,
        roc_auc,
        average_precision: if positives > 0 { ap } else { f64::NAN },
        best_f1_threshold_m: best_threshold,
        best_f1,
        points,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed_cases() {
        // Ties share ranks: [1, 2.5, 2.5, 4].
        assert_eq!(ranks(&[0.1, 0.3, 0.3, 0.9]), [1.0, 2.5, 2.5, 4.0]);
        let r = spearman(&[1.0, 2.0, 3.0, 4.0], &[10.0, 20.0, 30.0, 40.0]).unwrap();
        assert!((r - 1.0).abs() < 1e-15);
        let r = spearman(&[1.0, 2.0, 3.0, 4.0], &[4.0, 3.0, 2.0, 1.0]).unwrap();
        assert!((r + 1.0).abs() < 1e-15);
        assert!(spearman(&[1.0, 2.0], &[3.0, 3.0]).unwrap().is_nan());
        assert_eq!(
            median_ratio(&[0.1, 0.2, 0.0], &[0.2, 0.2, 5.0]).unwrap(),
            1.5
        );
        assert!((fit_scale(&[0.2, 0.8], &[0.1, 0.4]).unwrap() - 2.0).abs() < 1e-12);
        assert!(median_ratio(&[], &[]).is_err());
        assert!(spearman(&[f64::NAN], &[1.0]).is_err());
        // A perfect detector: AUC 1, AP 1; a useless one: AUC 0.5.
        let s = threshold_sweep(&[0.01, 0.02, 0.2, 0.3], &[0.1, 0.2, 0.3, 0.4], 0.1).unwrap();
        assert_eq!((s.positives, s.negatives), (2, 2));
        assert_eq!((s.roc_auc, s.average_precision), (1.0, 1.0));
        assert_eq!((s.best_f1, s.best_f1_threshold_m), (1.0, 0.3));
        let s = threshold_sweep(&[0.01, 0.2, 0.01, 0.2], &[0.5, 0.5, 0.1, 0.1], 0.1).unwrap();
        assert_eq!(s.roc_auc, 0.5);
        assert_eq!(s.points.len(), 2);
    }
}
