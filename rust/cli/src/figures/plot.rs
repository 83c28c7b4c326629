//! The error figure of `sitar rpe`, `ape` and `estimate` (`--plot FILE.svg`), after evo's
//! `--plot`: the error over time above, the trajectory seen from above and coloured by error
//! below (evo's colour-mapped `--plot_mode` plot), as SVG.

use std::ops::Range;
use std::path::PathBuf;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::figures::figure::{DrawResult, ErrorFigure, Path3, PlotMode, Sample};

/// The `--plot` and `--plot-mode` flags of `sitar estimate`.
#[derive(clap::Args, Debug)]
pub struct PlotArgs {
    /// Draw the figure here, SVG, PNG or PDF by the extension: the error over time, and the
    /// trajectory in the --plot-mode plane with each error as a dot coloured by its size.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Plane of the trajectory panel, horizontal axis first, with equal scales on both axes
    /// (evo's --plot_mode; xyz: 3-D); xz looks down on ARCore/Unity poses, whose y is up.
    #[arg(
        long = "plot-mode",
        alias = "plot_mode",
        value_enum,
        default_value_t,
        requires = "plot"
    )]
    pub plot_mode: PlotMode,
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
/// Colour of the dashed reference (evo's `plot_reference_color`).
const REFERENCE_COLOUR: RGBColor = RGBColor(0x44, 0x44, 0x44);
/// Colour of the line under the coloured errors.
const TRAJECTORY_COLOUR: RGBColor = RGBColor(160, 160, 160);
/// Font of tick labels and axis descriptions (plotters' default shrinks with the panel).
const LABEL_FONT: (&str, u32) = ("sans-serif", 13);
/// Height of the error-over-time panel.
const ERROR_PANEL_HEIGHT: u32 = 400;
/// Width of the colour bar beside the trajectory panel.
const COLOUR_BAR_WIDTH: u32 = 140;

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

/// Both panels on one page: the title, the error over time, the trajectory coloured by error.
pub fn both<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    mode: PlotMode,
    figure: &ErrorFigure,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (title, body) = root.split_vertically(40);
    title.titled(&figure.title.replace('\n', " "), ("sans-serif", 20))?;
    let (upper, lower) = body.split_vertically(ERROR_PANEL_HEIGHT);
    error_over_time(&upper, figure)?;
    trajectory_by_error(&lower, mode, figure)?;
    Ok(())
}

/// evo's "raw" figure alone: the error over the x dimension, titled.
pub fn raw<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    figure: &ErrorFigure,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (title, body) = root.split_vertically(60);
    title_lines(&title, &figure.title)?;
    error_over_time(&body, figure)
}

/// evo's "map" figure alone: the trajectories, the errors coloured, a colour bar.
pub fn map<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    mode: PlotMode,
    figure: &ErrorFigure,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (title, body) = root.split_vertically(60);
    title_lines(&title, &figure.title)?;
    trajectory_by_error(&body, mode, figure)
}

/// A title of one or more lines, centred.
pub fn title_lines<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let lines: Vec<&str> = title.lines().collect();
    let (w, h) = area.dim_in_pixel();
    let step = (h as usize / lines.len().max(1)).min(22) as i32;
    for (k, line) in lines.iter().enumerate() {
        let style = TextStyle::from(("sans-serif", 16).into_font()).pos(
            plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Center,
                plotters::style::text_anchor::VPos::Top,
            ),
        );
        area.draw_text(line, &style, ((w / 2) as i32, 6 + k as i32 * step))?;
    }
    Ok(())
}

/// The errors to draw: the finite ones.
fn finite(figure: &ErrorFigure) -> Vec<&Sample> {
    figure
        .samples
        .iter()
        .filter(|s| s.error.is_finite())
        .collect()
}

/// `metric (unit)`, or the metric alone without a unit.
fn with_unit(figure: &ErrorFigure) -> String {
    if figure.unit.is_empty() || figure.unit == "unit-less" {
        figure.metric.to_owned()
    } else {
        format!("{} ({})", figure.metric, figure.unit)
    }
}

