//! The statistics behind evo_res's distribution figures, as seaborn and matplotlib compute
//! them: numpy's percentile, the Freedman–Diaconis histogram bins of seaborn's `distplot`
//! (at most 50) with density heights, the Gaussian kernel density estimate with Scott's
//! bandwidth (scipy's `gaussian_kde`), and matplotlib's box statistics (whiskers at the
//! furthest values within 1.5 IQR of the quartiles). A leaf module.

/// numpy's default percentile (linear interpolation between closest ranks); NaN values are
/// left out; NaN for no values.
pub fn percentile(values: &[f64], p: f64) -> f64 {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| !v.is_nan()).collect();
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted.sort_by(f64::total_cmp);
    let rank = p / 100.0 * (sorted.len() - 1) as f64;
    let (k, f) = (rank.floor() as usize, rank - rank.floor());
    let next = sorted[(k + 1).min(sorted.len() - 1)];
    sorted[k] + f * (next - sorted[k])
}

/// The finite values of `values`.
fn finite(values: &[f64]) -> Vec<f64> {
    values.iter().copied().filter(|v| v.is_finite()).collect()
}

/// seaborn's `distplot` bin count: Freedman–Diaconis (`2 IQR / n^(1/3)` wide; `√n` bins
/// when the IQR is 0), at most 50, at least 1.
pub fn histogram_bins(values: &[f64]) -> usize {
    let values = finite(values);
    let n = values.len();
    if n < 2 {
        return 1;
    }
    let iqr = percentile(&values, 75.0) - percentile(&values, 25.0);
    let width = 2.0 * iqr / (n as f64).cbrt();
    let (low, high) = min_max(&values);
    let bins = if width == 0.0 {
        (n as f64).sqrt() as usize
    } else {
        ((high - low) / width).ceil() as usize
    };
    bins.clamp(1, 50)
}

/// numpy's `histogram(values, bins, density=True)`: `(left, right, density)` per bin over
/// the values' range (the last bin closed), densities integrating to 1.
pub fn histogram(values: &[f64], bins: usize) -> Vec<(f64, f64, f64)> {
    let values = finite(values);
    if values.is_empty() || bins == 0 {
        return Vec::new();
    }
    let (mut low, mut high) = min_max(&values);
    if low == high {
        (low, high) = (low - 0.5, high + 0.5);
    }
    let width = (high - low) / bins as f64;
    let mut counts = vec![0usize; bins];
    for v in &values {
        let k = (((v - low) / width) as usize).min(bins - 1);
        counts[k] += 1;
    }
    let scale = 1.0 / (values.len() as f64 * width);
    counts
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            let left = low + width * k as f64;
            (left, left + width, c as f64 * scale)
        })
        .collect()
}

/// Scott's bandwidth of scipy's `gaussian_kde`: `n^(-1/5)` times the sample standard
/// deviation (ddof 1); `None` for fewer than two values or no spread.
pub fn kde_bandwidth(values: &[f64]) -> Option<f64> {
    let values = finite(values);
    let n = values.len();
    if n < 2 {
        return None;
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let bandwidth = var.sqrt() * (n as f64).powf(-0.2);
    (bandwidth > 0.0).then_some(bandwidth)
}

/// The Gaussian kernel density estimate of `values` (bandwidth [`kde_bandwidth`]) at each
/// of `at`; empty when there is no bandwidth.
pub fn kde(values: &[f64], at: &[f64]) -> Vec<f64> {
    let Some(h) = kde_bandwidth(values) else {
        return Vec::new();
    };
    let values = finite(values);
    let norm = 1.0 / (values.len() as f64 * h * (2.0 * std::f64::consts::PI).sqrt());
    at.iter()
        .map(|x| {
            values
                .iter()
                .map(|v| (-0.5 * ((x - v) / h).powi(2)).exp())
                .sum::<f64>()
                * norm
        })
        .collect()
}

/// matplotlib's box statistics.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxStats {
    /// The first quartile.
    pub q1: f64,
    /// The median.
    pub median: f64,
    /// The third quartile.
    pub q3: f64,
    /// The smallest value within 1.5 IQR below `q1`.
    pub low: f64,
    /// The largest value within 1.5 IQR above `q3`.
    pub high: f64,
    /// The values beyond the whiskers.
    pub outliers: Vec<f64>,
}

