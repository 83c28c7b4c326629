//! Robust statistics over pair values ("uncertainty calculation settings") and evo's
//! summary statistics.

use std::fmt;
use std::str::FromStr;

use crate::Error;

/// The per-window statistic over the pairwise RPE values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Setting {
    /// Arithmetic mean.
    Mean,
    /// Median (mean of the two middle values for an even count, as numpy).
    Median,
    /// Trimmed mean cutting this percentage (10, 20, 30 or 40) from *each* end, as
    /// `scipy.stats.trim_mean`.
    TrimMean(u8),
    /// Mean of the values within [Q1 − 1.5·IQR, Q3 + 1.5·IQR] (numpy linear quartiles).
    MeanInliers,
}

impl Setting {
    /// Every setting, in the order of the paper's Table 2.
    pub const ALL: [Setting; 7] = [
        Setting::Mean,
        Setting::Median,
        Setting::TrimMean(10),
        Setting::TrimMean(20),
        Setting::TrimMean(30),
        Setting::TrimMean(40),
        Setting::MeanInliers,
    ];

    /// Applies the statistic. `values` is reordered in place; an empty slice gives NaN.
    pub fn apply(self, values: &mut [f64]) -> f64 {
        match self {
            Setting::Mean => mean(values),
            Setting::Median => median(values),
            Setting::TrimMean(percent) => trim_mean(values, f64::from(percent) / 100.0),
            Setting::MeanInliers => mean_inliers(values),
        }
    }
}

impl Default for Setting {
    /// [`sitar_core::DEFAULT_SETTING`]: `trim_mean_30` (a test keeps the two equal).
    fn default() -> Self {
        Setting::TrimMean(30)
    }
}

impl fmt::Display for Setting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Setting::Mean => f.write_str("mean"),
            Setting::Median => f.write_str("median"),
            Setting::TrimMean(p) => write!(f, "trim_mean_{p}"),
            Setting::MeanInliers => f.write_str("mean_inliers"),
        }
    }
}

impl FromStr for Setting {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        match s {
            "mean" => Ok(Setting::Mean),
            "median" => Ok(Setting::Median),
            "mean_inliers" => Ok(Setting::MeanInliers),
            "trim_mean_10" => Ok(Setting::TrimMean(10)),
            "trim_mean_20" => Ok(Setting::TrimMean(20)),
            "trim_mean_30" => Ok(Setting::TrimMean(30)),
            "trim_mean_40" => Ok(Setting::TrimMean(40)),
            other => Err(Error::InvalidArgument(format!(
                "unknown setting '{other}' (expected mean, median, trim_mean_10|20|30|40 or mean_inliers)"
            ))),
        }
    }
}

/// Arithmetic mean (NaN for no values).
pub fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

/// Median as `numpy.median` (NaN for no values). Reorders `values`.
pub fn median(values: &mut [f64]) -> f64 {
    let n = values.len();
    if n == 0 {
        return f64::NAN;
    }
    let (lower, mid, _) = values.select_nth_unstable_by(n / 2, f64::total_cmp);
    let mid = *mid;
    if n % 2 == 1 {
        mid
    } else {
        let below = lower.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (below + mid) / 2.0
    }
}

/// `scipy.stats.trim_mean(values, proportion)`: cut `int(proportion·n)` values from each end,
/// average the rest (NaN for no values). Reorders `values`.
pub fn trim_mean(values: &mut [f64], proportion: f64) -> f64 {
    let n = values.len();
    if n == 0 {
        return f64::NAN;
    }
    let lowercut = (proportion * n as f64) as usize;
    let uppercut = n.saturating_sub(lowercut);
    if lowercut >= uppercut {
        return f64::NAN;
    }
    if lowercut > 0 {
        values.select_nth_unstable_by(lowercut, f64::total_cmp);
        values[lowercut..].select_nth_unstable_by(uppercut - 1 - lowercut, f64::total_cmp);
    }
    mean(&values[lowercut..uppercut])
}

/// The `q`-quantile (0..=1) with numpy's default linear interpolation. Reorders `values`.
pub fn quantile(values: &mut [f64], q: f64) -> f64 {
    let n = values.len();
    if n == 0 {
        return f64::NAN;
    }
    let virtual_index = q * (n - 1) as f64;
    let below = (virtual_index.floor() as usize).min(n - 1);
    let above = (below + 1).min(n - 1);
    let t = virtual_index - below as f64;
    let (_, a, upper) = values.select_nth_unstable_by(below, f64::total_cmp);
    let a = *a;
    let b = if above == below {
        a
    } else {
        upper.iter().copied().fold(f64::INFINITY, f64::min)
    };
    // numpy's _lerp: computed from the nearer end for accuracy.
    let diff = b - a;
    if t >= 0.5 {
        b - diff * (1.0 - t)
    } else {
        a + diff * t
    }
}