/// Error panel: the error against the x dimension, the statistics lines, the std band.
fn error_over_time<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    figure: &ErrorFigure,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let samples = finite(figure);
    let points: Vec<(f64, f64)> = samples.iter().map(|s| (s.x, s.error)).collect();
    let x_range = padded(points.iter().map(|p| p.0), 0.0);
    let lines = figure.lines.iter().filter(|(_, v)| v.is_finite());
    let y_max = points
        .iter()
        .map(|p| p.1)
        .chain(lines.clone().map(|&(_, v)| v))
        .chain(figure.std_band.map(|b| b.1))
        .fold(0.0f64, f64::max);
    let y_min = points.iter().map(|p| p.1).fold(0.0f64, f64::min);
    let y_range = y_min..if y_max > 0.0 { y_max * 1.05 } else { 1.0 };
    let (x_decimals, y_decimals) = (
        decimals(x_range.end - x_range.start),
        decimals(y_range.end - y_range.start),
    );
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("{} over {}", figure.metric, figure.x_label),
            ("sans-serif", 16),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x_range.clone(), y_range)?;
    chart
        .configure_mesh()
        .max_light_lines(1)
        .x_desc(figure.x_label.as_str())
        .y_desc(with_unit(figure))
        .label_style(LABEL_FONT)
        .axis_desc_style(LABEL_FONT)
        .x_label_formatter(&|&x| tick(x, x_decimals))
        .y_label_formatter(&|&y| tick(y, y_decimals))
        .draw()?;
    if let Some((low, high)) = figure
        .std_band
        .filter(|b| b.0.is_finite() && b.1.is_finite())
    {
        let band = LINE_COLOURS[3].mix(0.2).filled();
        chart
            .draw_series([Rectangle::new(
                [(x_range.start, low), (x_range.end, high)],
                band,
            )])?
            .label("std")
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], band));
    }
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
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    }
    Ok(())
}

/// Map panel: the dashed reference, the trajectory carrying the errors with each error a
/// dot coloured by its size (equal scales), and a colour bar; 3-D in the xyz mode.
fn trajectory_by_error<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    mode: PlotMode,
    figure: &ErrorFigure,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let samples = finite(figure);
    let placed: Vec<([f64; 3], f64)> = samples
        .iter()
        .filter_map(|s| s.position.map(|p| (p, s.error)))
        .collect();
    let hidden = samples.len() - placed.len();
    const NAMES: [&str; 3] = ["x", "y", "z"];
    let plane = match mode.axes() {
        Some([a, b]) => format!("the {}{} plane", NAMES[a], NAMES[b]),
        None => "3-D".to_owned(),
    };
    let mut caption = format!(
        "{} in {plane}, coloured by {}",
        figure.trajectory_name, figure.metric
    );
    if !figure.reference.is_empty() {
        caption.push_str(&format!(", {} dashed", figure.reference_name));
    }
    if hidden > 0 {
        caption.push_str(&format!(
            " ({hidden} of {} not drawn: no pose here)",
            samples.len()
        ));
    }
    let area = area.titled(&caption, ("sans-serif", 16))?;
    let (map_area, bar_area) = area.split_horizontally(area.dim_in_pixel().0 - COLOUR_BAR_WIDTH);

    let (low, high) = figure.colour_range.unwrap_or_else(|| {
        placed
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p.1), h.max(p.1))
            })
    });
    let normalise = move |e: f64| {
        if high > low {
            (e - low) / (high - low)
        } else {
            0.5
        }
    };
    match mode.axes() {
        Some(axes) => plane_map(&map_area, axes, figure, &placed, &normalise)?,
        None => space_map(&map_area, figure, &placed, &normalise)?,
    }
    if placed.is_empty() || !(low.is_finite() && high.is_finite()) {
        return Ok(());
    }
    colour_bar(&bar_area, figure, low, high)
}

/// The map in a coordinate plane, equal metres per pixel on both axes.
fn plane_map<DB: DrawingBackend>(
    map_area: &DrawingArea<DB, plotters::coord::Shift>,
    [a, b]: [usize; 2],
    figure: &ErrorFigure,
    placed: &[([f64; 3], f64)],
    normalise: &dyn Fn(f64) -> f64,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    const NAMES: [&str; 3] = ["x", "y", "z"];
    let project = |p: &[f64; 3]| (p[a], p[b]);
    let build = |x: Range<f64>, y: Range<f64>| {
        ChartBuilder::on(map_area)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x, y)
    };
    // Building a chart without a caption draws nothing: a probe gives the plotting area's size.
    let pixels = build(0.0..1.0, 0.0..1.0)?.plotting_area().dim_in_pixel();
    let path: Vec<(f64, f64)> = figure.trajectory.iter().map(project).collect();
    let reference: Vec<(f64, f64)> = figure.reference.iter().map(project).collect();
    let all: Vec<(f64, f64)> = path.iter().chain(&reference).copied().collect();
    let (x_range, y_range) = equal_scale(&all, pixels);
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
    if !reference.is_empty() {
        chart.draw_series(DashedLineSeries::new(
            reference,
            6,
            4,
            REFERENCE_COLOUR.stroke_width(1),
        ))?;
    }
    chart.draw_series(LineSeries::new(path, TRAJECTORY_COLOUR.stroke_width(1)))?;
    chart.draw_series(
        placed
            .iter()
            .map(|(p, e)| Circle::new(project(p), 3, viridis(normalise(*e)).filled())),
    )?;
    Ok(())
}

