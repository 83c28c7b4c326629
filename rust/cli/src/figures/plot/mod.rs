//! The error figure of `sitar rpe`, `ape` and `estimate` (`--plot FILE.svg`), after evo's
//! `--plot`: the error over time above, the trajectory seen from above and coloured by error
//! below (evo's colour-mapped `--plot_mode` plot), as SVG.

pub mod axes;
mod error_panels;
pub mod paths;
mod style;

use std::path::PathBuf;

use plotters::prelude::*;

use crate::figures::figure::{DrawResult, ErrorFigure, PlotMode};
use crate::figures::plot::error_panels::{error_over_time, trajectory_by_error};
use crate::figures::plot::style::ERROR_PANEL_HEIGHT;

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
