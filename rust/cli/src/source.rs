//! evo's format subcommands (`tum`, `euroc`, `kitti`, `bag`, `bag2`/`mcap`) and
//! reading REF and EST the way evo does.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::ValueEnum;
use sitar_estimator::{
    ReadOptions, ReadReport, StampOrder, TimeUnitRule, Trajectory, read_euroc_csv_with, read_kitti,
    read_tum_with,
};

use crate::console::{Console, SEP};

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
    /// The library's rule.
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
                sync: crate::source::SyncArgs,
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
                sync: crate::source::SyncArgs,
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
                sync: crate::source::SyncArgs,
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
                sync: crate::source::SyncArgs,
                #[command(flatten)]
                options: $options,
            },
        }

        impl $name {
            /// The inputs and the options.
            pub fn split(self) -> (crate::source::Source, $options) {
                use crate::source::Source;
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

/// What evo knows of a loaded trajectory: its poses and its name (the path as given).
#[derive(Clone)]
pub struct Named {
    /// The poses.
    pub trajectory: Trajectory,
    /// The path as given on the command line (evo's `name`).
    pub name: String,
    /// Every quaternion was read with unit norm (by numpy's `allclose`, as evo's check).
    pub unit_quaternions: bool,
}

/// Reference and estimate as read, with whether they have stamps (KITTI has none).
pub struct Loaded {
    /// The reference.
    pub reference: Named,
    /// The estimate.
    pub estimate: Named,
    /// The sync options (None for KITTI).
    pub sync: Option<SyncArgs>,
}

/// evo's reading options with the stamp unit of `--time_unit`.
pub fn evo_read_options(unit: StampUnit) -> ReadOptions {
    ReadOptions {
        time_unit: unit.rule(),
        stamp_order: StampOrder::AsWritten,
        normalise_quaternions: true,
    }
}

/// Reads one TUM file by evo's rules, telling `console` what it met.
pub fn read_tum_evo(path: &Path, unit: StampUnit, console: &Console) -> Result<Named> {
    let (trajectory, report) = read_tum_with(path, &evo_read_options(unit))
        .map_err(|e| with_format_hint(e.into(), path, "tum"))?;
    finish(path, trajectory, &report, true, console)
}

/// Reads one EuRoC ground-truth file by evo's rules.
pub fn read_euroc_evo(path: &Path, console: &Console) -> Result<Named> {
    let (trajectory, report) = read_euroc_csv_with(path, &evo_read_options(StampUnit::Ns))
        .map_err(|e| with_format_hint(e.into(), path, "euroc"))?;
    finish(path, trajectory, &report, true, console)
}

/// Reads one KITTI file.
pub fn read_kitti_evo(path: &Path, console: &Console) -> Result<Named> {
    let trajectory = read_kitti(path).map_err(|e| with_format_hint(e.into(), path, "kitti"))?;
    finish(path, trajectory, &ReadReport::default(), false, console)
}

/// `error` (reading `path` as `given`), with a hint naming the format the file does read
/// as, if one does: `ape euroc` on a TUM file suggests `tum`.
fn with_format_hint(error: anyhow::Error, path: &Path, given: &str) -> anyhow::Error {
    let options = evo_read_options(StampUnit::S);
    let readers: [(&str, &dyn Fn() -> bool); 3] = [
        ("tum", &|| {
            read_tum_with(path, &options).is_ok_and(|t| !t.0.is_empty())
        }),
        ("euroc", &|| {
            read_euroc_csv_with(path, &options).is_ok_and(|t| !t.0.is_empty())
        }),
        ("kitti", &|| read_kitti(path).is_ok_and(|t| !t.is_empty())),
    ];
    match readers
        .iter()
        .find(|(name, reads)| *name != given && reads())
    {
        Some((name, _)) => anyhow::anyhow!(
            "{error:#} (the file reads as the {name} format: use `{name}` in place of `{given}`)"
        ),
        None => error,
    }
}

fn finish(
    path: &Path,
    trajectory: Trajectory,
    report: &ReadReport,
    timed: bool,
    console: &Console,
) -> Result<Named> {
    let name = path.display().to_string();
    if trajectory.is_empty() {
        bail!("{name}: no poses");
    }
    if let Some(line) = report.first_repeated_line {
        console.warn(&format!(
            "{name}: {} repeated timestamp(s), the first on line {line}; both poses are kept, as evo keeps them",
            report.repeated_stamps
        ));
    }
    if let Some(line) = report.first_decreasing_line {
        console.warn(&format!(
            "{name}: {} timestamp(s) below the previous one, the first on line {line}; the poses are kept in file order, as evo keeps them",
            report.decreasing_stamps
        ));
    }
    if report.normalised_quaternions > 0 {
        console.debug(&format!(
            "{name}: normalised {} quaternion(s) whose norm was not 1",
            report.normalised_quaternions
        ))?;
    }
    console.debug(&format!(
        "Loaded {} {} from: {name}",
        trajectory.len(),
        if timed { "stamps and poses" } else { "poses" }
    ))?;
    Ok(Named {
        trajectory,
        name,
        unit_quaternions: report.quaternions_off_unit == 0,
    })
}

/// Reads the reference and every estimate: one [`Loaded`] per estimate (the reference read
/// once, then each estimate in the order given).
pub fn load(source: &Source, console: &Console) -> Result<Vec<Loaded>> {
    console.debug(SEP)?;
    let pair = |reference: &Named, estimate: Named, sync: Option<&SyncArgs>| Loaded {
        reference: reference.clone(),
        estimate,
        sync: sync.cloned(),
    };
    match source {
        Source::Tum {
            reference,
            estimates,
            sync,
        } => {
            let reference = read_tum_evo(reference, sync.time_unit, console)?;
            estimates
                .iter()
                .map(|e| {
                    Ok(pair(
                        &reference,
                        read_tum_evo(e, sync.time_unit, console)?,
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
                        read_tum_evo(e, sync.time_unit, console)?,
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
            let wanted = crate::bag::Wanted::named(std::iter::once(reference).chain(estimates));
            let topics = crate::bag::open(kind, bag, &wanted, console)?;
            let named = |topic: &String| -> Result<Named> {
                let read = crate::bag::trajectory(&topics, topic, bag, console)?;
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
