//! Named trajectories drawn together (evo's trajectory plots), with axis labels and legend.

use std::ops::Range;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::figures::figure::{DrawResult, Path3, PlotMode};
use crate::figures::plot::axes::{cube, decimals, equal_scale, tick};
use crate::figures::plot::style::LABEL_FONT;

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
pub(super) fn space_chart<'a, 'b, DB: DrawingBackend + 'a>(
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
pub(super) fn z_up(p: &[f64; 3]) -> (f64, f64, f64) {
    (p[1], p[2], p[0])
}

/// evo's axis labels of a 3-D plot, `x (m)`, `y (m)`, `z (m)`: each beside the middle of
/// its axis's lowest (for z: leftmost) edge on screen, pushed away from the cube's centre.
pub(super) fn axis_labels<DB: DrawingBackend>(
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
