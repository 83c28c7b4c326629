//! evo's format subcommands (`tum`, `euroc`, `kitti`, `bag`, `bag2`/`mcap`) and
//! reading REF and EST the way evo does.

use std::path::PathBuf;

use anyhow::Result;
use clap::ValueEnum;
use sitar_estimator::TimeUnitRule;
use sitar_evo::read::{read_euroc_evo, read_kitti_evo, read_tum_evo};
use sitar_evo::{Loaded, Named, SyncOptions};

use crate::io::console::{Console, SEP};

/// evo's time-sync options of the `tum`, `euroc` and `bag` formats.
#[derive(clap::Args, Debug, Clone)]
pub struct SyncArgs {
    /// Maximum timestamp difference (s) for data association.
    #[arg(long = "t_max_diff", alias = "t-max-diff", default_value_t = 0.01)]
    pub t_max_diff: f64,
    /// Constant timestamp offset (s) added to the estimate for data association.
    #[arg(
        long = "t_offset",
        alias = "t-offset",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub t_offset: f64,
    /// nearest_time associates the closest stamps (see --t_max_diff); interpolation resamples
    /// the denser trajectory at the stamps of the sparser one.
    #[arg(long = "sync_method", value_enum, default_value_t = SyncMethod::NearestTime)]
    pub sync_method: SyncMethod,
    /// Only use reference poses with stamps >= this start time (s).
    #[arg(long = "t_start", allow_negative_numbers = true)]
    pub t_start: Option<f64>,
    /// Only use reference poses with stamps <= this end time (s).
    #[arg(long = "t_end", allow_negative_numbers = true)]
    pub t_end: Option<f64>,
    /// Unit of TUM stamps: s (evo's reading) or ns (ARCore's integer nanoseconds).
    #[arg(long = "time_unit", alias = "time-unit", value_enum, default_value_t = StampUnit::S)]
    pub time_unit: StampUnit,
}

impl SyncArgs {
    /// The library's options.
    pub fn options(&self) -> SyncOptions {
        SyncOptions {
            t_max_diff: self.t_max_diff,
            t_offset: self.t_offset,
            sync_method: self.sync_method.method(),
            t_start: self.t_start,
            t_end: self.t_end,
            time_unit: self.time_unit.unit(),
        }
    }
}

impl Default for SyncArgs {
    fn default() -> Self {
        Self {
            t_max_diff: 0.01,
            t_offset: 0.0,
            sync_method: SyncMethod::NearestTime,
            t_start: None,
            t_end: None,
            time_unit: StampUnit::S,
        }
    }
}

/// evo's `--sync_method`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SyncMethod {
    /// The nearest stamp within --t_max_diff.
    #[value(name = "nearest_time")]
    NearestTime,
    /// Interpolate the trajectory with more poses at the matched stamps of the other.
    Interpolation,
}

impl SyncMethod {
    /// The library's method.
    pub fn method(self) -> sitar_evo::SyncMethod {
        match self {
            SyncMethod::NearestTime => sitar_evo::SyncMethod::NearestTime,
            SyncMethod::Interpolation => sitar_evo::SyncMethod::Interpolation,
        }
    }
}

/// `--time_unit`: how TUM stamps are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StampUnit {
    /// Seconds (integers are whole seconds), as evo reads TUM files.
    S,
    /// Integer nanoseconds (ARCore).
    Ns,
    /// Nanoseconds when all stamps are integers above 10^11, else seconds (SiTAR's rule).
    Auto,
}

impl StampUnit {
    /// The library's unit.
    pub fn unit(self) -> sitar_evo::StampUnit {
        match self {
            StampUnit::S => sitar_evo::StampUnit::S,
            StampUnit::Ns => sitar_evo::StampUnit::Ns,
            StampUnit::Auto => sitar_evo::StampUnit::Auto,
        }
    }

    /// The trajectory library's rule.
    pub fn rule(self) -> TimeUnitRule {
        match self {
            StampUnit::S => TimeUnitRule::Seconds,
            StampUnit::Ns => TimeUnitRule::Nanoseconds,
            StampUnit::Auto => TimeUnitRule::Auto,
        }
    }
}

