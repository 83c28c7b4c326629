//! The error figure of `sitar rpe`, `ape` and `estimate` (`--plot FILE.svg`), after evo's
//! `--plot`: the error over time above, the trajectory seen from above and coloured by error
//! below (evo's colour-mapped `--plot_mode` plot), as SVG.

use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::ValueEnum;
use plotters::prelude::*;

/// The `--plot` and `--plot-mode` flags.
#[derive(clap::Args, Debug)]
pub struct PlotArgs {
    /// Draw an SVG figure here: the error over time, and the trajectory in the --plot-mode
    /// plane with each error as a dot coloured by its size (as evo's --plot).
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Plane of the trajectory panel, horizontal axis first, with equal scales on both axes
    /// (evo's --plot_mode); xz looks down on ARCore/Unity poses, whose y is up.
    #[arg(
        long = "plot-mode",
        alias = "plot_mode",
        value_enum,
        default_value_t,
        requires = "plot"
    )]
    pub plot_mode: PlotMode,
}

/// Plane of the trajectory panel: horizontal axis, then vertical axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum PlotMode {
    /// x horizontal, y vertical.
    Xy,
    /// x horizontal, z vertical: the top view of y-up (ARCore, Unity) poses.
    #[default]
    Xz,
    /// y horizontal, z vertical.
    Yz,
    /// z horizontal, x vertical.
    Zx,
    /// z horizontal, y vertical.
    Zy,
    /// y horizontal, x vertical.
    Yx,
}

impl PlotMode {
    /// Indices of the horizontal and the vertical coordinate.
    fn axes(self) -> [usize; 2] {
        match self {
            PlotMode::Xy => [0, 1],
            PlotMode::Xz => [0, 2],
            PlotMode::Yz => [1, 2],
            PlotMode::Zx => [2, 0],
            PlotMode::Zy => [2, 1],
            PlotMode::Yx => [1, 0],
        }
    }
}

/// One error to draw: when, where on the trajectory, and how large.
pub struct Sample {
    /// Stamp (ns) of the pose or of the window's first pose.
    pub stamp: i64,
    /// Position (m) on the figure's trajectory; `None`: not drawn on the trajectory panel.
    pub position: Option<[f64; 3]>,
    /// The error.
    pub error: f64,
}

/// What the error figure shows.
pub struct ErrorFigure {
    /// Title above both panels.
    pub title: String,
    /// Name of the error ("APE", "RPE", "estimated error").
    pub metric: &'static str,
    /// Unit of the error ("m", "deg", "rad", or "" for full transformations).
    pub unit: &'static str,
    /// Stamp (ns) the time axis counts from.
    pub first_stamp: i64,
    /// Stamps are pose indices (KITTI), not nanoseconds.
    pub stamps_are_indices: bool,
    /// Horizontal lines with a legend on the error panel (`("mean", value)`, …).
    pub lines: Vec<(&'static str, f64)>,
    /// Name of the trajectory of the lower panel ("reference", "trial 0").
    pub trajectory_name: String,
    /// Every position (m) of that trajectory, drawn as a grey line.
    pub trajectory: Vec<[f64; 3]>,
    /// The errors, in time order; non-finite ones are left out of both panels.
    pub samples: Vec<Sample>,
}

/// Colour of the error line (matplotlib's first colour, as evo's).
const ERROR_COLOUR: RGBColor = RGBColor(0x1F, 0x77, 0xB4);
/// Colours of the horizontal lines, in order.
const LINE_COLOURS: [RGBColor; 4] = [
    RGBColor(0xD6, 0x27, 0x28),
    RGBColor(0x2C, 0xA0, 0x2C),
    RGBColor(0xFF, 0x7F, 0x0E),
    RGBColor(0x94, 0x67, 0xBD),
];
/// Font of tick labels and axis descriptions (plotters' default shrinks with the panel).
const LABEL_FONT: (&str, u32) = ("sans-serif", 13);
/// Figure size in pixels.
const SIZE: (u32, u32) = (1000, 1150);
/// Height of the error-over-time panel.
const ERROR_PANEL_HEIGHT: u32 = 400;
/// Width of the colour bar beside the trajectory panel.
const COLOUR_BAR_WIDTH: u32 = 110;

/// Matplotlib's viridis at 0, 1/8, …, 1 (perceptually uniform, readable in grey and with
/// colour-vision deficiencies); linearly interpolated in between.
const VIRIDIS: [(u8, u8, u8); 9] = [
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
fn viridis(t: f64) -> RGBColor {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let k = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - k as f64;
    let (a, b) = (VIRIDIS[k], VIRIDIS[k + 1]);
    let lerp = |a: u8, b: u8| (f64::from(a) + f * (f64::from(b) - f64::from(a))).round() as u8;
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// Draws `figure` and writes it to `path` as SVG; the error names the file.
pub fn write(path: &Path, mode: PlotMode, figure: &ErrorFigure) -> Result<()> {
    let svg = render(mode, figure)
        .map_err(|e| anyhow::anyhow!("{}: cannot draw the plot: {e}", path.display()))?;
    std::fs::write(path, svg).with_context(|| format!("{}: cannot write the plot", path.display()))
}

type DrawResult<T> = Result<T, Box<dyn std::error::Error>>;

/// The figure as SVG text.
fn render(mode: PlotMode, figure: &ErrorFigure) -> DrawResult<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE)?;
        let (title, body) = root.split_vertically(40);
        title.titled(&figure.title, ("sans-serif", 20))?;
        let (upper, lower) = body.split_vertically(ERROR_PANEL_HEIGHT);
        let samples: Vec<&Sample> = figure
            .samples
            .iter()
            .filter(|s| s.error.is_finite())
            .collect();
        error_over_time(&upper, figure, &samples)?;
        trajectory_by_error(&lower, mode, figure, &samples)?;
        root.present()?;
    }
    Ok(svg)
}

