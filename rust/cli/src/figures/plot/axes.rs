//! Axis ranges and tick labels: equal scales, padded ranges, offsets for large values,
//! fixed decimals.

use std::ops::Range;

/// A cube of equal sides around `points` (10 % margin) for 3-D plots, and tick decimals.
pub(super) fn cube<'a>(points: impl Iterator<Item = &'a [f64; 3]>) -> ([Range<f64>; 3], usize) {
    let (mut low, mut high) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in points {
        for k in 0..3 {
            low[k] = low[k].min(p[k]);
            high[k] = high[k].max(p[k]);
        }
    }
    if low[0] > high[0] {
        (low, high) = ([0.0; 3], [0.0; 3]);
    }
    let half = (0..3).map(|k| high[k] - low[k]).fold(1e-3, f64::max) * 0.55;
    let range = |k: usize| {
        let c = (low[k] + high[k]) / 2.0;
        c - half..c + half
    };
    ([range(0), range(1), range(2)], decimals(2.0 * half))
}

/// The range of `values` with 2 % margins; `fallback ± 1` without a spread.
pub(super) fn padded(values: impl Iterator<Item = f64>, fallback: f64) -> Range<f64> {
    let (low, high) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    if high > low {
        let pad = 0.02 * (high - low);
        low - pad..high + pad
    } else if low.is_finite() {
        low - 1.0..low + 1.0
    } else {
        fallback - 1.0..fallback + 1.0
    }
}

/// A tick label with `decimals` decimals, without a minus on zero.
pub fn tick(value: f64, decimals: usize) -> String {
    let text = format!("{value:.decimals$}");
    match text.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_owned(),
        _ => text,
    }
}

/// The offset of an axis whose values are large beside their spread (absolute Unix seconds
/// over a minute), as matplotlib's: its ticks show `value - offset` and its label
/// `+ offset`, so "1311 868 210.0" becomes "10.0". 0 when the values need none (an offset
/// would save fewer than 4 digits). The offset is the range's start rounded down to the
/// power of ten just above its width.
pub fn axis_offset(range: &Range<f64>) -> f64 {
    let width = range.end - range.start;
    let magnitude = range.start.abs().max(range.end.abs());
    if !(width > 0.0 && magnitude.is_finite()) || magnitude < 1e4 * width {
        return 0.0;
    }
    let step = 10f64.powf(width.log10().ceil());
    (range.start / step).floor() * step
}

/// Decimals for tick labels over a range of width `span` (about two significant digits).
pub fn decimals(span: f64) -> usize {
    if span > 0.0 && span.is_finite() {
        (1.0 - span.log10().floor()).clamp(0.0, 9.0) as usize
    } else {
        3
    }
}

/// Ranges around `points` (10 % margin) with the same metres per pixel on both axes of a
/// plotting area of `pixels`.
pub(super) fn equal_scale(points: &[(f64, f64)], pixels: (u32, u32)) -> (Range<f64>, Range<f64>) {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in points {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if !(x0 <= x1 && y0 <= y1) {
        (x0, x1, y0, y1) = (0.0, 0.0, 0.0, 0.0);
    }
    let (w, h) = (f64::from(pixels.0.max(1)), f64::from(pixels.1.max(1)));
    // Metres per pixel; a millimetre over the panel at least, for a standing-still trajectory.
    let per_pixel = ((x1 - x0) / w).max((y1 - y0) / h).max(1e-3 / w.max(h)) * 1.1;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let (half_w, half_h) = (per_pixel * w / 2.0, per_pixel * h / 2.0);
    (cx - half_w..cx + half_w, cy - half_h..cy + half_h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_time_axes_get_an_offset() {
        // fr1/xyz: 30 s of Unix seconds.
        let range = 1_305_031_098.6..1_305_031_128.7;
        assert_eq!(axis_offset(&range), 1_305_031_000.0);
        assert_eq!(
            tick(range.start - axis_offset(&range), decimals(3.0)),
            "98.6"
        );
        assert_eq!(axis_offset(&(0.0..30.0)), 0.0);
        assert_eq!(axis_offset(&(-2.0..3.5)), 0.0);
        assert_eq!(axis_offset(&(1000.0..1000.0)), 0.0);
        assert_eq!(
            axis_offset(&(-1_305_031_128.7..-1_305_031_098.6)),
            -1_305_031_200.0
        );
    }

    #[test]
    fn equal_scale_has_one_scale_and_contains_the_data() {
        let points = [(0.0, 0.0), (4.0, 1.0), (2.0, -1.0)];
        let pixels = (800, 500);
        let (x, y) = equal_scale(&points, pixels);
        let (sx, sy) = (
            (x.end - x.start) / f64::from(pixels.0),
            (y.end - y.start) / f64::from(pixels.1),
        );
        assert!((sx - sy).abs() < 1e-12 * sx, "{sx} vs {sy}");
        for (px, py) in points {
            assert!(x.contains(&px) && y.contains(&py));
        }
        // The wide direction fills the panel (with the 10 % margin), the other is centred.
        assert!((x.end - x.start - 4.4).abs() < 1e-12);
        assert!((y.start + y.end).abs() < 1e-12);
        // A tall trajectory is limited by the height instead.
        let (x, y) = equal_scale(&[(0.0, 0.0), (0.1, 10.0)], pixels);
        assert!((y.end - y.start - 11.0).abs() < 1e-9);
        assert!(((x.end - x.start) / 800.0 - (y.end - y.start) / 500.0).abs() < 1e-12);
        // A single point still gets a non-empty view.
        let (x, y) = equal_scale(&[(1.0, 2.0)], pixels);
        assert!(x.start < 1.0 && x.end > 1.0 && y.start < 2.0 && y.end > 2.0);
    }

    #[test]
    fn ticks_have_fixed_decimals_and_no_negative_zero() {
        assert_eq!(tick(-0.0, 1), "0.0");
        assert_eq!(tick(-1e-17, 2), "0.00");
        assert_eq!(tick(-0.25, 2), "-0.25");
        assert_eq!(tick(1.0, 0), "1");
        assert_eq!(decimals(2.0), 1);
        assert_eq!(decimals(0.05), 3);
        assert_eq!(decimals(0.0), 3);
    }
}