/// Interquartile range Q3 − Q1 (numpy linear quartiles). Reorders `values`.
pub fn interquartile_range(values: &mut [f64]) -> f64 {
    let q1 = quantile(values, 0.25);
    let q3 = quantile(values, 0.75);
    q3 - q1
}

/// Mean of the values within [Q1 − 1.5·IQR, Q3 + 1.5·IQR] (numpy linear quartiles).
pub fn mean_inliers(values: &mut [f64]) -> f64 {
    let q1 = quantile(values, 0.25);
    let q3 = quantile(values, 0.75);
    let iqr = q3 - q1;
    let (low, high) = (q1 - 1.5 * iqr, q3 + 1.5 * iqr);
    let (sum, count) = values
        .iter()
        .filter(|&&v| v >= low && v <= high)
        .fold((0.0, 0usize), |(s, c), &v| (s + v, c + 1));
    sum / count as f64
}

/// evo's summary statistics of an error vector.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Statistics {
    /// Root mean square error.
    pub rmse: f64,
    /// Mean.
    pub mean: f64,
    /// Median.
    pub median: f64,
    /// Population standard deviation (numpy `std`).
    pub std: f64,
    /// Minimum.
    pub min: f64,
    /// Maximum.
    pub max: f64,
    /// Sum of squared errors.
    pub sse: f64,
}

impl Statistics {
    /// Computes all statistics (NaN fields for an empty vector).
    pub fn from_errors(errors: &[f64]) -> Self {
        let n = errors.len() as f64;
        let mean_value = mean(errors);
        let sse: f64 = errors.iter().map(|e| e * e).sum();
        let variance = errors.iter().map(|e| (e - mean_value).powi(2)).sum::<f64>() / n;
        let mut sorted = errors.to_vec();
        Statistics {
            rmse: (sse / n).sqrt(),
            mean: mean_value,
            median: median(&mut sorted),
            std: variance.sqrt(),
            min: errors.iter().copied().fold(f64::INFINITY, f64::min),
            max: errors.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            sse,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn default_is_the_shared_default_name() {
        assert_eq!(Setting::default().to_string(), sitar_core::DEFAULT_SETTING);
        assert_eq!(
            sitar_core::DEFAULT_SETTING.parse::<Setting>().unwrap(),
            Setting::default()
        );
    }

    fn naive_trim_mean(values: &[f64], proportion: f64) -> f64 {
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let cut = (proportion * values.len() as f64) as usize;
        let kept = &sorted[cut..values.len() - cut];
        kept.iter().sum::<f64>() / kept.len() as f64
    }

    #[test]
    fn known_values() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        // scipy.stats.trim_mean(range(10), 0.1) == 4.5; cut 1 each end.
        let mut v: Vec<f64> = (0..10).map(f64::from).collect();
        v.reverse();
        assert_eq!(trim_mean(&mut v, 0.1), 4.5);
        // trim_mean([1, 2, 3, 100], 0.3): int(1.2) = 1 → mean(2, 3) = 2.5
        assert_eq!(trim_mean(&mut [100.0, 1.0, 3.0, 2.0], 0.3), 2.5);
        // numpy.percentile([1,2,3,4], 25) == 1.75
        assert_eq!(quantile(&mut [4.0, 3.0, 2.0, 1.0], 0.25), 1.75);
        // Q1 = 1.75, Q3 = 3.25+..: [1,2,3,4,100] → Q1 2, Q3 4, fences -1..7 → mean(1..4) = 2.5
        assert_eq!(mean_inliers(&mut [1.0, 2.0, 3.0, 4.0, 100.0]), 2.5);
        assert_eq!(
            "trim_mean_30".parse::<Setting>().unwrap(),
            Setting::default()
        );
        assert!("trim_mean_50".parse::<Setting>().is_err());
        for s in Setting::ALL {
            assert_eq!(s.to_string().parse::<Setting>().unwrap(), s);
        }
        let s = Statistics::from_errors(&[3.0, 4.0]);
        assert_eq!(
            (s.rmse, s.mean, s.std, s.sse, s.min, s.max),
            (12.5f64.sqrt(), 3.5, 0.5, 25.0, 3.0, 4.0)
        );
    }

    proptest! {
        #[test]
        fn trim_mean_matches_sort_and_cut(values in prop::collection::vec(-1e3f64..1e3, 1..200), pct in 0u8..=4) {
            let proportion = f64::from(pct * 10) / 100.0;
            let mut work = values.clone();
            let fast = trim_mean(&mut work, proportion);
            let naive = naive_trim_mean(&values, proportion);
            prop_assert!((fast - naive).abs() <= 1e-9 * (1.0 + naive.abs()), "{} vs {}", fast, naive);
        }

        #[test]
        fn median_and_quantiles_match_sorting(values in prop::collection::vec(-1e3f64..1e3, 1..100), q in 0.0f64..=1.0) {
            let mut sorted = values.clone();
            sorted.sort_by(f64::total_cmp);
            let position = q * (sorted.len() - 1) as f64;
            let (lo, hi) = (position.floor() as usize, position.ceil() as usize);
            let expected = sorted[lo] + (sorted[hi] - sorted[lo]) * (position - lo as f64);
            let got = quantile(&mut values.clone(), q);
            prop_assert!((got - expected).abs() <= 1e-9 * (1.0 + expected.abs()));
            let med = median(&mut values.clone());
            prop_assert!((med - quantile(&mut values.clone(), 0.5)).abs() <= 1e-9 * (1.0 + med.abs()));
        }
    }
}

/// Order statistics on non-negative floats stored as their IEEE bits (whose integer order is
/// the float order), with exact sums: the estimator's per-window statistic.
///
/// Every result depends only on the multiset of values, never on the order they lie in:
/// ranks are selected, sums are exact ([`crate::exact`]) and rounded once. That is what lets
/// the incremental estimate equal the one-shot one bit for bit; the rules both use (ranks,
/// cuts, fences and the final arithmetic) are the functions of this module.
pub(crate) mod bits {
    use super::Setting;
    use crate::exact::{ExactSquares, ExactSum, add_values, population_std};