/// `metric (unit)`, or the metric alone without a unit.
fn with_unit(figure: &ErrorFigure) -> String {
    if figure.unit.is_empty() {
        figure.metric.to_owned()
    } else {
        format!("{} ({})", figure.metric, figure.unit)
    }
}

/// Upper panel: the error against time, with the horizontal lines and their legend.
fn error_over_time<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    figure: &ErrorFigure,
    samples: &[&Sample],
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let time = |stamp: i64| {
        let offset = stamp.saturating_sub(figure.first_stamp) as f64;
        if figure.stamps_are_indices {
            offset
        } else {
            offset * 1e-9
        }
    };
    let points: Vec<(f64, f64)> = samples.iter().map(|s| (time(s.stamp), s.error)).collect();
    let x_range = padded(points.iter().map(|p| p.0), 0.0);
    let lines = figure.lines.iter().filter(|(_, v)| v.is_finite());
    let y_max = points
        .iter()
        .map(|p| p.1)
        .chain(lines.clone().map(|&(_, v)| v))
        .fold(0.0f64, f64::max);
    let y_range = 0.0..if y_max > 0.0 { y_max * 1.05 } else { 1.0 };
    let (x_decimals, y_decimals) = (
        decimals(x_range.end - x_range.start),
        decimals(y_range.end - y_range.start),
    );
    let mut chart = ChartBuilder::on(area)
        .caption(format!("{} over time", figure.metric), ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x_range.clone(), y_range)?;
    chart
        .configure_mesh()
        .max_light_lines(1)
        .x_desc(if figure.stamps_are_indices {
            "pose index from the first"
        } else {
            "t − t₀ (s)"
        })
        .y_desc(with_unit(figure))
        .label_style(LABEL_FONT)
        .axis_desc_style(LABEL_FONT)
        .x_label_formatter(&|&x| tick(x, x_decimals))
        .y_label_formatter(&|&y| tick(y, y_decimals))
        .draw()?;
    chart
        .draw_series(LineSeries::new(points, ERROR_COLOUR.stroke_width(1)))?
        .label(figure.metric)
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], ERROR_COLOUR.stroke_width(2)));
    for (&(name, value), colour) in lines.zip(LINE_COLOURS.iter().cycle()) {
        let style = colour.stroke_width(2);
        chart
            .draw_series(LineSeries::new(
                [(x_range.start, value), (x_range.end, value)],
                style,
            ))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
    }
    if !figure.lines.is_empty() {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    Ok(())
}

