//! `sitar traj`'s command line: evo_traj's formats and options.

use std::path::PathBuf;

use crate::figures::figure::PlotMode;
use crate::io::console::UsabilityArgs;
use crate::io::source::{StampUnit, SyncMethod};
use crate::results::metric_args::PlaneArg;

/// Trajectory analysis and manipulation, as evo_traj.
///
/// `sitar traj tum A.txt B.txt --ref GT.txt -a -p`: information on every trajectory, with
/// --ref synchronised and aligned to the reference; --save_as_tum/--save_as_kitti write the
/// result into the current directory as evo does.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar traj tum trajectory_0.txt trajectory_1.txt --ref ground_truth.txt -a --full_check\n  sitar traj euroc data.csv --save_as_tum\n  sitar traj tum a.txt b.txt --merge --save_as_kitti"
)]
pub struct Args {
    #[command(subcommand)]
    pub(super) format: Format,
}

#[derive(clap::Subcommand, Debug)]
pub(super) enum Format {
    /// TUM trajectory files.
    #[command(args_override_self = true)]
    Tum {
        /// One or multiple trajectory files.
        #[arg(required = true)]
        traj_files: Vec<PathBuf>,
        #[command(flatten)]
        options: Options,
    },
    /// EuRoC MAV ground-truth .csv files.
    #[command(args_override_self = true)]
    Euroc {
        /// SEQUENCE/mav0/state_groundtruth_estimate0/data.csv
        #[arg(required = true)]
        state_gt_csv: Vec<PathBuf>,
        #[command(flatten)]
        options: Options,
    },
    /// KITTI pose files.
    #[command(args_override_self = true)]
    Kitti {
        /// One or multiple pose files.
        #[arg(required = true)]
        pose_files: Vec<PathBuf>,
        #[command(flatten)]
        options: Options,
    },
    /// ROS 1 bag files; topics of the pose types evo reads or tf ids (--ref is a topic too).
    Bag {
        /// ROS bag file.
        bag: String,
        /// Trajectory topics.
        topics: Vec<String>,
        /// Use all compatible topics in the bag.
        #[arg(long = "all_topics")]
        all_topics: bool,
        #[command(flatten)]
        options: Options,
    },
    /// ROS 2 bags: a bag directory, an .mcap or a .db3 file; topics of the pose types evo
    /// reads or tf ids (--ref is a topic too).
    #[command(alias = "mcap")]
    Bag2 {
        /// ROS 2 bag file.
        bag: String,
        /// Trajectory topics.
        topics: Vec<String>,
        /// Use all compatible topics in the bag.
        #[arg(long = "all_topics", alias = "all_channels")]
        all_topics: bool,
        #[command(flatten)]
        options: Options,
    },
}