    /// Partially sorts `v` (covering absolute ranks `offset..offset + v.len()`) so that every
    /// rank in `ranks` (sorted, absolute) holds its order statistic, with smaller values
    /// before it and larger ones after.
    fn select_ranks(v: &mut [u64], offset: usize, ranks: &[usize]) {
        if ranks.is_empty() || v.len() <= 1 {
            return;
        }
        if v.len() <= 24 {
            v.sort_unstable();
            return;
        }
        let mid = ranks.len() / 2;
        let r = ranks[mid] - offset;
        v.select_nth_unstable(r);
        let (left, right) = v.split_at_mut(r);
        select_ranks(left, offset, &ranks[..mid]);
        select_ranks(&mut right[1..], offset + r + 1, &ranks[mid + 1..]);
    }

    fn at(v: &[u64], rank: usize) -> f64 {
        f64::from_bits(v[rank])
    }

    /// `scipy.stats.trim_mean`'s `(lowercut, uppercut)`: the mean is over ranks `lowercut..uppercut`.
    pub(crate) fn trim_cuts(percent: u8, n: usize) -> (usize, usize) {
        let lowercut = (f64::from(percent) / 100.0 * n as f64) as usize;
        (lowercut, n.saturating_sub(lowercut))
    }

    /// The ranks (lower, upper) whose values give the median of `n > 0` values.
    pub(crate) fn median_ranks(n: usize) -> [usize; 2] {
        [(n - 1) / 2, n / 2]
    }

    /// numpy's median from the values at [`median_ranks`].
    pub(crate) fn median_of(n: usize, lower: f64, upper: f64) -> f64 {
        if n % 2 == 1 {
            upper
        } else {
            (lower + upper) / 2.0
        }
    }

    /// The ranks (below, above) numpy's linear `q`-quantile of `n > 0` values interpolates.
    pub(crate) fn quantile_ranks(n: usize, q: f64) -> [usize; 2] {
        let below = ((q * (n - 1) as f64).floor() as usize).min(n - 1);
        [below, (below + 1).min(n - 1)]
    }

    /// numpy's linear `q`-quantile from the values at [`quantile_ranks`] (its `_lerp`,
    /// computed from the nearer end).
    pub(crate) fn interpolate(n: usize, q: f64, below: f64, above: f64) -> f64 {
        let position = q * (n - 1) as f64;
        let t = position - quantile_ranks(n, q)[0] as f64;
        let diff = above - below;
        if t >= 0.5 {
            above - diff * (1.0 - t)
        } else {
            below + diff * t
        }
    }

