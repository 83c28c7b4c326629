//! The error figure's colours, fonts and sizes, and matplotlib's viridis colour map.

use plotters::prelude::*;

/// Colour of the error line (matplotlib's first colour, as evo's).
pub(super) const ERROR_COLOUR: RGBColor = RGBColor(0x1F, 0x77, 0xB4);
/// Colours of the horizontal lines, in order.
pub(super) const LINE_COLOURS: [RGBColor; 4] = [
    RGBColor(0xD6, 0x27, 0x28),
    RGBColor(0x2C, 0xA0, 0x2C),
    RGBColor(0xFF, 0x7F, 0x0E),
    RGBColor(0x94, 0x67, 0xBD),
];
/// Colour of the dashed reference (evo's `plot_reference_color`).
pub(super) const REFERENCE_COLOUR: RGBColor = RGBColor(0x44, 0x44, 0x44);
/// Colour of the line under the coloured errors.
pub(super) const TRAJECTORY_COLOUR: RGBColor = RGBColor(160, 160, 160);
/// Font of tick labels and axis descriptions (plotters' default shrinks with the panel).
pub(super) const LABEL_FONT: (&str, u32) = ("sans-serif", 13);
/// Height of the error-over-time panel.
pub(super) const ERROR_PANEL_HEIGHT: u32 = 400;
/// Width of the colour bar beside the trajectory panel.
pub(super) const COLOUR_BAR_WIDTH: u32 = 140;

/// Matplotlib's viridis at 0, 1/8, …, 1 (perceptually uniform, readable in grey and with
/// colour-vision deficiencies); linearly interpolated in between.
pub(super) const VIRIDIS: [(u8, u8, u8); 9] = [
    (0x44, 0x01, 0x54),
    (0x47, 0x2D, 0x7B),
    (0x3B, 0x52, 0x8B),
    (0x2C, 0x72, 0x8E),
    (0x21, 0x91, 0x8C),
    (0x28, 0xAE, 0x80),
    (0x5E, 0xC9, 0x62),
    (0xAD, 0xDC, 0x30),
    (0xFD, 0xE7, 0x25),
];

/// Viridis at `t` in [0, 1] (clamped; NaN gives the low end).
pub(super) fn viridis(t: f64) -> RGBColor {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let k = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - k as f64;
    let (a, b) = (VIRIDIS[k], VIRIDIS[k + 1]);
    let lerp = |a: u8, b: u8| (f64::from(a) + f * (f64::from(b) - f64::from(a))).round() as u8;
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_ends_and_clamps() {
        assert_eq!(viridis(0.0), RGBColor(0x44, 0x01, 0x54));
        assert_eq!(viridis(1.0), RGBColor(0xFD, 0xE7, 0x25));
        assert_eq!(viridis(-3.0), viridis(0.0));
        assert_eq!(viridis(7.0), viridis(1.0));
        assert_eq!(viridis(f64::NAN), viridis(0.0));
        assert_eq!(viridis(0.5), RGBColor(0x21, 0x91, 0x8C));
        assert_eq!(viridis(1.0 / 16.0), RGBColor(0x46, 0x17, 0x68));
        // Lightness rises monotonically (perceptual map): green channel increases.
        let greens: Vec<u8> = (0..=20).map(|k| viridis(k as f64 / 20.0).1).collect();
        assert!(greens.windows(2).all(|g| g[0] <= g[1]), "{greens:?}");
    }
}
