//! `sitar evaluate`'s figure (`--plot`): accuracy and F1 against the trial count per
//! setting (the paper's Figure 5), as SVG.

use std::path::Path;

use anyhow::Result;
use plotters::prelude::*;
use sitar_estimator::{PAPER_CLASSIFIERS, Setting, Thresholds};

use crate::analysis::evaluate::table::cm;

/// One point of Figure 5.
pub(super) struct PlotRow {
    pub(super) boundaries: Thresholds,
    pub(super) setting: Setting,
    pub(super) trials: usize,
    pub(super) accuracy: f64,
    pub(super) macro_f1: f64,
}

/// The paper's Figure 5: per class-boundary setting, accuracy (left) and F1 (right) against
/// the number of trials, one line per setting.
pub(super) fn plot(
    path: &Path,
    rows: &[PlotRow],
    settings: &[Setting],
    counts: &[usize],
) -> Result<()> {
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::new(path, (1100, 1200)).into_drawing_area();
        root.fill(&WHITE)?;
        let (title, body) = root.split_vertically(40);
        title.titled(
            "SiTAR uncertainty-based pose error estimation vs ground truth",
            ("sans-serif", 22),
        )?;
        let panels = body.split_evenly((PAPER_CLASSIFIERS.len(), 2));
        let x_max = counts.iter().copied().max().unwrap_or(2) as f64;
        let x_min = counts.iter().copied().min().unwrap_or(2) as f64;
        let x_range = if x_max > x_min {
            x_min..x_max
        } else {
            x_min - 1.0..x_max + 1.0
        };
        // A common y range for all panels, like the paper's, zoomed to the data.
        let lowest = rows
            .iter()
            .flat_map(|r| [r.accuracy, r.macro_f1])
            .filter(|v| v.is_finite())
            .fold(1.0f64, f64::min);
        let y_min = ((lowest - 0.05) * 10.0).floor().max(0.0) / 10.0;
        for (row, bounds) in PAPER_CLASSIFIERS.iter().enumerate() {
            for (col, metric) in ["accuracy", "F1"].iter().enumerate() {
                let value = |r: &PlotRow| if col == 0 { r.accuracy } else { r.macro_f1 };
                let mut chart = ChartBuilder::on(&panels[row * 2 + col])
                    .caption(
                        format!("{metric}, boundaries {}", cm(bounds)),
                        ("sans-serif", 16),
                    )
                    .margin(10)
                    .x_label_area_size(35)
                    .y_label_area_size(45)
                    .build_cartesian_2d(x_range.clone(), y_min..1.0)?;
                chart
                    .configure_mesh()
                    .max_light_lines(1)
                    .x_desc("trials")
                    .y_desc(*metric)
                    .x_label_formatter(&|x| format!("{x:.0}"))
                    .y_label_formatter(&|y| format!("{y:.2}"))
                    .draw()?;
                for (i, setting) in settings.iter().enumerate() {
                    let colour = Palette99::pick(i).to_rgba();
                    let points: Vec<(f64, f64)> = rows
                        .iter()
                        .filter(|r| r.boundaries == *bounds && r.setting == *setting)
                        .map(|r| (r.trials as f64, value(r)))
                        .filter(|(_, v)| v.is_finite())
                        .collect();
                    chart
                        .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))?
                        .label(setting.to_string())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                        });
                    chart
                        .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
                }
                if row == 0 && col == 1 {
                    chart
                        .configure_series_labels()
                        .position(SeriesLabelPosition::LowerRight)
                        .background_style(WHITE.mix(0.8))
                        .border_style(BLACK)
                        .draw()?;
                }
            }
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| anyhow::anyhow!("{}: cannot draw the plot: {e}", path.display()))
}
