//! Thinning for display: what a long walk's page and 3-D view draw (`page.rs`,
//! `scene_view.rs`), evenly spaced so the drawing keeps the walk's shape.

/// Indices `0..n` thinned evenly to at most `max` (first and last kept).
pub(crate) fn thin(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        return (0..n).collect();
    }
    let max = max.max(2);
    (0..max)
        .map(|i| (i as f64 * (n - 1) as f64 / (max - 1) as f64).round() as usize)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinning_keeps_both_ends_and_the_bound() {
        assert_eq!(thin(5, 10), vec![0, 1, 2, 3, 4]);
        let kept = thin(78_001, 6_000);
        assert_eq!(kept.len(), 6_000);
        assert_eq!((kept[0], kept[5_999]), (0, 78_000));
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        // Even spacing: every gap 13 ± 1.
        assert!(kept.windows(2).all(|w| (12..=14).contains(&(w[1] - w[0]))));
    }
}
