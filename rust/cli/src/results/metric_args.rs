//! The options `sitar ape` and `sitar rpe` share with `evo_ape`/`evo_rpe` (same names, short
//! forms and defaults; `-` spellings accepted too), plus SiTAR's extras (`--format`, `-o`).

use std::path::PathBuf;

use clap::ValueEnum;
use sitar_estimator::{GravityAxis, Plane};
use sitar_evo::AlgorithmOptions;

use crate::figures::figure::PlotMode;
use crate::io::output::OutputFormat;

/// evo's algorithm options of `ape` and `rpe` (the pose relation is per tool).
#[derive(clap::Args, Debug, Clone)]
pub struct AlgorithmArgs {
    /// Alignment with Umeyama's method (no scale).
    #[arg(short = 'a', long)]
    pub align: bool,
    /// Correct scale with Umeyama's method (alone: scale only; with -a: Sim(3)).
    #[arg(short = 's', long = "correct_scale", alias = "correct-scale")]
    pub correct_scale: bool,
    /// The number of poses to use for Umeyama alignment, counted from the start (-1: all).
    #[arg(long = "n_to_align", default_value_t = -1, allow_negative_numbers = true)]
    pub n_to_align: i64,
    /// SiTAR extra, with -a: 4-DoF alignment, a translation and a rotation about the
    /// gravity axis only (the least-squares yaw, as rpg_trajectory_evaluation's posyaw);
    /// --n_to_align counts as for -a. Cannot be combined with -s.
    #[arg(long = "yaw_only", alias = "yaw-only", requires = "align")]
    pub yaw_only: bool,
    /// SiTAR extra: the gravity (vertical) axis of the reference's world frame: z (ROS,
    /// EuRoC, TUM) or y (ARCore, Unity: gravity along -y); used by --yaw_only and by the
    /// direction relations of ape.
    #[arg(long = "yaw_axis", alias = "yaw-axis", value_enum, default_value_t = AxisArg::Z)]
    pub yaw_axis: AxisArg,
    /// SiTAR extra: estimate the constant time offset that --t_offset would need (s added
    /// to the estimate's stamps): the offset within ±--t_offset_range minimising the APE
    /// RMSE (translation) after the chosen alignment (SE(3) without -a), associated as evo
    /// at each offset; prints it on stderr and uses it (instead of --t_offset).
    #[arg(long = "estimate_t_offset", alias = "estimate-t-offset")]
    pub estimate_t_offset: bool,
    /// The search range (s) of --estimate_t_offset: offsets in [-S, S].
    #[arg(
        long = "t_offset_range",
        alias = "t-offset-range",
        default_value_t = 1.0,
        value_name = "S",
        requires = "estimate_t_offset"
    )]
    pub t_offset_range: f64,
    /// SiTAR extra: print on stderr how many estimate poses were paired with a reference pose
    /// and how many were dropped, and why (the JSON output always has it as "pairing").
    #[arg(long = "show_pairing", alias = "show-pairing")]
    pub show_pairing: bool,
    /// Align the trajectory origin to the origin of the reference trajectory.
    #[arg(
        long = "align_origin",
        alias = "align-origin",
        conflicts_with = "align"
    )]
    pub align_origin: bool,
    /// Changes the output unit of the metric, if possible.
    #[arg(long = "change_unit", value_enum)]
    pub change_unit: Option<ChangeUnit>,
    /// Projects the trajectories to 2D in the desired plane (after alignment).
    #[arg(long = "project_to_plane", value_enum)]
    pub project_to_plane: Option<PlaneArg>,
    /// Downsample trajectories to max N poses (before synchronisation).
    #[arg(long, value_name = "N")]
    pub downsample: Option<usize>,
    /// Filters out poses if the distance or angle to the previous one is below the
    /// threshold distance (m) or angle (degrees).
    #[arg(long = "motion_filter", num_args = 2, value_names = ["DISTANCE", "ANGLE_DEGREES"])]
    pub motion_filter: Option<Vec<f64>>,
}

impl AlgorithmArgs {
    /// The library's options.
    pub fn options(&self) -> AlgorithmOptions {
        AlgorithmOptions {
            align: self.align,
            correct_scale: self.correct_scale,
            n_to_align: self.n_to_align,
            yaw_only: self.yaw_only,
            yaw_axis: self.yaw_axis.axis(),
            estimate_t_offset: self.estimate_t_offset,
            t_offset_range: self.t_offset_range,
            show_pairing: self.show_pairing,
            align_origin: self.align_origin,
            change_unit: self.change_unit.map(ChangeUnit::unit),
            project_to_plane: self.project_to_plane.map(PlaneArg::plane),
            downsample: self.downsample,
            motion_filter: self
                .motion_filter
                .as_deref()
                .and_then(|f| Some([*f.first()?, *f.get(1)?])),
        }
    }
}