    /// The bits range `[low, high)` of the non-negative values within
    /// [Q1 − 1.5·IQR, Q3 + 1.5·IQR]; NaN values are never inside, NaN fences keep none.
    pub(crate) fn inlier_range(q1: f64, q3: f64) -> (u64, u64) {
        let iqr = q3 - q1;
        let (low, high) = (q1 - 1.5 * iqr, q3 + 1.5 * iqr + 0.0);
        if low.is_nan() || high.is_nan() || high < 0.0 {
            return (0, 0);
        }
        let low_bits = if low > 0.0 { low.to_bits() } else { 0 };
        (low_bits, high.to_bits().min(f64::INFINITY.to_bits()) + 1)
    }

    /// A mean from an exact sum: rounded once, then divided.
    pub(crate) fn mean_of(sum: &ExactSum, count: usize) -> f64 {
        sum.value() / count as f64
    }

    fn quantile(v: &[u64], q: f64) -> f64 {
        let [below, above] = quantile_ranks(v.len(), q);
        interpolate(v.len(), q, at(v, below), at(v, above))
    }

    /// `(statistic, population standard deviation)` of the values; equal to
    /// [`Setting::apply`] and numpy's `std` up to rounding, and a function of the multiset
    /// alone. `v` must be non-empty and hold non-negative floats; it is reordered.
    pub(crate) fn window_statistics(v: &mut [u64], setting: Setting) -> (f64, f64) {
        let n = v.len();
        let mut ranks = Vec::with_capacity(4);
        match setting {
            Setting::TrimMean(percent) => {
                let (lowercut, uppercut) = trim_cuts(percent, n);
                if lowercut > 0 && lowercut < uppercut {
                    ranks.extend([lowercut, uppercut - 1]);
                }
            }
            Setting::Median => ranks.extend(median_ranks(n)),
            Setting::MeanInliers => {
                ranks.extend(quantile_ranks(n, 0.25));
                ranks.extend(quantile_ranks(n, 0.75));
            }
            Setting::Mean => {}
        }
        ranks.sort_unstable();
        ranks.dedup();
        select_ranks(v, 0, &ranks);
        let bound = v.iter().copied().max().unwrap_or(0);
        let (mut sum, mut squares) = (ExactSum::new(), ExactSquares::new());
        // A trimmed mean's middle is summed on its own and added to the rest: one pass.
        let middle_range = match setting {
            Setting::TrimMean(percent) => {
                let (lowercut, uppercut) = trim_cuts(percent, n);
                lowercut.min(uppercut)..uppercut
            }
            _ => 0..0,
        };
        let mut middle = ExactSum::new();
        let inside = v[middle_range.clone()].iter().copied();
        add_values(&mut middle, Some(&mut squares), inside, bound);
        let outside = v[..middle_range.start].iter().chain(&v[middle_range.end..]);
        add_values(&mut sum, Some(&mut squares), outside.copied(), bound);
        sum.add_sum(&middle, false);
        let spread = population_std(n, &sum, &squares);
        let value = match setting {
            Setting::Mean => mean_of(&sum, n),
            Setting::Median => {
                let [lower, upper] = median_ranks(n);
                median_of(n, at(v, lower), at(v, upper))
            }
            Setting::TrimMean(percent) => {
                let (lowercut, uppercut) = trim_cuts(percent, n);
                if lowercut >= uppercut {
                    f64::NAN
                } else {
                    mean_of(&middle, uppercut - lowercut)
                }
            }
            Setting::MeanInliers => {
                let (low, high) = inlier_range(quantile(v, 0.25), quantile(v, 0.75));
                let inside = || v.iter().copied().filter(|b| (low..high).contains(b));
                let mut inliers = ExactSum::new();
                add_values(&mut inliers, None, inside(), bound);
                mean_of(&inliers, inside().count())
            }
        };
        (value, spread)
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #[test]
            fn equals_the_float_statistics(values in prop::collection::vec(0.0f64..10.0, 1..300), which in 0usize..7) {
                let setting = Setting::ALL[which];
                let mut bits: Vec<u64> = values.iter().map(|v| v.to_bits()).collect();
                let (value, spread) = window_statistics(&mut bits, setting);
                let want = setting.apply(&mut values.clone());
                let want_spread = crate::Statistics::from_errors(&values).std;
                prop_assert!((value - want).abs() <= 1e-12 * (1.0 + want.abs()), "{} vs {}", value, want);
                prop_assert!((spread - want_spread).abs() <= 1e-12);
            }
        }
    }
}