/// evo_traj's options.
#[derive(clap::Args, Debug)]
pub(super) struct Options {
    /// Run all checks and print all stats.
    #[arg(short = 'f', long = "full_check")]
    pub(super) full_check: bool,
    /// Scale correction with Umeyama's method (requires --ref).
    #[arg(short = 's', long = "correct_scale", alias = "correct-scale")]
    pub(super) correct_scale: bool,
    /// The number of poses to use for Umeyama alignment, counted from the start (-1: all).
    #[arg(long = "n_to_align", default_value_t = -1, allow_negative_numbers = true)]
    pub(super) n_to_align: i64,
    /// Associate trajectories via matching timestamps (requires --ref).
    #[arg(long)]
    pub(super) sync: bool,
    /// File with a transformation (4x4 text or .npy, or JSON x y z qx qy qz qw and optional scale) to
    /// apply to the trajectories (left multiplicative).
    #[arg(long = "transform_left", value_name = "FILE")]
    pub(super) transform_left: Option<PathBuf>,
    /// As --transform_left, right multiplicative.
    #[arg(
        long = "transform_right",
        value_name = "FILE",
        conflicts_with = "transform_left"
    )]
    pub(super) transform_right: Option<PathBuf>,
    /// With --transform_right: transform each pose and propagate the drift to the next.
    #[arg(long = "propagate_transform")]
    pub(super) propagate_transform: bool,
    /// Invert the transformation of the file.
    #[arg(long = "invert_transform")]
    pub(super) invert_transform: bool,
    /// Trajectory that will be marked/used as the reference.
    #[arg(long = "ref", value_name = "FILE")]
    pub(super) reference: Option<PathBuf>,
    /// Add a constant timestamp offset (s) to the trajectories (not to --ref).
    #[arg(
        long = "t_offset",
        alias = "t-offset",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub(super) t_offset: f64,
    /// Maximum timestamp difference (s) for data association.
    #[arg(long = "t_max_diff", alias = "t-max-diff", default_value_t = 0.01)]
    pub(super) t_max_diff: f64,
    /// Method of the time synchronization.
    #[arg(long = "sync_method", value_enum, default_value_t = SyncMethod::NearestTime)]
    pub(super) sync_method: SyncMethod,
    /// Merge the trajectories in a single trajectory.
    #[arg(long)]
    pub(super) merge: bool,
    /// Projects the trajectories to 2D in the desired plane (after alignment).
    #[arg(long = "project_to_plane", value_enum)]
    pub(super) project_to_plane: Option<PlaneArg>,
    /// Downsample trajectories to max N poses.
    #[arg(long, value_name = "N")]
    pub(super) downsample: Option<usize>,
    /// Filters out poses if the distance (m) or angle (degrees) to the previous one is below
    /// the threshold.
    #[arg(long = "motion_filter", num_args = 2, value_names = ["DISTANCE", "ANGLE_DEGREES"])]
    pub(super) motion_filter: Option<Vec<f64>>,
    /// Alignment with Umeyama's method (no scale; requires --ref).
    #[arg(short = 'a', long)]
    pub(super) align: bool,
    /// Align the trajectory origin to the origin of the reference trajectory.
    #[arg(
        long = "align_origin",
        alias = "align-origin",
        conflicts_with = "align"
    )]
    pub(super) align_origin: bool,
    /// Show the plots (evo's -p); without a display sitar says so and shows nothing.
    #[arg(short = 'p', long)]
    pub(super) plot: bool,
    /// Show timestamps relative to the start of the reference.
    #[arg(long = "plot_relative_time")]
    pub(super) plot_relative_time: bool,
    /// The axes for plot projection (xyz: 3-D).
    #[arg(long = "plot_mode", alias = "plot-mode", value_enum, default_value_t = PlotMode::Xyz)]
    pub(super) plot_mode: PlotMode,
    /// ROS map image yaml (not supported by sitar).
    #[arg(long = "ros_map_yaml")]
    pub(super) ros_map_yaml: Option<String>,
    /// Map tile layer (not supported by sitar).
    #[arg(long = "map_tile")]
    pub(super) map_tile: Option<String>,
    /// Path to save the plots: PNG, SVG or PDF by the extension (FILE_trajectories.png,
    /// FILE_xyz.png, FILE_rpy.png, FILE_speeds.png; one PDF with every page).
    #[arg(long = "save_plot", value_name = "FILE")]
    pub(super) save_plot: Option<PathBuf>,
    /// Send visualization data to Rerun (not supported by sitar).
    #[arg(long)]
    pub(super) rerun: bool,
    /// Rerun recording ID (not supported by sitar).
    #[arg(long = "rerun_rec_id")]
    pub(super) rerun_rec_id: Option<String>,
    /// Path to save a table with the trajectories' statistics (CSV).
    #[arg(long = "save_table", value_name = "FILE")]
    pub(super) save_table: Option<PathBuf>,
    /// Save the trajectories in TUM format (as NAME.tum in the current directory).
    #[arg(long = "save_as_tum")]
    pub(super) save_as_tum: bool,
    /// Save the poses in KITTI format (as NAME.kitti in the current directory).
    #[arg(long = "save_as_kitti")]
    pub(super) save_as_kitti: bool,
    /// Save the trajectories in a ROS 1 bag as DATE.bag (YYYY-MM-DD-hh-mm-ss; PoseStamped topics).
    #[arg(long = "save_as_bag")]
    pub(super) save_as_bag: bool,
    /// Save the trajectories in a ROS 2 bag (MCAP storage) as the directory DATE.
    #[arg(long = "save_as_bag2")]
    pub(super) save_as_bag2: bool,
    /// Don't shorten input file paths when displaying trajectory names.
    #[arg(long = "show_full_names")]
    pub(super) show_full_names: bool,
    /// Unit of TUM stamps: s (evo's reading) or ns (ARCore's integer nanoseconds).
    #[arg(long = "time_unit", alias = "time-unit", value_enum, default_value_t = StampUnit::S)]
    pub(super) time_unit: StampUnit,
    #[command(flatten)]
    pub(super) usability: UsabilityArgs,
}
