//! The error figure's panels: the error over time with its statistics, and the trajectory
//! coloured by error (in a plane or in 3-D) with its colour bar.

use std::ops::Range;

use plotters::prelude::*;

use crate::figures::figure::{DrawResult, ErrorFigure, PlotMode, Sample};
use crate::figures::plot::axes::{decimals, equal_scale, padded, tick};
use crate::figures::plot::paths::{legend, space_chart, z_up};
use crate::figures::plot::style::{
    COLOUR_BAR_WIDTH, ERROR_COLOUR, LABEL_FONT, LINE_COLOURS, REFERENCE_COLOUR, TRAJECTORY_COLOUR,
    viridis,
};

/// The errors to draw: the finite ones.
pub(super) fn finite(figure: &ErrorFigure) -> Vec<&Sample> {
    figure
        .samples
        .iter()
        .filter(|s| s.error.is_finite())
        .collect()
}

/// `metric (unit)`, or the metric alone without a unit.
pub(super) fn with_unit(figure: &ErrorFigure) -> String {
    if figure.unit.is_empty() || figure.unit == "unit-less" {
        figure.metric.to_owned()
    } else {
        format!("{} ({})", figure.metric, figure.unit)
    }
}

/// Error panel: the error against the x dimension, the statistics lines, the std band.
pub(super) fn error_over_time<DB: DrawingBackend>(
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
pub(super) fn trajectory_by_error<DB: DrawingBackend>(
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
pub(super) fn plane_map<DB: DrawingBackend>(
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
pub(super) fn space_map<DB: DrawingBackend>(
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
pub(super) fn colour_bar<DB: DrawingBackend>(
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