/// Lower panel: the trajectory in the plane of `mode` with equal scales, each sample's
/// position a dot coloured by its error, and a colour bar.
fn trajectory_by_error<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    mode: PlotMode,
    figure: &ErrorFigure,
    samples: &[&Sample],
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let [a, b] = mode.axes();
    const NAMES: [&str; 3] = ["x", "y", "z"];
    let project = |p: &[f64; 3]| (p[a], p[b]);
    let placed: Vec<((f64, f64), f64)> = samples
        .iter()
        .filter_map(|s| s.position.as_ref().map(|p| (project(p), s.error)))
        .collect();
    let hidden = samples.len() - placed.len();
    let mut caption = format!(
        "{} in the {}{} plane, coloured by {}",
        figure.trajectory_name, NAMES[a], NAMES[b], figure.metric
    );
    if hidden > 0 {
        caption.push_str(&format!(
            " ({hidden} of {} not drawn: no pose here)",
            samples.len()
        ));
    }
    let area = area.titled(&caption, ("sans-serif", 16))?;
    let (map_area, bar_area) = area.split_horizontally(area.dim_in_pixel().0 - COLOUR_BAR_WIDTH);

    let errors = placed.iter().map(|p| p.1);
    let low = errors.clone().fold(f64::INFINITY, f64::min);
    let high = errors.fold(f64::NEG_INFINITY, f64::max);
    let normalise = |e: f64| {
        if high > low {
            (e - low) / (high - low)
        } else {
            0.5
        }
    };

    let build = |x: Range<f64>, y: Range<f64>| {
        ChartBuilder::on(&map_area)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x, y)
    };
    // Building a chart without a caption draws nothing: a probe gives the plotting area's size.
    let pixels = build(0.0..1.0, 0.0..1.0)?.plotting_area().dim_in_pixel();
    let path: Vec<(f64, f64)> = figure.trajectory.iter().map(project).collect();
    let (x_range, y_range) = equal_scale(&path, pixels);
    let map_decimals = decimals((x_range.end - x_range.start).max(y_range.end - y_range.start));
    let mut chart = build(x_range, y_range)?;
    chart
        .configure_mesh()
        .max_light_lines(1)
        .x_desc(format!("{} (m)", NAMES[a]))
        .y_desc(format!("{} (m)", NAMES[b]))
        .label_style(LABEL_FONT)
        .axis_desc_style(LABEL_FONT)
        .x_label_formatter(&|&x| tick(x, map_decimals))
        .y_label_formatter(&|&y| tick(y, map_decimals))
        .draw()?;
    chart.draw_series(LineSeries::new(
        path,
        RGBColor(160, 160, 160).stroke_width(1),
    ))?;
    chart.draw_series(
        placed
            .iter()
            .map(|&(p, e)| Circle::new(p, 3, viridis(normalise(e)).filled())),
    )?;

    if placed.is_empty() {
        return Ok(());
    }
    let bar_range = if high > low {
        low..high
    } else {
        low - 0.5..low + 0.5
    };
    let bar_decimals = decimals(bar_range.end - bar_range.start);
    let mut bar = ChartBuilder::on(&bar_area)
        .margin(10)
        .margin_right(0)
        .x_label_area_size(40)
        .right_y_label_area_size(70)
        .build_cartesian_2d(0.0..1.0, bar_range.clone())?;
    const STEPS: usize = 64;
    let span = bar_range.end - bar_range.start;
    bar.draw_series((0..STEPS).map(|k| {
        let (v0, v1) = (
            bar_range.start + span * k as f64 / STEPS as f64,
            bar_range.start + span * (k + 1) as f64 / STEPS as f64,
        );
        let colour = viridis((k as f64 + 0.5) / STEPS as f64);
        Rectangle::new([(0.0, v0), (1.0, v1)], colour.filled())
    }))?;
    bar.configure_mesh()
        .disable_mesh()
        .x_labels(0)
        .y_desc(with_unit(figure))
        .label_style(LABEL_FONT)
        .axis_desc_style(LABEL_FONT)
        .y_label_formatter(&|&y| tick(y, bar_decimals))
        .draw()?;
    Ok(())
}

/// The range of `values` with 2 % margins; `fallback ± 1` without a spread.
fn padded(values: impl Iterator<Item = f64>, fallback: f64) -> Range<f64> {
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
fn tick(value: f64, decimals: usize) -> String {
    let text = format!("{value:.decimals$}");
    match text.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_owned(),
        _ => text,
    }
}

/// Decimals for tick labels over a range of width `span` (about two significant digits).
fn decimals(span: f64) -> usize {
    if span > 0.0 && span.is_finite() {
        (1.0 - span.log10().floor()).clamp(0.0, 9.0) as usize
    } else {
        3
    }
}

/// Ranges around `points` (10 % margin) with the same metres per pixel on both axes of a
/// plotting area of `pixels`.
fn equal_scale(points: &[(f64, f64)], pixels: (u32, u32)) -> (Range<f64>, Range<f64>) {
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

    #[test]
    fn plot_modes_pick_evo_axes() {
        assert_eq!(PlotMode::default(), PlotMode::Xz);
        assert_eq!(PlotMode::Xz.axes(), [0, 2]);
        assert_eq!(PlotMode::Zy.axes(), [2, 1]);
        assert_eq!(
            PlotMode::from_str("yx", false).map(PlotMode::axes),
            Ok([1, 0])
        );
    }
}