/// The box statistics of the finite `values`; `None` for none.
pub fn box_stats(values: &[f64]) -> Option<BoxStats> {
    let values = finite(values);
    if values.is_empty() {
        return None;
    }
    let (q1, median, q3) = (
        percentile(&values, 25.0),
        percentile(&values, 50.0),
        percentile(&values, 75.0),
    );
    let reach = 1.5 * (q3 - q1);
    let inside = |v: &&f64| **v >= q1 - reach && **v <= q3 + reach;
    let (low, high) = min_max(&values.iter().filter(inside).copied().collect::<Vec<_>>());
    Some(BoxStats {
        q1,
        median,
        q3,
        low: low.min(q1),
        high: high.max(q3),
        outliers: values.iter().filter(|v| !inside(v)).copied().collect(),
    })
}

/// The smallest and largest of `values` (∞, −∞ for none).
pub fn min_max(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentile_is_numpys() {
        // numpy.percentile([1, 2, 3, 4], [25, 50, 90]) = [1.75, 2.5, 3.7]
        let v = [4.0, 1.0, 3.0, 2.0];
        assert_eq!(percentile(&v, 25.0), 1.75);
        assert_eq!(percentile(&v, 50.0), 2.5);
        assert!((percentile(&v, 90.0) - 3.7).abs() < 1e-12);
        assert!(percentile(&[], 50.0).is_nan());
    }

    #[test]
    fn bins_are_seaborns() {
        // seaborn._freedman_diaconis_bins(range(100)) = 5 (IQR 49.5, width 21.33…)
        let v: Vec<f64> = (0..100).map(f64::from).collect();
        assert_eq!(histogram_bins(&v), 5);
        assert_eq!(histogram_bins(&[1.0, 1.0, 1.0, 1.0]), 2);
        assert_eq!(histogram_bins(&[3.0]), 1);
        let mut wide: Vec<f64> = (0..1000).map(f64::from).collect();
        wide.push(1e9);
        assert_eq!(histogram_bins(&wide), 50, "capped");
    }

    #[test]
    fn histogram_densities_integrate_to_one() {
        let v = [0.0, 0.5, 1.0, 1.0, 2.0];
        let h = histogram(&v, 4);
        assert_eq!(h.len(), 4);
        assert_eq!((h[0].0, h[3].1), (0.0, 2.0));
        // numpy.histogram([0, .5, 1, 1, 2], 4, density=True): 0.4, 0.4, 0.8, 0.4 (the
        // last bin closed)
        assert_eq!(
            h.iter().map(|b| b.2).collect::<Vec<_>>(),
            [0.4, 0.4, 0.8, 0.4]
        );
        let area: f64 = h.iter().map(|(l, r, d)| (r - l) * d).sum();
        assert!((area - 1.0).abs() < 1e-12);
    }

    #[test]
    fn kde_is_scipys() {
        // scipy.stats.gaussian_kde([0, 1, 2, 4]): factor 4^-0.2, std 1.707825127659933,
        // density 0.19665499 at 1.0
        let v = [0.0, 1.0, 2.0, 4.0];
        let h = kde_bandwidth(&v).unwrap();
        assert!((h - 1.707_825_127_659_933 * 4f64.powf(-0.2)).abs() < 1e-12);
        assert!((kde(&v, &[1.0])[0] - 0.196_654_99).abs() < 1e-8);
        let grid: Vec<f64> = (0..4001).map(|k| -10.0 + k as f64 * 0.006).collect();
        let density = kde(&v, &grid);
        let area: f64 = density.iter().sum::<f64>() * 0.006;
        assert!((area - 1.0).abs() < 1e-6, "{area}");
        assert!(kde(&[1.0, 1.0], &[1.0]).is_empty());
    }

    #[test]
    fn box_whiskers_stop_at_the_last_value_within_reach() {
        let mut v: Vec<f64> = (1..=9).map(f64::from).collect();
        v.push(30.0);
        let b = box_stats(&v).unwrap();
        assert_eq!((b.q1, b.median, b.q3), (3.25, 5.5, 7.75));
        assert_eq!((b.low, b.high), (1.0, 9.0));
        assert_eq!(b.outliers, [30.0]);
        assert!(box_stats(&[f64::NAN]).is_none());
    }
}