/// The inputs of `ape`/`rpe`/`drift`, by format: a reference and one estimate (evo's
/// command line) or several (repeated runs of one system).
#[derive(Debug, Clone)]
pub enum Source {
    /// TUM files.
    Tum {
        reference: PathBuf,
        estimates: Vec<PathBuf>,
        sync: SyncArgs,
    },
    /// EuRoC ground-truth CSV and TUM estimates.
    Euroc {
        reference: PathBuf,
        estimates: Vec<PathBuf>,
        sync: SyncArgs,
    },
    /// KITTI pose files (no stamps: poses pair by index).
    Kitti {
        reference: PathBuf,
        estimates: Vec<PathBuf>,
    },
    /// A ROS bag and two of its topics.
    Bag {
        /// `bag` (ROS 1) or `bag2`.
        kind: &'static str,
        /// The bag (a directory, `.mcap` or `.db3`).
        bag: String,
        /// The reference topic.
        reference: String,
        /// The estimate topics (one per run).
        estimates: Vec<String>,
        /// The sync options.
        sync: SyncArgs,
    },
}

/// Defines a clap subcommand enum of evo's formats whose variants carry `$options`.
macro_rules! format_subcommands {
    ($name:ident, $options:ty) => {
        /// The input format, as evo's subcommands.
        #[derive(clap::Subcommand, Debug)]
        pub enum $name {
            /// TUM trajectory files (`t x y z qx qy qz qw`, stamps in seconds).
            #[command(args_override_self = true)]
            Tum {
                /// Reference trajectory file.
                ref_file: std::path::PathBuf,
                /// Estimated trajectory file (several: repeated runs of one system).
                #[arg(required = true)]
                est_file: Vec<std::path::PathBuf>,
                #[command(flatten)]
                sync: crate::io::source::SyncArgs,
                #[command(flatten)]
                options: $options,
            },
            /// EuRoC MAV ground truth (SEQ/mav0/state_groundtruth_estimate0/data.csv) and a
            /// TUM estimate.
            #[command(args_override_self = true)]
            Euroc {
                /// Ground truth: SEQ/mav0/state_groundtruth_estimate0/data.csv.
                state_gt_csv: std::path::PathBuf,
                /// Estimated trajectory file in TUM format (several: repeated runs).
                #[arg(required = true)]
                est_file: Vec<std::path::PathBuf>,
                #[command(flatten)]
                sync: crate::io::source::SyncArgs,
                #[command(flatten)]
                options: $options,
            },
            /// KITTI pose files (12 numbers per line; poses pair by index).
            #[command(args_override_self = true)]
            Kitti {
                /// Reference pose file (ground truth).
                ref_file: std::path::PathBuf,
                /// Estimated pose file (several: repeated runs of one system).
                #[arg(required = true)]
                est_file: Vec<std::path::PathBuf>,
                #[command(flatten)]
                options: $options,
            },
            /// ROS 1 bag files (uncompressed, bz2 or lz4 chunks), with the topics of
            /// PoseStamped, PoseWithCovarianceStamped, TransformStamped, PointStamped or
            /// Odometry messages, or tf ids (/tf:PARENT.CHILD).
            Bag {
                /// ROS bag file.
                bag: String,
                /// Reference trajectory topic.
                ref_topic: String,
                /// Estimated trajectory topic (several: repeated runs of one system).
                #[arg(required = true)]
                est_topic: Vec<String>,
                #[command(flatten)]
                sync: crate::io::source::SyncArgs,
                #[command(flatten)]
                options: $options,
            },
            /// ROS 2 bags: a bag directory, an .mcap or a .db3 file (zstd/lz4 chunks, rosbag2's
            /// file or message compression), with the topics of PoseStamped,
            /// PoseWithCovarianceStamped, TransformStamped, PointStamped or Odometry messages,
            /// or tf ids (/tf:PARENT.CHILD).
            #[command(alias = "mcap")]
            Bag2 {
                /// ROS 2 bag file.
                bag: String,
                /// Reference trajectory topic.
                ref_topic: String,
                /// Estimated trajectory topic (several: repeated runs of one system).
                #[arg(required = true)]
                est_topic: Vec<String>,
                #[command(flatten)]
                sync: crate::io::source::SyncArgs,
                #[command(flatten)]
                options: $options,
            },
        }

        impl $name {
            /// The inputs and the options.
            pub fn split(self) -> (crate::io::source::Source, $options) {
                use crate::io::source::Source;
                let bag_kind = if matches!(self, Self::Bag { .. }) {
                    "bag"
                } else {
                    "bag2"
                };
                match self {
                    Self::Tum {
                        ref_file,
                        est_file,
                        sync,
                        options,
                    } => (
                        Source::Tum {
                            reference: ref_file,
                            estimates: est_file,
                            sync,
                        },
                        options,
                    ),
                    Self::Euroc {
                        state_gt_csv,
                        est_file,
                        sync,
                        options,
                    } => (
                        Source::Euroc {
                            reference: state_gt_csv,
                            estimates: est_file,
                            sync,
                        },
                        options,
                    ),
                    Self::Kitti {
                        ref_file,
                        est_file,
                        options,
                    } => (
                        Source::Kitti {
                            reference: ref_file,
                            estimates: est_file,
                        },
                        options,
                    ),
                    Self::Bag {
                        bag,
                        ref_topic,
                        est_topic,
                        sync,
                        options,
                    }
                    | Self::Bag2 {
                        bag,
                        ref_topic,
                        est_topic,
                        sync,
                        options,
                    } => (
                        Source::Bag {
                            kind: bag_kind,
                            bag,
                            reference: ref_topic,
                            estimates: est_topic,
                            sync,
                        },
                        options,
                    ),
                }
            }
        }
    };
}
pub(crate) use format_subcommands;