/// The map in 3-D (evo's xyz mode): a cube of equal scales around every position.
fn space_map<DB: DrawingBackend>(
    map_area: &DrawingArea<DB, plotters::coord::Shift>,
    figure: &ErrorFigure,
    placed: &[([f64; 3], f64)],
    normalise: &dyn Fn(f64) -> f64,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let mut chart = space_chart(map_area, figure.trajectory.iter().chain(&figure.reference))?;
    let point = z_up;
    // Dashes: every other short run of the reference's segments.
    let reference: Vec<(f64, f64, f64)> = figure.reference.iter().map(point).collect();
    let dash = (reference.len() / 150).max(1);
    for run in reference.chunks(dash + 1).step_by(2) {
        chart.draw_series(LineSeries::new(
            run.to_vec(),
            REFERENCE_COLOUR.stroke_width(1),
        ))?;
    }
    chart.draw_series(LineSeries::new(
        figure.trajectory.iter().map(point),
        TRAJECTORY_COLOUR.stroke_width(1),
    ))?;
    chart.draw_series(
        placed
            .iter()
            .map(|(p, e)| Circle::new(point(p), 3, viridis(normalise(*e)).filled())),
    )?;
    Ok(())
}

/// The colour bar from `low` to `high`.
fn colour_bar<DB: DrawingBackend>(
    bar_area: &DrawingArea<DB, plotters::coord::Shift>,
    figure: &ErrorFigure,
    low: f64,
    high: f64,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let bar_range = if high > low {
        low..high
    } else {
        low - 0.5..low + 0.5
    };
    let bar_decimals = decimals(bar_range.end - bar_range.start);
    let mut bar = ChartBuilder::on(bar_area)
        .margin(10)
        .margin_right(28)
        .x_label_area_size(40)
        .right_y_label_area_size(72)
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

/// Several named trajectories in a plane (equal scales) or in 3-D, with a legend; dashed
/// ones in evo's reference style.
pub fn paths<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    mode: PlotMode,
    paths: &[Path3],
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    const NAMES: [&str; 3] = ["x", "y", "z"];
    match mode.axes() {
        Some([a, b]) => {
            let project = |p: &[f64; 3]| (p[a], p[b]);
            let build = |x: Range<f64>, y: Range<f64>| {
                ChartBuilder::on(area)
                    .margin(10)
                    .x_label_area_size(40)
                    .y_label_area_size(60)
                    .build_cartesian_2d(x, y)
            };
            let pixels = build(0.0..1.0, 0.0..1.0)?.plotting_area().dim_in_pixel();
            let all: Vec<(f64, f64)> = paths
                .iter()
                .flat_map(|p| p.points.iter().map(project))
                .collect();
            let (x_range, y_range) = equal_scale(&all, pixels);
            let d = decimals((x_range.end - x_range.start).max(y_range.end - y_range.start));
            let mut chart = build(x_range, y_range)?;
            chart
                .configure_mesh()
                .max_light_lines(1)
                .x_desc(format!("{} (m)", NAMES[a]))
                .y_desc(format!("{} (m)", NAMES[b]))
                .label_style(LABEL_FONT)
                .axis_desc_style(LABEL_FONT)
                .x_label_formatter(&|&x| tick(x, d))
                .y_label_formatter(&|&y| tick(y, d))
                .draw()?;
            for path in paths {
                let style = path.colour.stroke_width(if path.dashed { 1 } else { 2 });
                let points: Vec<(f64, f64)> = path.points.iter().map(project).collect();
                let series = if path.dashed {
                    chart.draw_series(DashedLineSeries::new(points, 6, 4, style))?
                } else {
                    chart.draw_series(LineSeries::new(points, style))?
                };
                series
                    .label(path.name.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
            }
            legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        }
        None => {
            let mut chart = space_chart(area, paths.iter().flat_map(|p| &p.points))?;
            for path in paths {
                let style = path.colour.stroke_width(if path.dashed { 1 } else { 2 });
                let points: Vec<(f64, f64, f64)> = path.points.iter().map(z_up).collect();
                let dash = if path.dashed {
                    (points.len() / 150).max(1)
                } else {
                    points.len().max(1)
                };
                let mut first = true;
                for run in points
                    .chunks(dash + 1)
                    .step_by(if path.dashed { 2 } else { 1 })
                {
                    let series = chart.draw_series(LineSeries::new(run.to_vec(), style))?;
                    if first {
                        series.label(path.name.as_str()).legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], style)
                        });
                        first = false;
                    }
                }
            }
            legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        }
    }
    Ok(())
}