/// evo's output options of `ape` and `rpe`, and SiTAR's `--format`/`-o`.
#[derive(clap::Args, Debug, Clone)]
pub struct OutputArgs {
    /// Show the plot (evo's -p). On a machine without a display sitar says so and shows
    /// nothing. With a file (SiTAR's older `--plot FILE.svg`), writes the two panels there.
    #[arg(short = 'p', long, num_args = 0..=1, value_name = "FILE", default_missing_value = "")]
    pub plot: Option<String>,
    /// The axes for plot projection (xyz: 3-D).
    #[arg(long = "plot_mode", alias = "plot-mode", value_enum, default_value_t = PlotMode::Xyz)]
    pub plot_mode: PlotMode,
    /// Dimension on the x-axis of the raw value plot (index when there are no stamps).
    #[arg(long = "plot_x_dimension", value_enum, default_value_t = XDimension::Seconds)]
    pub plot_x_dimension: XDimension,
    /// The upper bound of the colour map (default: the maximum error).
    #[arg(long = "plot_colormap_max", allow_negative_numbers = true)]
    pub plot_colormap_max: Option<f64>,
    /// The lower bound of the colour map (default: the minimum error).
    #[arg(long = "plot_colormap_min", allow_negative_numbers = true)]
    pub plot_colormap_min: Option<f64>,
    /// Percentile (%) of the errors as the upper bound of the colour map (overrides
    /// --plot_colormap_max).
    #[arg(long = "plot_colormap_max_percentile")]
    pub plot_colormap_max_percentile: Option<f64>,
    /// Plot the full, unsynchronized reference trajectory.
    #[arg(long = "plot_full_ref")]
    pub plot_full_ref: bool,
    /// ROS map image yaml (not supported by sitar).
    #[arg(long = "ros_map_yaml", value_name = "FILE")]
    pub ros_map_yaml: Option<String>,
    /// Map tile layer (not supported by sitar).
    #[arg(long = "map_tile", value_name = "CRS")]
    pub map_tile: Option<String>,
    /// Path to save the plot: PNG, SVG or PDF by the extension (evo's naming: FILE_raw.png
    /// and FILE_map.png; one two-page FILE.pdf).
    #[arg(long = "save_plot", value_name = "FILE")]
    pub save_plot: Option<PathBuf>,
    /// Log to Rerun (not supported by sitar).
    #[arg(long)]
    pub rerun: bool,
    /// Rerun recording ID (not supported by sitar).
    #[arg(long = "rerun_rec_id")]
    pub rerun_rec_id: Option<String>,
    /// .zip file path to store results (evo's archive: evo_res and sitar res read it).
    #[arg(long = "save_results", value_name = "FILE.zip")]
    pub save_results: Option<PathBuf>,
    /// SiTAR extra: print the errors as CSV or JSON (with statistics and alignment) instead
    /// of evo's table.
    #[arg(long, value_enum)]
    pub format: Option<OutputFormat>,
    /// SiTAR extra: write the --format output to this file instead of stdout.
    #[arg(short = 'o', long, requires = "format")]
    pub output: Option<PathBuf>,
    /// SiTAR extra: also write one self-contained HTML page (tables, every figure inline,
    /// the JSON document); it fetches nothing when opened.
    #[arg(long, value_name = "FILE")]
    pub html: Option<PathBuf>,
}

/// `--change_unit`: evo's angle and length units.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ChangeUnit {
    /// Degrees.
    Deg,
    /// Radians.
    Rad,
    /// Millimetres.
    Mm,
    /// Centimetres.
    Cm,
    /// Metres.
    M,
    /// Kilometres.
    Km,
}

impl ChangeUnit {
    /// The library's unit.
    pub fn unit(self) -> sitar_evo::ChangeUnit {
        match self {
            ChangeUnit::Deg => sitar_evo::ChangeUnit::Deg,
            ChangeUnit::Rad => sitar_evo::ChangeUnit::Rad,
            ChangeUnit::Mm => sitar_evo::ChangeUnit::Mm,
            ChangeUnit::Cm => sitar_evo::ChangeUnit::Cm,
            ChangeUnit::M => sitar_evo::ChangeUnit::M,
            ChangeUnit::Km => sitar_evo::ChangeUnit::Km,
        }
    }
}

/// `--yaw_axis`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AxisArg {
    /// z up.
    Z,
    /// y (gravity along -y).
    Y,
}

impl AxisArg {
    /// The library's axis.
    pub fn axis(self) -> GravityAxis {
        match self {
            AxisArg::Z => GravityAxis::Z,
            AxisArg::Y => GravityAxis::Y,
        }
    }
}

/// `--project_to_plane`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PlaneArg {
    /// The xy plane.
    Xy,
    /// The xz plane.
    Xz,
    /// The yz plane.
    Yz,
}

impl PlaneArg {
    /// The library's plane.
    pub fn plane(self) -> Plane {
        match self {
            PlaneArg::Xy => Plane::Xy,
            PlaneArg::Xz => Plane::Xz,
            PlaneArg::Yz => Plane::Yz,
        }
    }

    /// evo's name.
    pub fn name(self) -> &'static str {
        match self {
            PlaneArg::Xy => "xy",
            PlaneArg::Xz => "xz",
            PlaneArg::Yz => "yz",
        }
    }
}

/// `--plot_x_dimension`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum XDimension {
    /// The error's index.
    Index,
    /// Seconds from the first stamp.
    Seconds,
    /// Distance travelled on the reference (m).
    Distances,
}

/// Refuses evo's options that need software sitar does not have (Rerun, map tiles, ROS
/// maps), by name.
pub fn check_supported(output: &OutputArgs) -> anyhow::Result<()> {
    let unsupported = [
        (output.rerun || output.rerun_rec_id.is_some(), "--rerun"),
        (output.map_tile.is_some(), "--map_tile"),
        (output.ros_map_yaml.is_some(), "--ros_map_yaml"),
    ];
    if let Some((_, flag)) = unsupported.iter().find(|(used, _)| *used) {
        anyhow::bail!("{flag} is not supported by sitar (it needs evo's optional viewers)");
    }
    Ok(())
}
