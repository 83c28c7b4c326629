//! The figures of `ape`, `rpe`, `traj` and `res`, as evo draws them: what goes on them is
//! decided here, the drawing itself is in `plot.rs` and the file formats in `canvas.rs`.

use anyhow::Result;
use plotters::prelude::*;

use crate::canvas::{self, Page};
use crate::console::Console;
use crate::metric::{Metric, Outcome};
use crate::metric_args::{OutputArgs, XDimension};
use crate::plot::{DrawResult, ErrorFigure, PAGE, PlotMode, SIZE, Sample};

/// evo's colour cycle (seaborn "deep"), for several trajectories or results.
pub const PALETTE: [RGBColor; 6] = [
    RGBColor(0x4C, 0x72, 0xB0),
    RGBColor(0xDD, 0x84, 0x52),
    RGBColor(0x55, 0xA8, 0x68),
    RGBColor(0xC4, 0x4E, 0x52),
    RGBColor(0x81, 0x72, 0xB3),
    RGBColor(0x93, 0x78, 0x60),
];

/// The error figure of a metric outcome, with evo's x dimension and colour-map limits.
pub fn error_figure(outcome: &Outcome, output: &OutputArgs) -> Result<ErrorFigure> {
    let archive_like = outcome.archive();
    let array = |name: &str| archive_like.array(name).map(|a| a.data.clone());
    let n = outcome.errors.errors.len();
    let (xs, x_label) = match (output.plot_x_dimension, outcome.timed) {
        (XDimension::Distances, true) => (array("distances_from_start"), "d (m)"),
        (XDimension::Seconds, true) => (array("seconds_from_start"), "t (s)"),
        _ => (None, "index"),
    };
    let xs = xs.unwrap_or_else(|| (0..n).map(|i| i as f64).collect());
    let positions = outcome.error_positions();
    let stats = &outcome.stats;
    let mut high = output.plot_colormap_max.unwrap_or(stats.max);
    if let Some(p) = output.plot_colormap_max_percentile {
        if !(0.0..=100.0).contains(&p) {
            anyhow::bail!("--plot_colormap_max_percentile must be within [0, 100], got {p}");
        }
        high = percentile(&outcome.errors.errors, p);
    }
    let low = output.plot_colormap_min.unwrap_or(stats.min);
    let reference = outcome
        .reference_full
        .as_ref()
        .filter(|_| output.plot_full_ref)
        .unwrap_or(&outcome.reference);
    Ok(ErrorFigure {
        title: outcome.title.clone(),
        metric: outcome.metric.name(),
        unit: outcome.unit.clone(),
        x_label: x_label.to_owned(),
        lines: vec![
            ("rmse", stats.rmse),
            ("median", stats.median),
            ("mean", stats.mean),
        ],
        std_band: Some((stats.mean - stats.std, stats.mean + stats.std)),
        reference_name: "reference".into(),
        reference: reference.positions.iter().map(|p| p.to_array()).collect(),
        trajectory_name: match outcome.metric {
            Metric::Ape(_) => "estimate".into(),
            Metric::Rpe(_) => "estimate (each pair's end pose)".into(),
        },
        trajectory: outcome
            .estimate
            .positions
            .iter()
            .map(|p| p.to_array())
            .collect(),
        samples: outcome
            .errors
            .errors
            .iter()
            .zip(xs)
            .zip(positions)
            .map(|((&error, x), position)| Sample {
                x,
                position: Some(position),
                error,
            })
            .collect(),
        colour_range: Some((low, high)),
    })
}

/// numpy's default percentile (linear interpolation between closest ranks).
pub fn percentile(values: &[f64], p: f64) -> f64 {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| !v.is_nan()).collect();
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted.sort_by(f64::total_cmp);
    let rank = p / 100.0 * (sorted.len() - 1) as f64;
    let (k, f) = (rank.floor() as usize, rank - rank.floor());
    let next = sorted[(k + 1).min(sorted.len() - 1)];
    sorted[k] + f * (next - sorted[k])
}

/// SiTAR's `--plot FILE` of `ape`/`rpe`: both panels in one file.
pub fn single_file(outcome: &Outcome, output: &OutputArgs, console: &Console) -> Result<()> {
    let Some(path) = output.plot.as_ref().filter(|p| !p.is_empty()) else {
        return Ok(());
    };
    let figure = error_figure(outcome, output)?;
    let path = std::path::Path::new(path);
    canvas::save_one(path, SIZE, &Page::Both(&figure, output.plot_mode))?;
    console.debug(&format!("Plot saved to {}", path.display()))
}

/// evo's `-p` and `--save_plot` of `ape`/`rpe`: the "raw" and "map" figures.
pub fn collection(outcome: &Outcome, output: &OutputArgs, console: &Console) -> Result<()> {
    let show = output.plot.as_ref().is_some_and(|p| p.is_empty());
    if !show && output.save_plot.is_none() {
        return Ok(());
    }
    let figure = error_figure(outcome, output)?;
    let pages = [
        ("raw", Page::Raw(&figure)),
        ("map", Page::Map(&figure, output.plot_mode)),
    ];
    if show {
        canvas::show(PAGE, &pages, console)?;
    }
    if let Some(path) = &output.save_plot {
        for file in canvas::save_collection(path, PAGE, &pages)? {
            console.info(&format!("Plot saved to {}", file.display()))?;
        }
    }
    Ok(())
}

/// A named line of a figure.
pub struct Series {
    /// Legend name.
    pub name: String,
    /// Points.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub colour: RGBColor,
    /// Dashed (evo's reference style).
    pub dashed: bool,
}

/// A named 3-D path of a trajectory figure.
pub struct Path3 {
    /// Legend name.
    pub name: String,
    /// Positions (m).
    pub points: Vec<[f64; 3]>,
    /// Colour.
    pub colour: RGBColor,
    /// Dashed (the reference).
    pub dashed: bool,
}

/// Figures other than the error figure.
pub enum Drawing {
    /// Stacked panels of lines over a shared x-axis (evo_traj's xyz, rpy and speed plots,
    /// evo_res's raw plot).
    Panels {
        /// Title.
        title: String,
        /// x-axis label.
        x_label: String,
        /// (y-axis label, lines) per panel, top to bottom.
        panels: Vec<(String, Vec<Series>)>,
    },
    /// Trajectories in a plane or in 3-D (evo_traj's trajectory plot).
    Trajectories {
        /// Title.
        title: String,
        /// Plane or 3-D.
        mode: PlotMode,
        /// The paths.
        paths: Vec<Path3>,
    },
    /// Horizontal bars per statistic, one per result (evo_res's stats plot).
    Bars {
        /// Title.
        title: String,
        /// x-axis label (the metric's unit).
        x_label: String,
        /// Statistic names (rows).
        groups: Vec<String>,
        /// (result name, one value per group).
        series: Vec<(String, Vec<f64>)>,
    },
}

impl Drawing {
    /// Draws the figure on `root`.
    pub fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, plotters::coord::Shift>,
    ) -> DrawResult<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        match self {
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
    let mut chart = ChartBuilder::on(area)
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(xs, ys)?;
    chart
        .configure_mesh()
        .max_light_lines(1)
        .x_desc(x_label)
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
    let names = groups.to_vec();
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(rows)
        .y_label_formatter(&move |y| {
            let k = (*y - 0.5).round();
            if (y - 0.5 - k).abs() < 1e-6 && k >= 0.0 {
                names.get(k as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .x_desc(x_label)
        .label_style(("sans-serif", 12))
        .draw()?;
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
