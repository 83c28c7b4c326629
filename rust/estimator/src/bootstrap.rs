//! Confidence intervals over sequences: the percentile bootstrap of a mean.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::Error;

/// A mean with its percentile-bootstrap confidence interval.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MeanInterval {
    /// The mean of the values.
    pub mean: f64,
    /// Lower end of the interval.
    pub low: f64,
    /// Upper end of the interval.
    pub high: f64,
}

/// The mean of `values` (one per sequence) and its `level` (e.g. 0.95) percentile-bootstrap
/// interval from `resamples` resamples with replacement, deterministic from `seed`; the
/// interval's ends are the `(1 ± level)/2` quantiles of the resampled means with linear
/// interpolation (numpy's default, as `scipy.stats.bootstrap(method="percentile")`). NaN
/// values are left out.
pub fn bootstrap_mean(
    values: &[f64],
    resamples: usize,
    level: f64,
    seed: u64,
) -> Result<MeanInterval, Error> {
    let values: Vec<f64> = values.iter().copied().filter(|v| !v.is_nan()).collect();
    if values.is_empty() || resamples == 0 || !(level > 0.0 && level < 1.0) {
        return Err(Error::InvalidArgument(format!(
            "a bootstrap needs values ({} given), resamples ({resamples}) and a level in (0, 1) ({level})",
            values.len()
        )));
    }
    let n = values.len();
    let mean = values.iter().sum::<f64>() / n as f64;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut means: Vec<f64> = (0..resamples)
        .map(|_| (0..n).map(|_| values[rng.random_range(0..n)]).sum::<f64>() / n as f64)
        .collect();
    means.sort_by(f64::total_cmp);
    Ok(MeanInterval {
        mean,
        low: sorted_quantile(&means, (1.0 - level) / 2.0),
        high: sorted_quantile(&means, (1.0 + level) / 2.0),
    })
}

/// The `q`-quantile of sorted values, numpy's linear interpolation.
pub(crate) fn sorted_quantile(sorted: &[f64], q: f64) -> f64 {
    let position = q * (sorted.len() - 1) as f64;
    let below = position.floor() as usize;
    let above = (below + 1).min(sorted.len() - 1);
    let t = position - below as f64;
    sorted[below] + (sorted[above] - sorted[below]) * t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_brackets_the_mean_and_narrows_with_more_values() {
        let few = [0.7, 0.8, 0.9, 0.75];
        let many: Vec<f64> = (0..64).map(|i| few[i % 4]).collect();
        let a = bootstrap_mean(&few, 2000, 0.95, 1).unwrap();
        let b = bootstrap_mean(&many, 2000, 0.95, 1).unwrap();
        assert!((a.mean - 0.7875).abs() < 1e-12 && (b.mean - 0.7875).abs() < 1e-12);
        assert!(a.low < a.mean && a.mean < a.high, "{a:?}");
        assert!(a.low >= 0.7 && a.high <= 0.9);
        assert!(b.high - b.low < (a.high - a.low) / 2.0, "{a:?} {b:?}");
        assert_eq!(a, bootstrap_mean(&few, 2000, 0.95, 1).unwrap());
        let one = bootstrap_mean(&[0.5], 10, 0.9, 3).unwrap();
        assert_eq!((one.low, one.mean, one.high), (0.5, 0.5, 0.5));
        assert!(bootstrap_mean(&[], 10, 0.95, 1).is_err());
        assert!(bootstrap_mean(&[1.0], 10, 1.5, 1).is_err());
    }
}