/// A 3-D chart on `area` over a cube around `points`, seen from above at an angle, its
/// axes drawn.
fn space_chart<'a, 'b, DB: DrawingBackend + 'a>(
    area: &'a DrawingArea<DB, plotters::coord::Shift>,
    points: impl Iterator<Item = &'b [f64; 3]>,
) -> DrawResult<
    ChartContext<
        'a,
        DB,
        plotters::coord::cartesian::Cartesian3d<
            plotters::coord::types::RangedCoordf64,
            plotters::coord::types::RangedCoordf64,
            plotters::coord::types::RangedCoordf64,
        >,
    >,
>
where
    DB::ErrorType: 'static,
{
    let ([rx, ry, rz], d) = cube(points);
    let ranges = [rx.clone(), ry.clone(), rz.clone()];
    // z up, as evo (matplotlib) draws it: plotters' vertical axis is its second, so it
    // holds z; its first holds y and its depth axis x, a cyclic exchange that keeps the
    // axes right-handed on screen (points go through [`z_up`]).
    let mut chart = ChartBuilder::on(area)
        .margin(20)
        .margin_left(45)
        .margin_bottom(45)
        .build_cartesian_3d(ry, rz, rx)?;
    chart.with_projection(|mut p| {
        p.pitch = 0.45;
        p.yaw = 0.6 - std::f64::consts::FRAC_PI_2;
        p.scale = 0.85;
        p.into_matrix()
    });
    chart
        .configure_axes()
        .label_style(LABEL_FONT)
        .max_light_lines(1)
        .x_formatter(&|&x| tick(x, d))
        .y_formatter(&|&y| tick(y, d))
        .z_formatter(&|&z| tick(z, d))
        .draw()?;
    axis_labels(area, &chart, &ranges)?;
    Ok(chart)
}

/// A point in plotters' 3-D coordinates with z up: (y, z, x).
fn z_up(p: &[f64; 3]) -> (f64, f64, f64) {
    (p[1], p[2], p[0])
}

/// evo's axis labels of a 3-D plot, `x (m)`, `y (m)`, `z (m)`: each beside the middle of
/// its axis's lowest (for z: leftmost) edge on screen, pushed away from the cube's centre.
fn axis_labels<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    chart: &ChartContext<
        '_,
        DB,
        plotters::coord::cartesian::Cartesian3d<
            plotters::coord::types::RangedCoordf64,
            plotters::coord::types::RangedCoordf64,
            plotters::coord::types::RangedCoordf64,
        >,
    >,
    ranges: &[Range<f64>; 3],
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let base = area.get_base_pixel();
    let screen = |p: [f64; 3]| {
        let (x, y) = plotters::coord::CoordTranslate::translate(chart.as_coord_spec(), &z_up(&p));
        (f64::from(x - base.0), f64::from(y - base.1))
    };
    let ends = |k: usize| [ranges[k].start, ranges[k].end];
    let centre = screen([0, 1, 2].map(|k| (ranges[k].start + ranges[k].end) / 2.0));
    let style = TextStyle::from(LABEL_FONT.into_font()).pos(Pos::new(HPos::Center, VPos::Center));
    for (axis, name) in ["x (m)", "y (m)", "z (m)"].into_iter().enumerate() {
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        // The middles of the four edges parallel to this axis.
        let middles = ends(a).into_iter().flat_map(|va| {
            ends(b).into_iter().map(move |vb| {
                let mut p = [0.0; 3];
                p[axis] = (ranges[axis].start + ranges[axis].end) / 2.0;
                (p[a], p[b]) = (va, vb);
                p
            })
        });
        let key = |m: &(f64, f64)| if axis == 2 { -m.0 } else { m.1 };
        let Some(middle) = middles.map(screen).max_by(|m, n| key(m).total_cmp(&key(n))) else {
            continue;
        };
        let (dx, dy) = (middle.0 - centre.0, middle.1 - centre.1);
        let length = dx.hypot(dy).max(1.0);
        let at = (
            (middle.0 + 40.0 * dx / length) as i32,
            (middle.1 + 40.0 * dy / length) as i32,
        );
        area.draw(&Text::new(name, at, style.clone()))?;
    }
    Ok(())
}

/// The legend of a chart's labelled series, on a translucent white box.
pub fn legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(LABEL_FONT)
        .draw()?;
    Ok(())
}

/// A cube of equal sides around `points` (10 % margin) for 3-D plots, and tick decimals.
fn cube<'a>(points: impl Iterator<Item = &'a [f64; 3]>) -> ([Range<f64>; 3], usize) {
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
    use clap::ValueEnum;

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
        assert_eq!(PlotMode::Xz.axes(), Some([0, 2]));
        assert_eq!(PlotMode::Zy.axes(), Some([2, 1]));
        assert_eq!(PlotMode::Xyz.axes(), None);
        assert_eq!(
            PlotMode::from_str("yx", false).map(PlotMode::axes),
            Ok(Some([1, 0]))
        );
    }
}
