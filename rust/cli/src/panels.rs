//! The drawing of the figures other than the error figure ([`Drawing`]): evo_traj's and
//! evo_res's stacked line panels, trajectory plots and statistics bars.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::figure::{DrawResult, Drawing, PALETTE, Path3, PlotMode, Series};

/// Draws `drawing` on `root`.
pub fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    drawing: &Drawing,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    {
        root.fill(&WHITE)?;
        match drawing {
            Drawing::Panels {
                title,
                x_label,
                panels,
            } => {
                let (top, body) = root.split_vertically(50);
                crate::plot::title_lines(&top, title)?;
                let areas = body.split_evenly((panels.len().max(1), 1));
                for (area, (y_label, series)) in areas.iter().zip(panels) {
                    lines_panel(area, x_label, y_label, series)?;
                }
                Ok(())
            }
            Drawing::Trajectories { title, mode, paths } => {
                let (top, body) = root.split_vertically(50);
                crate::plot::title_lines(&top, title)?;
                trajectories_panel(&body, *mode, paths)
            }
            Drawing::Bars {
                title,
                x_label,
                groups,
                series,
            } => {
                let (top, body) = root.split_vertically(50);
                crate::plot::title_lines(&top, title)?;
                bars_panel(&body, x_label, groups, series)
            }
        }
    }
}

fn span(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if lo > hi {
        return 0.0..1.0;
    }
    let pad = ((hi - lo) * 0.05).max(1e-9);
    lo - pad..hi + pad
}

fn lines_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let xs = span(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
    let ys = span(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
    // Absolute Unix seconds: ticks relative to an offset named in the label, as evo's.
    let offset = crate::plot::axis_offset(&xs);
    let x_decimals = crate::plot::decimals(xs.end - xs.start);
    let x_desc = if offset == 0.0 {
        x_label.to_owned()
    } else {
        format!("{x_label} + {offset}")
    };
    let mut chart = ChartBuilder::on(area)
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(xs, ys)?;
    chart
        .configure_mesh()
        .max_light_lines(1)
        .x_label_formatter(&|x| crate::plot::tick(x - offset, x_decimals))
        .x_desc(x_desc)
        .y_desc(y_label)
        .label_style(("sans-serif", 12))
        .axis_desc_style(("sans-serif", 12))
        .draw()?;
    for s in series {
        let style = s.colour.stroke_width(1);
        if s.dashed {
            chart
                .draw_series(DashedLineSeries::new(s.points.clone(), 6, 4, style))?
                .label(s.name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        } else {
            chart
                .draw_series(LineSeries::new(s.points.clone(), style))?
                .label(s.name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        }
    }
    crate::plot::legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    Ok(())
}

fn trajectories_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    mode: PlotMode,
    paths: &[Path3],
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    crate::plot::paths(area, mode, paths)
}

fn bars_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    x_label: &str,
    groups: &[String],
    series: &[(String, Vec<f64>)],
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let max = series
        .iter()
        .flat_map(|s| s.1.iter().copied())
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let rows = groups.len().max(1);
    let per = series.len().max(1);
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..(max * 1.1).max(1e-12), 0.0..rows as f64)?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(0)
        .x_desc(x_label)
        .label_style(("sans-serif", 12))
        .draw()?;
    // The statistic's name left of its group of bars (evo's category labels): plotters'
    // own ticks fall where its tick rule puts them, not at the groups' centres.
    let base = area.get_base_pixel();
    let label =
        TextStyle::from(("sans-serif", 13).into_font()).pos(Pos::new(HPos::Right, VPos::Center));
    for (g, name) in groups.iter().enumerate() {
        let (x, y) = chart.backend_coord(&(0.0, g as f64 + 0.5));
        area.draw(&Text::new(
            name.clone(),
            (x - base.0 - 8, y - base.1),
            label.clone(),
        ))?;
    }
    for (s, (name, values)) in series.iter().enumerate() {
        let colour = PALETTE[s % PALETTE.len()];
        let h = 0.8 / per as f64;
        chart
            .draw_series(values.iter().enumerate().map(|(g, &v)| {
                let y0 = g as f64 + 0.1 + s as f64 * h;
                Rectangle::new([(0.0, y0), (v.max(0.0), y0 + h)], colour.filled())
            }))?
            .label(name.as_str())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], colour.filled()));
    }
    crate::plot::legend(&mut chart, SeriesLabelPosition::LowerRight)?;
    Ok(())
}
