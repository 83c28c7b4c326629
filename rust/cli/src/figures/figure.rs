//! The figure model shared by the figure builders (`figures`, `traj`, `res`, `estimate`), the
//! drawing (`plot`, `panels`) and the files (`canvas`): what a figure shows, no drawing. A
//! leaf module: it uses nothing else of the crate.

use plotters::style::RGBColor;

/// evo's colour cycle (seaborn "deep"), for several trajectories or results.
pub const PALETTE: [RGBColor; 6] = [
    RGBColor(0x4C, 0x72, 0xB0),
    RGBColor(0xDD, 0x84, 0x52),
    RGBColor(0x55, 0xA8, 0x68),
    RGBColor(0xC4, 0x4E, 0x52),
    RGBColor(0x81, 0x72, 0xB3),
    RGBColor(0x93, 0x78, 0x60),
];

/// Plane of the trajectory panel: horizontal axis, then vertical axis; or 3-D.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
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
    /// 3-D, x, y and z (evo's default).
    Xyz,
}

impl PlotMode {
    /// Indices of the horizontal and the vertical coordinate (`None` for 3-D).
    pub fn axes(self) -> Option<[usize; 2]> {
        match self {
            PlotMode::Xy => Some([0, 1]),
            PlotMode::Xz => Some([0, 2]),
            PlotMode::Yz => Some([1, 2]),
            PlotMode::Zx => Some([2, 0]),
            PlotMode::Zy => Some([2, 1]),
            PlotMode::Yx => Some([1, 0]),
            PlotMode::Xyz => None,
        }
    }
}

/// One error to draw: where on the x-axis, where on the trajectory, and how large.
pub struct Sample {
    /// Position on the x-axis of the error panel (seconds from start, index or metres).
    pub x: f64,
    /// Position (m) on the coloured trajectory; `None`: not drawn on the trajectory panel.
    pub position: Option<[f64; 3]>,
    /// The error.
    pub error: f64,
}

/// What the error figure shows.
pub struct ErrorFigure {
    /// Title above the panels.
    pub title: String,
    /// Name of the error ("APE", "RPE", "estimated error").
    pub metric: &'static str,
    /// Unit of the error ("m", "deg", "rad", or "" for full transformations).
    pub unit: String,
    /// Label of the error panel's x-axis.
    pub x_label: String,
    /// Horizontal lines with a legend on the error panel (`("mean", value)`, …).
    pub lines: Vec<(&'static str, f64)>,
    /// A band (low, high) drawn behind the error, labelled "std" (evo: mean ± std/2).
    pub std_band: Option<(f64, f64)>,
    /// Name of the dashed trajectory (the reference), if any.
    pub reference_name: String,
    /// Every position (m) of the dashed reference; empty: none.
    pub reference: Vec<[f64; 3]>,
    /// Name of the trajectory carrying the coloured errors ("estimate", "trial 0").
    pub trajectory_name: String,
    /// Every position (m) of that trajectory, drawn as a grey line under the dots.
    pub trajectory: Vec<[f64; 3]>,
    /// The errors, in order; non-finite ones are left out of both panels.
    pub samples: Vec<Sample>,
    /// Colour-map limits (default: the smallest and largest error drawn).
    pub colour_range: Option<(f64, f64)>,
}

/// Size of the two-panel figure, pixels.
pub const SIZE: (u32, u32) = (1000, 1150);
/// Size of one evo figure ("raw", "map"), pixels.
pub const PAGE: (u32, u32) = (1000, 760);

/// The result of drawing.
pub type DrawResult<T> = Result<T, Box<dyn std::error::Error>>;
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
    /// A circle on every point (the KITTI devkit's `linespoints`).
    pub markers: bool,
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
        /// Every y-axis from 0, with room above the largest value for the legend (the KITTI
        /// devkit's error plots); otherwise around the values.
        y_from_zero: bool,
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
    /// The distribution of each result's values (evo_res's histogram, box and violin plots).
    Distributions {
        /// Title.
        title: String,
        /// Label of the values (`APE (m)`).
        label: String,
        /// How the distributions are drawn.
        kind: DistributionKind,
        /// (result name, values) per result.
        groups: Vec<(String, Vec<f64>)>,
    },
}

/// How evo_res draws distributions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DistributionKind {
    /// One density histogram with its kernel density line per result, side by side
    /// (seaborn's `distplot` on a `FacetGrid`).
    Histogram,
    /// A box per result: quartiles, median, whiskers within 1.5 IQR, outliers.
    Box,
    /// A violin per result: the mirrored kernel density with the box inside.
    Violin,
}

#[cfg(test)]
mod tests {
    use clap::ValueEnum;

    use super::*;

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
