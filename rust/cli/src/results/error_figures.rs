//! The figures of `ape`, `rpe`, `traj` and `res`, as evo draws them: what goes on them is
//! decided here; the model is `figure.rs`, the drawing `plot/` and `panels.rs`, the file
//! formats `canvas.rs`.

use anyhow::Result;

use crate::figures::canvas::{self, Page};
use crate::figures::distribution::percentile;
use crate::figures::figure::{ErrorFigure, PAGE, SIZE, Sample};
use crate::io::console::Console;
use sitar_evo::metric::{Metric, Outcome};

use crate::results::archive::ResultArchive;
use crate::results::metric_args::{OutputArgs, XDimension};

/// The error figure of a metric outcome, with evo's x dimension and colour-map limits.
pub fn error_figure(outcome: &Outcome, output: &OutputArgs) -> Result<ErrorFigure> {
    let archive_like = ResultArchive::of(outcome);
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
        std_band: Some(std_band(stats.mean, stats.std)),
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

/// evo's "std" band of the raw plot: mean ± std/2 (the `axhspan` of evo's
/// `plot.error_array`), one std wide.
pub fn std_band(mean: f64, std: f64) -> (f64, f64) {
    (mean - std / 2.0, mean + std / 2.0)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_std_band_is_one_std_wide_around_the_mean() {
        assert_eq!(std_band(2.0, 1.0), (1.5, 2.5));
        assert_eq!(std_band(0.0, 0.0), (0.0, 0.0));
    }
}
