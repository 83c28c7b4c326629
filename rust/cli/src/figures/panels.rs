//! The drawing of the figures other than the error figure ([`Drawing`]): evo_traj's and
//! evo_res's stacked line panels, trajectory plots, statistics bars and distributions
//! (histograms, boxes, violins).

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::figures::distribution::{
    box_stats, histogram, histogram_bins, kde, kde_bandwidth, min_max,
};
use crate::figures::figure::{
    DistributionKind, DrawResult, Drawing, PALETTE, Path3, PlotMode, Series,
};

/// Draws `drawing` on `root`.
pub fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    drawing: &Drawing,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    match drawing {
        Drawing::Panels {
            title,
            x_label,
            panels,
            y_from_zero,
        } => {
            let (top, body) = root.split_vertically(50);
            crate::figures::plot::title_lines(&top, title)?;
            let areas = body.split_evenly((panels.len().max(1), 1));
            for (area, (y_label, series)) in areas.iter().zip(panels) {
                lines_panel(area, x_label, y_label, series, *y_from_zero)?;
            }
            Ok(())
        }
        Drawing::Trajectories { title, mode, paths } => {
            let (top, body) = root.split_vertically(50);
            crate::figures::plot::title_lines(&top, title)?;
            trajectories_panel(&body, *mode, paths)
        }
        Drawing::Bars {
            title,
            x_label,
            groups,
            series,
        } => {
            let (top, body) = root.split_vertically(50);
            crate::figures::plot::title_lines(&top, title)?;
            bars_panel(&body, x_label, groups, series)
        }
        Drawing::Distributions {
            title,
            label,
            kind,
            groups,
        } => {
            let (top, body) = root.split_vertically(50);
            crate::figures::plot::title_lines(&top, title)?;
            match kind {
                DistributionKind::Histogram => histograms(&body, label, groups),
                DistributionKind::Box | DistributionKind::Violin => {
                    boxes_or_violins(&body, label, *kind, groups)
                }
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
    y_from_zero: bool,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let xs = span(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
    let mut ys = span(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
    if y_from_zero {
        let top = series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        ys = 0.0..if top > 0.0 { top * 1.25 } else { 1.0 };
    }
    // Absolute Unix seconds: ticks relative to an offset named in the label, as evo's.
    let offset = crate::figures::plot::axes::axis_offset(&xs);
    let x_decimals = crate::figures::plot::axes::decimals(xs.end - xs.start);
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
        .x_label_formatter(&|x| crate::figures::plot::axes::tick(x - offset, x_decimals))
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
        if s.markers {
            chart.draw_series(
                s.points
                    .iter()
                    .map(|&p| Circle::new(p, 3, s.colour.stroke_width(1))),
            )?;
        }
    }
    crate::figures::plot::paths::legend(&mut chart, SeriesLabelPosition::UpperRight)?;
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
    crate::figures::plot::paths::paths(area, mode, paths)
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
    crate::figures::plot::paths::legend(&mut chart, SeriesLabelPosition::LowerRight)?;
    Ok(())
}

/// Font of the distribution figures' labels.
const DISTRIBUTION_FONT: (&str, u32) = ("sans-serif", 13);

/// evo_res's histogram figure: per result a panel (shared axes, seaborn's `FacetGrid`)
/// titled `estimate = NAME`, its density histogram (seaborn's bins) and kernel density line.
fn histograms<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    label: &str,
    groups: &[(String, Vec<f64>)],
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let all: Vec<f64> = groups.iter().flat_map(|g| g.1.iter().copied()).collect();
    let xs = span(all.iter().copied());
    let grid: Vec<f64> = (0..=200)
        .map(|k| xs.start + (xs.end - xs.start) * f64::from(k) / 200.0)
        .collect();
    // Per result: its histogram's (left, right, density) bins and its density line.
    type Drawn = (Vec<(f64, f64, f64)>, Vec<f64>);
    let drawn: Vec<Drawn> = groups
        .iter()
        .map(|(_, values)| {
            let bins = histogram(values, histogram_bins(values));
            (bins, kde(values, &grid))
        })
        .collect();
    let top = drawn
        .iter()
        .flat_map(|(bins, line)| bins.iter().map(|b| b.2).chain(line.iter().copied()))
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let colour = PALETTE[0];
    let facets = area.split_evenly((1, groups.len().max(1)));
    for (facet, ((name, _), (bins, line))) in facets.iter().zip(groups.iter().zip(&drawn)) {
        let mut chart = ChartBuilder::on(facet)
            .margin(10)
            .caption(format!("estimate = {name}"), DISTRIBUTION_FONT)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(xs.clone(), 0.0..(top * 1.05).max(1e-12))?;
        let x_decimals = crate::figures::plot::axes::decimals(xs.end - xs.start);
        chart
            .configure_mesh()
            .max_light_lines(1)
            .x_labels(5)
            .x_label_formatter(&|x| crate::figures::plot::axes::tick(*x, x_decimals))
            .x_desc(label)
            .y_desc("Density")
            .label_style(("sans-serif", 12))
            .axis_desc_style(DISTRIBUTION_FONT)
            .draw()?;
        chart.draw_series(
            bins.iter()
                .map(|&(l, r, d)| Rectangle::new([(l, 0.0), (r, d)], colour.mix(0.4).filled())),
        )?;
        if !line.is_empty() {
            chart.draw_series(LineSeries::new(
                grid.iter().copied().zip(line.iter().copied()),
                colour.stroke_width(2),
            ))?;
        }
    }
    Ok(())
}

/// evo_res's box or violin figure: per result, at x = its index, matplotlib's box (or the
/// mirrored kernel density, cut 2 bandwidths beyond the values as seaborn's, with the box
/// inside), the results' names under the axis.
fn boxes_or_violins<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    label: &str,
    kind: DistributionKind,
    groups: &[(String, Vec<f64>)],
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let violin = kind == DistributionKind::Violin;
    // Each violin's outline: (value, half width) from the density, widest at 0.4.
    let outlines: Vec<Vec<(f64, f64)>> = groups
        .iter()
        .map(|(_, values)| {
            let (Some(h), true) = (kde_bandwidth(values), violin) else {
                return Vec::new();
            };
            let (low, high) = min_max(values);
            let at: Vec<f64> = (0..=100)
                .map(|k| low - 2.0 * h + (high - low + 4.0 * h) * f64::from(k) / 100.0)
                .collect();
            let density = kde(values, &at);
            let widest = density.iter().copied().fold(0.0f64, f64::max).max(1e-300);
            at.into_iter()
                .zip(density.iter().map(|d| 0.4 * d / widest))
                .collect()
        })
        .collect();
    let ys = span(
        groups
            .iter()
            .flat_map(|g| g.1.iter().copied())
            .chain(outlines.iter().flatten().map(|p| p.0)),
    );
    let n = groups.len().max(1);
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .margin_bottom(30)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.5..n as f64 - 0.5, ys.clone())?;
    let y_decimals = crate::figures::plot::axes::decimals(ys.end - ys.start);
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_label_formatter(&|y| crate::figures::plot::axes::tick(*y, y_decimals))
        .y_desc(label)
        .x_desc("estimate")
        .label_style(("sans-serif", 12))
        .axis_desc_style(DISTRIBUTION_FONT)
        .draw()?;
    let base = area.get_base_pixel();
    let name_style =
        TextStyle::from(DISTRIBUTION_FONT.into_font()).pos(Pos::new(HPos::Center, VPos::Top));
    let dark = RGBColor(0x44, 0x44, 0x44);
    for (i, ((name, values), outline)) in groups.iter().zip(&outlines).enumerate() {
        let x = i as f64;
        let (px, py) = chart.backend_coord(&(x, ys.start));
        area.draw(&Text::new(
            name.clone(),
            (px - base.0, py - base.1 + 8),
            name_style.clone(),
        ))?;
        let Some(b) = box_stats(values) else {
            continue;
        };
        let colour = PALETTE[0];
        if violin {
            let shape: Vec<(f64, f64)> = outline
                .iter()
                .map(|&(y, w)| (x - w, y))
                .chain(outline.iter().rev().map(|&(y, w)| (x + w, y)))
                .collect();
            chart.draw_series(std::iter::once(Polygon::new(
                shape.clone(),
                colour.filled(),
            )))?;
            chart.draw_series(std::iter::once(PathElement::new(
                shape,
                dark.stroke_width(1),
            )))?;
            // seaborn's inner box: the whiskers thin, the quartiles thick, the median white.
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(x, b.low), (x, b.high)],
                dark.stroke_width(2),
            )))?;
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(x, b.q1), (x, b.q3)],
                dark.stroke_width(7),
            )))?;
            chart.draw_series(std::iter::once(Circle::new(
                (x, b.median),
                2,
                WHITE.filled(),
            )))?;
        } else {
            let (l, r) = (x - 0.4, x + 0.4);
            chart.draw_series(std::iter::once(Rectangle::new(
                [(l, b.q1), (r, b.q3)],
                colour.filled(),
            )))?;
            chart.draw_series(std::iter::once(Rectangle::new(
                [(l, b.q1), (r, b.q3)],
                dark.stroke_width(1),
            )))?;
            for segment in [
                vec![(l, b.median), (r, b.median)],
                vec![(x, b.q1), (x, b.low)],
                vec![(x, b.q3), (x, b.high)],
                vec![(x - 0.2, b.low), (x + 0.2, b.low)],
                vec![(x - 0.2, b.high), (x + 0.2, b.high)],
            ] {
                chart.draw_series(std::iter::once(PathElement::new(
                    segment,
                    dark.stroke_width(2),
                )))?;
            }
            chart.draw_series(
                b.outliers
                    .iter()
                    .map(|&v| Circle::new((x, v), 3, dark.stroke_width(1))),
            )?;
        }
    }
    Ok(())
}