/// Reads the reference and every estimate: one [`Loaded`] per estimate (the reference read
/// once, then each estimate in the order given).
pub fn load(source: &Source, console: &Console) -> Result<Vec<Loaded>> {
    console.debug(SEP)?;
    let pair = |reference: &Named, estimate: Named, sync: Option<&SyncArgs>| Loaded {
        reference: reference.clone(),
        estimate,
        sync: sync.map(SyncArgs::options),
    };
    match source {
        Source::Tum {
            reference,
            estimates,
            sync,
        } => {
            let reference = read_tum_evo(reference, sync.time_unit.unit(), console)?;
            estimates
                .iter()
                .map(|e| {
                    Ok(pair(
                        &reference,
                        read_tum_evo(e, sync.time_unit.unit(), console)?,
                        Some(sync),
                    ))
                })
                .collect()
        }
        Source::Euroc {
            reference,
            estimates,
            sync,
        } => {
            let reference = read_euroc_evo(reference, console)?;
            estimates
                .iter()
                .map(|e| {
                    Ok(pair(
                        &reference,
                        read_tum_evo(e, sync.time_unit.unit(), console)?,
                        Some(sync),
                    ))
                })
                .collect()
        }
        Source::Kitti {
            reference,
            estimates,
        } => {
            let reference = read_kitti_evo(reference, console)?;
            estimates
                .iter()
                .map(|e| Ok(pair(&reference, read_kitti_evo(e, console)?, None)))
                .collect()
        }
        Source::Bag {
            kind,
            bag,
            reference,
            estimates,
            sync,
        } => {
            let wanted = crate::io::bag::Wanted::named(std::iter::once(reference).chain(estimates));
            let topics = crate::io::bag::open(kind, bag, &wanted, console)?;
            let named = |topic: &String| -> Result<Named> {
                let read = crate::io::bag::trajectory(&topics, topic, bag, console)?;
                Ok(Named {
                    trajectory: read.trajectory,
                    name: topic.clone(),
                    unit_quaternions: read.quaternions_off_unit == 0,
                })
            };
            let reference = named(reference)?;
            estimates
                .iter()
                .map(|e| Ok(pair(&reference, named(e)?, Some(sync))))
                .collect()
        }
    }
}
