//! The trimmed mean of a cell's errors, as `scipy.stats.trim_mean`.

/// The share cut from each end for a cell's error (the paper's best statistic).
pub const CELL_TRIM: f64 = 0.3;

/// `scipy.stats.trim_mean(values, proportion)`: cut `int(proportion · n)` values from each
/// end of the sorted values and average the rest. Reorders `values`; NaN when nothing is
/// left (empty input, or a proportion of 0.5 or more).
pub fn trim_mean(values: &mut [f64], proportion: f64) -> f64 {
    let n = values.len();
    let cut = (proportion * n as f64) as usize;
    if n == 0 || 2 * cut >= n {
        return f64::NAN;
    }
    values.sort_unstable_by(f64::total_cmp);
    let kept = &values[cut..n - cut];
    kept.iter().sum::<f64>() / kept.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cuts_as_scipy_does() {
        // int(0.3·n) from each end: nothing below 4 values, 1 from 4 to 6, 3 at 10.
        assert_eq!(trim_mean(&mut [5.0], 0.3), 5.0);
        assert_eq!(trim_mean(&mut [1.0, 100.0, 2.0], 0.3), 103.0 / 3.0);
        assert_eq!(trim_mean(&mut [1.0, 100.0, 2.0, 3.0], 0.3), 2.5);
        let mut ten: Vec<f64> = (0..10).map(f64::from).rev().collect();
        // scipy.stats.trim_mean(range(10), 0.3) == 4.5 (keeps 3…6).
        assert_eq!(trim_mean(&mut ten, 0.3), 4.5);
        ten[9] = 1e9; // sorted by the call above: the largest becomes an outlier
        assert_eq!(trim_mean(&mut ten, 0.3), 4.5);
        assert!(trim_mean(&mut [], 0.3).is_nan());
        assert!(trim_mean(&mut [1.0, 2.0], 0.5).is_nan());
    }
}
