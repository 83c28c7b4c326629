//! `sitar traj`: trajectory information and manipulation, as `evo_traj`: per-trajectory
//! information, checks and statistics; synchronisation with and alignment to `--ref`;
//! merge, time offset, transformations, projection; TUM/KITTI export, a statistics table and
//! the plots.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use glam::{DMat3, DMat4, DQuat, DVec3};
use sitar_estimator::{Alignment, TimeUnit, Trajectory, align_first, write_tum};

use crate::figures::canvas::{self, Page};
use crate::figures::figure::{Drawing, PAGE, PALETTE, Path3, PlotMode, Series};
use crate::io::console::{Console, SEP, UsabilityArgs};
use crate::io::source::{StampUnit, SyncMethod};
use crate::results::metric_args::PlaneArg;
use sitar_evo::read::{read_euroc_evo, read_kitti_evo, read_tum_evo};

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
    format: Format,
}

#[derive(clap::Subcommand, Debug)]
enum Format {
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
struct Options {
    /// Run all checks and print all stats.
    #[arg(short = 'f', long = "full_check")]
    full_check: bool,
    /// Scale correction with Umeyama's method (requires --ref).
    #[arg(short = 's', long = "correct_scale", alias = "correct-scale")]
    correct_scale: bool,
    /// The number of poses to use for Umeyama alignment, counted from the start (-1: all).
    #[arg(long = "n_to_align", default_value_t = -1, allow_negative_numbers = true)]
    n_to_align: i64,
    /// Associate trajectories via matching timestamps (requires --ref).
    #[arg(long)]
    sync: bool,
    /// File with a transformation (4x4 text or .npy, or JSON x y z qx qy qz qw and optional scale) to
    /// apply to the trajectories (left multiplicative).
    #[arg(long = "transform_left", value_name = "FILE")]
    transform_left: Option<PathBuf>,
    /// As --transform_left, right multiplicative.
    #[arg(
        long = "transform_right",
        value_name = "FILE",
        conflicts_with = "transform_left"
    )]
    transform_right: Option<PathBuf>,
    /// With --transform_right: transform each pose and propagate the drift to the next.
    #[arg(long = "propagate_transform")]
    propagate_transform: bool,
    /// Invert the transformation of the file.
    #[arg(long = "invert_transform")]
    invert_transform: bool,
    /// Trajectory that will be marked/used as the reference.
    #[arg(long = "ref", value_name = "FILE")]
    reference: Option<PathBuf>,
    /// Add a constant timestamp offset (s) to the trajectories (not to --ref).
    #[arg(
        long = "t_offset",
        alias = "t-offset",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    t_offset: f64,
    /// Maximum timestamp difference (s) for data association.
    #[arg(long = "t_max_diff", alias = "t-max-diff", default_value_t = 0.01)]
    t_max_diff: f64,
    /// Method of the time synchronization.
    #[arg(long = "sync_method", value_enum, default_value_t = SyncMethod::NearestTime)]
    sync_method: SyncMethod,
    /// Merge the trajectories in a single trajectory.
    #[arg(long)]
    merge: bool,
    /// Projects the trajectories to 2D in the desired plane (after alignment).
    #[arg(long = "project_to_plane", value_enum)]
    project_to_plane: Option<PlaneArg>,
    /// Downsample trajectories to max N poses.
    #[arg(long, value_name = "N")]
    downsample: Option<usize>,
    /// Filters out poses if the distance (m) or angle (degrees) to the previous one is below
    /// the threshold.
    #[arg(long = "motion_filter", num_args = 2, value_names = ["DISTANCE", "ANGLE_DEGREES"])]
    motion_filter: Option<Vec<f64>>,
    /// Alignment with Umeyama's method (no scale; requires --ref).
    #[arg(short = 'a', long)]
    align: bool,
    /// Align the trajectory origin to the origin of the reference trajectory.
    #[arg(
        long = "align_origin",
        alias = "align-origin",
        conflicts_with = "align"
    )]
    align_origin: bool,
    /// Show the plots (evo's -p); without a display sitar says so and shows nothing.
    #[arg(short = 'p', long)]
    plot: bool,
    /// Show timestamps relative to the start of the reference.
    #[arg(long = "plot_relative_time")]
    plot_relative_time: bool,
    /// The axes for plot projection (xyz: 3-D).
    #[arg(long = "plot_mode", alias = "plot-mode", value_enum, default_value_t = PlotMode::Xyz)]
    plot_mode: PlotMode,
    /// ROS map image yaml (not supported by sitar).
    #[arg(long = "ros_map_yaml")]
    ros_map_yaml: Option<String>,
    /// Map tile layer (not supported by sitar).
    #[arg(long = "map_tile")]
    map_tile: Option<String>,
    /// Path to save the plots: PNG, SVG or PDF by the extension (FILE_trajectories.png,
    /// FILE_xyz.png, FILE_rpy.png, FILE_speeds.png; one PDF with every page).
    #[arg(long = "save_plot", value_name = "FILE")]
    save_plot: Option<PathBuf>,
    /// Send visualization data to Rerun (not supported by sitar).
    #[arg(long)]
    rerun: bool,
    /// Rerun recording ID (not supported by sitar).
    #[arg(long = "rerun_rec_id")]
    rerun_rec_id: Option<String>,
    /// Path to save a table with the trajectories' statistics (CSV).
    #[arg(long = "save_table", value_name = "FILE")]
    save_table: Option<PathBuf>,
    /// Save the trajectories in TUM format (as NAME.tum in the current directory).
    #[arg(long = "save_as_tum")]
    save_as_tum: bool,
    /// Save the poses in KITTI format (as NAME.kitti in the current directory).
    #[arg(long = "save_as_kitti")]
    save_as_kitti: bool,
    /// Save the trajectories in a ROS 1 bag as DATE.bag (YYYY-MM-DD-hh-mm-ss; PoseStamped topics).
    #[arg(long = "save_as_bag")]
    save_as_bag: bool,
    /// Save the trajectories in a ROS 2 bag (MCAP storage) as the directory DATE.
    #[arg(long = "save_as_bag2")]
    save_as_bag2: bool,
    /// Don't shorten input file paths when displaying trajectory names.
    #[arg(long = "show_full_names")]
    show_full_names: bool,
    /// Unit of TUM stamps: s (evo's reading) or ns (ARCore's integer nanoseconds).
    #[arg(long = "time_unit", alias = "time-unit", value_enum, default_value_t = StampUnit::S)]
    time_unit: StampUnit,
    #[command(flatten)]
    usability: UsabilityArgs,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Tum,
    Euroc,
    Kitti,
}

/// The bundle: named trajectories (in the order given), the reference and, after a sync,
/// each trajectory's synchronised reference.
struct Bundle {
    trajectories: Vec<(String, Trajectory)>,
    reference: Option<(String, Trajectory)>,
    synced_refs: BTreeMap<String, Trajectory>,
    synced: bool,
    /// Trajectories read with quaternions off unit norm (evo's check calls them invalid).
    off_unit: std::collections::BTreeSet<String>,
    /// The trajectories are a bag's topics (named by topic, never shortened).
    from_bag: bool,
    /// A bag topic's frame (evo's `meta.frame_id`), by name.
    frames: BTreeMap<String, String>,
}

pub fn run(args: Args) -> Result<()> {
    let mut bag2 = None;
    let (kind, files, options) = match args.format {
        Format::Tum {
            traj_files,
            options,
        } => (Kind::Tum, traj_files, options),
        Format::Euroc {
            state_gt_csv,
            options,
        } => (Kind::Euroc, state_gt_csv, options),
        Format::Kitti {
            pose_files,
            options,
        } => (Kind::Kitti, pose_files, options),
        Format::Bag {
            bag,
            topics,
            all_topics,
            options,
        } => {
            bag2 = Some(("bag", bag, topics, all_topics));
            (Kind::Tum, Vec::new(), options)
        }
        Format::Bag2 {
            bag,
            topics,
            all_topics,
            options,
        } => {
            bag2 = Some(("bag2", bag, topics, all_topics));
            (Kind::Tum, Vec::new(), options)
        }
    };
    let console = Console::new(&options.usability)?;
    for (used, flag) in [
        (options.rerun || options.rerun_rec_id.is_some(), "--rerun"),
        (options.map_tile.is_some(), "--map_tile"),
        (options.ros_map_yaml.is_some(), "--ros_map_yaml"),
    ] {
        if used {
            bail!("{flag} is not supported by sitar (it needs ROS or evo's optional viewers)");
        }
    }
    console.debug(SEP)?;
    let mut off_unit = std::collections::BTreeSet::new();
    let mut read = |path: &Path| -> Result<(String, Trajectory)> {
        let named = match kind {
            Kind::Tum => read_tum_evo(path, options.time_unit.unit(), &console)?,
            Kind::Euroc => read_euroc_evo(path, &console)?,
            Kind::Kitti => read_kitti_evo(path, &console)?,
        };
        if !named.unit_quaternions {
            off_unit.insert(named.name.clone());
        }
        Ok((named.name, named.trajectory))
    };
    let mut bundle = Bundle {
        trajectories: Vec::new(),
        reference: None,
        synced_refs: BTreeMap::new(),
        synced: false,
        off_unit: Default::default(),
        from_bag: bag2.is_some(),
        frames: BTreeMap::new(),
    };
    for file in &files {
        if options.reference.as_ref() == Some(file) {
            continue;
        }
        let (name, trajectory) = read(file)?;
        match bundle.trajectories.iter_mut().find(|(n, _)| *n == name) {
            Some(entry) => entry.1 = trajectory,
            None => bundle.trajectories.push((name, trajectory)),
        }
    }
    if let Some(path) = options.reference.as_ref().filter(|_| bag2.is_none()) {
        bundle.reference = Some(read(path)?);
    }
    bundle.off_unit = off_unit;
    if let Some((bag_kind, bag, topics, all_topics)) = &bag2 {
        let selection = BagSelection {
            kind: bag_kind,
            bag,
            topics,
            all_topics: *all_topics,
        };
        read_bag_topics(&mut bundle, &selection, &options, &console)?;
    }
    manipulate(&mut bundle, kind, &options, &console)?;
    print_infos(&bundle, &options, kind, &console)?;
    if options.plot || options.save_plot.is_some() {
        plot(&bundle, &options, kind, &console)?;
    }
    export(&bundle, &options, kind, &console)
}

/// The topics of a bag that `traj` reads.
struct BagSelection<'a> {
    /// evo's format: `bag` or `bag2`.
    kind: &'a str,
    bag: &'a str,
    topics: &'a [String],
    all_topics: bool,
}

/// evo_traj's topics of a ROS bag: those given, and with `--all_topics` every topic of a
/// pose type evo reads (sorted; `--ref` left out of them), each named by its topic; `--ref`
/// is a topic too.
fn read_bag_topics(
    bundle: &mut Bundle,
    selection: &BagSelection<'_>,
    options: &Options,
    console: &Console,
) -> Result<()> {
    let BagSelection {
        kind,
        bag,
        topics,
        all_topics,
    } = *selection;
    if topics.is_empty() && !all_topics {
        bail!("No topics used - specify topics or set --all_topics.");
    }
    let reference = options
        .reference
        .as_ref()
        .map(|r| r.to_string_lossy().into_owned());
    let wanted = if all_topics {
        crate::io::bag::Wanted::All
    } else {
        crate::io::bag::Wanted::named(topics.iter().chain(&reference))
    };
    let content = crate::io::bag::open(kind, bag, &wanted, console)?;
    let mut chosen = topics.to_vec();
    if all_topics {
        chosen.extend(crate::io::bag::supported_topics(&content));
        chosen.retain(|t| Some(t) != reference.as_ref());
        if chosen.is_empty() {
            bail!(
                "{bag}: found no topics of supported types (geometry_msgs/msg/PoseStamped, PoseWithCovarianceStamped, TransformStamped, PointStamped, nav_msgs/msg/Odometry)"
            );
        }
    }
    let mut read = |topic: &String| -> Result<Trajectory> {
        let read = crate::io::bag::trajectory(&content, topic, bag, console)?;
        if read.quaternions_off_unit > 0 {
            bundle.off_unit.insert(topic.clone());
        }
        bundle.frames.insert(topic.clone(), read.frame_id);
        Ok(read.trajectory)
    };
    let mut trajectories: Vec<(String, Trajectory)> = Vec::new();
    for topic in chosen {
        if trajectories.iter().all(|(n, _)| *n != topic) {
            let trajectory = read(&topic)?;
            trajectories.push((topic, trajectory));
        }
    }
    let reference = match reference {
        Some(topic) => Some((topic.clone(), read(&topic)?)),
        None => None,
    };
    bundle.trajectories = trajectories;
    bundle.reference = reference;
    Ok(())
}

/// evo_traj's steps in its order: downsample, motion filter, merge, time offset, sync,
/// alignment, transformation, projection.
fn manipulate(bundle: &mut Bundle, kind: Kind, options: &Options, console: &Console) -> Result<()> {
    filter(bundle, options, console)?;
    if options.merge {
        merge(bundle, kind)?;
    }
    if options.t_offset != 0.0 {
        add_time_offset(bundle, kind, options.t_offset, console)?;
    }
    if options.n_to_align != -1 && !(options.align || options.correct_scale) {
        bail!("--n_to_align is useless without --align or/and --correct_scale");
    }
    let needs_sync = (kind == Kind::Kitti && bundle.reference.is_some())
        || options.sync
        || options.align
        || options.correct_scale
        || options.align_origin;
    if needs_sync {
        sync_with_reference(bundle, kind, options, console)?;
        align_to_reference(bundle, options, console)?;
    }
    if let Some(path) = options
        .transform_left
        .as_ref()
        .or(options.transform_right.as_ref())
    {
        transform(bundle, path, options, console)?;
    }
    if let Some(plane) = options.project_to_plane {
        project(bundle, plane, console)?;
    }
    Ok(())
}

/// Applies `f` to every trajectory, the reference included.
fn each(bundle: &mut Bundle, f: &mut dyn FnMut(&mut Trajectory) -> Result<()>) -> Result<()> {
    for (_, t) in &mut bundle.trajectories {
        f(t)?;
    }
    if let Some((_, t)) = &mut bundle.reference {
        f(t)?;
    }
    Ok(())
}

/// `--downsample` and `--motion_filter` on every trajectory, the reference included.
fn filter(bundle: &mut Bundle, options: &Options, console: &Console) -> Result<()> {
    if let Some(n) = options.downsample {
        console.debug(SEP)?;
        console.info(&format!("Downsampling trajectories to max {n} poses."))?;
        each(bundle, &mut |t| Ok(t.downsample(n)?))?;
    }
    if let Some(filter) = &options.motion_filter {
        console.debug(SEP)?;
        console.info(&format!(
            "Filtering trajectories with motion filter thresholds: {:.6} m, {:.6} deg",
            filter[0], filter[1]
        ))?;
        each(bundle, &mut |t| Ok(t.motion_filter(filter[0], filter[1])?))?;
    }
    Ok(())
}

/// `--merge`: the trajectories (not the reference) become one, sorted by stamp.
fn merge(bundle: &mut Bundle, kind: Kind) -> Result<()> {
    if kind == Kind::Kitti {
        bail!("Can't merge KITTI files.");
    }
    if bundle.trajectories.is_empty() {
        bail!("No trajectories to merge.");
    }
    let parts: Vec<Trajectory> = bundle.trajectories.iter().map(|(_, t)| t.clone()).collect();
    bundle.trajectories = vec![("merged_trajectory".into(), Trajectory::merge(&parts))];
    Ok(())
}

/// `--t_offset` on the trajectories (not the reference): evo adds it to its float seconds,
/// rounding as it goes; nanosecond stamps add it in integers.
fn add_time_offset(
    bundle: &mut Bundle,
    kind: Kind,
    t_offset: f64,
    console: &Console,
) -> Result<()> {
    console.debug(SEP)?;
    let offset = sitar_estimator::seconds_to_ns(t_offset);
    for (name, t) in &mut bundle.trajectories {
        if kind == Kind::Kitti {
            bail!("{name} doesn't have timestamps - can't add time offset.");
        }
        console.info(&format!(
            "Adding time offset to {name}: {} (s)",
            sitar_evo::pyfmt::repr(t_offset)
        ))?;
        let unit = t.time_unit;
        for s in &mut t.stamps {
            *s = match unit {
                TimeUnit::Seconds | TimeUnit::RosStamp => {
                    sitar_estimator::seconds_to_ns(unit.seconds(*s) + t_offset)
                }
                TimeUnit::Nanoseconds => *s + offset,
            };
        }
        // The shifted floats are decimal seconds now (seconds_to_ns keeps them exactly).
        if unit == TimeUnit::RosStamp {
            t.time_unit = TimeUnit::Seconds;
        }
    }
    Ok(())
}

/// Each trajectory synchronised with the reference (KITTI: paired by index), keeping the
/// reference's synchronised copy per trajectory.
fn sync_with_reference(
    bundle: &mut Bundle,
    kind: Kind,
    options: &Options,
    console: &Console,
) -> Result<()> {
    let Some((ref_name, reference)) = bundle.reference.clone() else {
        bail!("Can't align or sync without a reference! (--ref)  *grunt*");
    };
    bundle.synced = true;
    if kind == Kind::Kitti {
        for (name, _) in &bundle.trajectories {
            bundle.synced_refs.insert(name.clone(), reference.clone());
        }
        return Ok(());
    }
    console.debug(SEP)?;
    let sync = sitar_evo::SyncOptions {
        t_max_diff: options.t_max_diff,
        sync_method: options.sync_method.method(),
        ..Default::default()
    };
    for (name, t) in &mut bundle.trajectories {
        console.debug(&format!("Syncing {name} with reference."))?;
        let (r, e, _) = sitar_evo::sync::synchronise(
            reference.clone(),
            t.clone(),
            &sync,
            (&ref_name, name),
            console,
        )?;
        *t = e;
        bundle.synced_refs.insert(name.clone(), r);
    }
    Ok(())
}

/// `-a`, `-s`, `--n_to_align` and `--align_origin` of the synchronised trajectories.
fn align_to_reference(bundle: &mut Bundle, options: &Options, console: &Console) -> Result<()> {
    let n = match options.n_to_align {
        -1 => None,
        n if n > 0 => Some(n as usize),
        n => bail!("--n_to_align must be -1 (all poses) or positive, got {n}"),
    };
    if options.align || options.correct_scale {
        console.debug(SEP)?;
        let alignment = match (options.align, options.correct_scale) {
            (true, true) => Alignment::Sim3,
            (true, false) => Alignment::Se3,
            _ => Alignment::ScaleOnly,
        };
        for (name, t) in &mut bundle.trajectories {
            console.debug(&format!("Aligning {name} to reference."))?;
            let r = &bundle.synced_refs[name];
            if r.len() != t.len() {
                bail!(
                    "{name}: {} poses, the reference {}: align needs equal numbers (KITTI poses pair by index)",
                    t.len(),
                    r.len()
                );
            }
            sitar_evo::align::align_logged(t, r, alignment, n, console)
                .with_context(|| format!("aligning {name}"))?;
        }
    }
    if options.align_origin {
        console.debug(SEP)?;
        for (name, t) in &mut bundle.trajectories {
            console.debug(&format!("Aligning {name}'s origin to reference."))?;
            let r = &bundle.synced_refs[name];
            align_first(t, r, Alignment::Origin, None)
                .with_context(|| format!("aligning {name}'s origin"))?;
        }
    }
    Ok(())
}

/// `--transform_left|right FILE` (`--invert_transform`, `--propagate_transform`) on the
/// trajectories (not the reference).
fn transform(bundle: &mut Bundle, path: &Path, options: &Options, console: &Console) -> Result<()> {
    let mut transform = load_transform(path)?;
    if options.invert_transform {
        transform = transform.inverse();
    }
    let right = options.transform_right.is_some();
    console.debug(SEP)?;
    console.debug(&format!(
        "Applying a {}-multiplicative transformation:\n{transform}",
        if right { "right" } else { "left" }
    ))?;
    for (_, t) in &mut bundle.trajectories {
        apply_transform(t, transform, right, options.propagate_transform)?;
    }
    Ok(())
}

/// `--project_to_plane` on every trajectory and synchronised reference.
fn project(bundle: &mut Bundle, plane: PlaneArg, console: &Console) -> Result<()> {
    console.debug(SEP)?;
    console.debug(&format!(
        "Projecting trajectories to {} plane.",
        plane.name()
    ))?;
    each(bundle, &mut |t| {
        t.project(plane.plane());
        Ok(())
    })?;
    for r in bundle.synced_refs.values_mut() {
        r.project(plane.plane());
    }
    Ok(())
}

/// evo's `load_transform`: a 4×4 matrix as text or `.npy`, or JSON with `x y z qx qy qz qw`
/// (and optionally `scale`); it must be an SE(3) or Sim(3) matrix.
fn load_transform(path: &Path) -> Result<DMat4> {
    let bytes = std::fs::read(path)
        .with_context(|| format!("{}: cannot read the transformation", path.display()))?;
    let name = path.display();
    let rows: Vec<f64> = if bytes.starts_with(b"\x93NUMPY") {
        let array =
            crate::results::archive::parse_npy(&bytes).with_context(|| format!("{name}"))?;
        if array.shape != [4, 4] {
            bail!(
                "{name} doesn't contain a 4x4 matrix (shape {:?})",
                array.shape
            );
        }
        array.data
    } else if bytes.trim_ascii_start().starts_with(b"{") {
        let json: serde_json::Value =
            serde_json::from_slice(&bytes).with_context(|| format!("{name}: not JSON"))?;
        let get = |k: &str| json[k].as_f64();
        let keys = ["x", "y", "z", "qx", "qy", "qz", "qw"];
        let values: Option<Vec<f64>> = keys.iter().map(|k| get(k)).collect();
        let Some(v) = values else {
            bail!("invalid transform file {name} - expected keys {keys:?}");
        };
        let scale = get("scale").unwrap_or(1.0);
        let q = DQuat::from_xyzw(v[3], v[4], v[5], v[6]).normalize();
        let m = DMat4::from_scale_rotation_translation(
            DVec3::splat(scale),
            q,
            DVec3::new(v[0], v[1], v[2]),
        );
        return Ok(m);
    } else {
        let text = String::from_utf8_lossy(&bytes);
        text.lines()
            .filter(|l| !l.trim_start().starts_with('#'))
            .flat_map(str::split_whitespace)
            .map(|t| {
                t.parse::<f64>()
                    .with_context(|| format!("{name}: '{t}' is not a number"))
            })
            .collect::<Result<_>>()?
    };
    if rows.len() != 16 {
        bail!(
            "{name} doesn't contain a valid Sim(3) or SE(3) matrix ({} values, 16 expected)",
            rows.len()
        );
    }
    let m = DMat4::from_cols_slice(&rows).transpose();
    let linear = DMat3::from_mat4(m);
    let scale = linear.determinant().cbrt();
    let rotation = linear * (1.0 / scale);
    let orthonormal = (rotation * rotation.transpose() - DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .all(|e| e.abs() < 1e-6);
    if !(scale > 0.0 && orthonormal && m.row(3).abs_diff_eq(glam::DVec4::W, 1e-9)) {
        bail!("{name} doesn't contain a valid Sim(3) or SE(3) matrix");
    }
    Ok(m)
}

/// A pose as a 4×4 matrix.
fn pose_matrix(t: &Trajectory, i: usize) -> DMat4 {
    DMat4::from_rotation_translation(t.orientations[i], t.positions[i])
}

/// Applies `m` to every pose: `m·P` (left), `P·m` (right) or, with `propagate`, the
/// relative motions right-multiplied and chained from the first pose (evo's `transform`).
fn apply_transform(t: &mut Trajectory, m: DMat4, right: bool, propagate: bool) -> Result<()> {
    let poses: Vec<DMat4> = (0..t.len()).map(|i| pose_matrix(t, i)).collect();
    let new: Vec<DMat4> = if right && propagate {
        let mut out = vec![poses[0]];
        for w in poses.windows(2) {
            let relative = w[0].inverse() * w[1] * m;
            let last = *out.last().unwrap_or(&poses[0]);
            out.push(last * relative);
        }
        out
    } else if right {
        poses.iter().map(|p| *p * m).collect()
    } else {
        poses.iter().map(|p| m * *p).collect()
    };
    for (i, p) in new.iter().enumerate() {
        let (scale, rotation, translation) = p.to_scale_rotation_translation();
        if !(scale - DVec3::ONE).abs().max_element().is_finite() {
            bail!("the transformation gives a non-finite pose");
        }
        t.positions[i] = translation;
        t.orientations[i] = rotation.normalize();
    }
    Ok(())
}

/// evo's compact name: the file stem unless --show_full_names (a bag's topic stays whole).
fn compact(name: &str, options: &Options, from_bag: bool) -> String {
    if options.show_full_names || from_bag {
        name.to_owned()
    } else {
        Path::new(name)
            .file_stem()
            .map_or_else(|| name.to_owned(), |s| s.to_string_lossy().into_owned())
    }
}

/// evo's per-trajectory information lines.
fn print_traj_info(
    name: &str,
    t: &Trajectory,
    unit_quaternions: bool,
    frame_id: Option<&str>,
    options: &Options,
    kind: Kind,
    console: &Console,
) -> Result<()> {
    console.info(SEP)?;
    console.info(&format!("name:\t{name}"))?;
    let timed = kind != Kind::Kitti;
    let repr = |v: f64| sitar_evo::pyfmt::repr(v);
    if !(console.is_verbose() || options.full_check) {
        let mut line = format!("{} poses, {:.3}m path length", t.len(), t.path_length());
        if timed {
            let duration =
                t.time_unit.seconds(t.stamps[t.len() - 1]) - t.time_unit.seconds(t.stamps[0]);
            line += &format!(", {duration:.3}s duration");
        }
        return console.info(&format!("infos:\t{line}"));
    }
    let mut infos = vec![
        ("nr. of poses".to_owned(), t.len().to_string()),
        (
            "path length (m)".to_owned(),
            sitar_evo::pyfmt::repr(t.path_length()),
        ),
        (
            "pos_start (m)".to_owned(),
            sitar_evo::pyfmt::numpy_vector(&t.positions[0].to_array()),
        ),
        (
            "pos_end (m)".to_owned(),
            sitar_evo::pyfmt::numpy_vector(&t.positions[t.len() - 1].to_array()),
        ),
    ];
    if timed {
        let (first, last) = (t.stamps[0], t.stamps[t.len() - 1]);
        infos.push((
            "duration (s)".into(),
            repr(t.time_unit.seconds(last) - t.time_unit.seconds(first)),
        ));
        infos.push(("t_start (s)".into(), repr(t.time_unit.seconds(first))));
        infos.push(("t_end (s)".into(), repr(t.time_unit.seconds(last))));
    }
    infos.sort();
    console.info(&dict("infos", &infos))?;
    if let Some(frame) = frame_id {
        console.info(&dict("meta", &[("frame_id".to_owned(), frame.to_owned())]))?;
    }
    if options.full_check {
        let mut checks = vec![
            ("array shapes".to_owned(), "ok".to_owned()),
            ("SE(3) conform".to_owned(), "yes".to_owned()),
            (
                "quaternions".to_owned(),
                if unit_quaternions {
                    "ok"
                } else {
                    "invalid (must be unit quaternions)"
                }
                .to_owned(),
            ),
        ];
        if timed {
            checks.push(("nr. of stamps".into(), "ok".into()));
            let ascending = t.stamps.windows(2).all(|w| w[0] < w[1]);
            checks.push((
                "timestamps".into(),
                if ascending {
                    "ok"
                } else {
                    "wrong, not ascending or duplicates"
                }
                .into(),
            ));
        }
        checks.sort();
        console.info(&dict("checks", &checks))?;
        let mut text = "stats:".to_owned();
        match statistics(t, timed) {
            Ok(stats) => {
                let mut stats: Vec<_> = stats.into_iter().collect();
                stats.sort_by(|a, b| a.0.cmp(&b.0));
                for (k, v) in stats {
                    text += &format!("\n\t{k}\t{v:.6}");
                }
            }
            Err(e) => console.warn(&format!("Failed to compute all trajectory stats: {e}")),
        }
        console.info(&text)?;
    }
    Ok(())
}

fn dict(title: &str, entries: &[(String, String)]) -> String {
    let mut text = format!("{title}:");
    for (k, v) in entries {
        text += &format!("\n\t{k}\t{v}");
    }
    text
}

/// evo's `get_statistics`: speeds between poses and stamp steps (empty without stamps or
/// with fewer than two poses); a repeated or decreasing stamp is an error, as in evo.
fn statistics(t: &Trajectory, timed: bool) -> Result<Vec<(String, f64)>> {
    if !timed || t.len() < 2 {
        return Ok(Vec::new());
    }
    let mut speeds = Vec::with_capacity(t.len() - 1);
    let mut steps = Vec::with_capacity(t.len() - 1);
    for i in 0..t.len() - 1 {
        let dt = t.time_unit.seconds(t.stamps[i + 1]) - t.time_unit.seconds(t.stamps[i]);
        if dt <= 0.0 {
            bail!(
                "bad timestamps: {} & {}",
                sitar_evo::pyfmt::repr(t.time_unit.seconds(t.stamps[i])),
                sitar_evo::pyfmt::repr(t.time_unit.seconds(t.stamps[i + 1]))
            );
        }
        speeds.push((t.positions[i + 1] - t.positions[i]).length() / dt);
        steps.push(dt);
    }
    let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (vmax, vmin, vmean) = (max(&speeds), min(&speeds), mean(&speeds));
    Ok(vec![
        ("v_max (m/s)".into(), vmax),
        ("v_min (m/s)".into(), vmin),
        ("v_avg (m/s)".into(), vmean),
        ("v_max (km/h)".into(), vmax * 3.6),
        ("v_min (km/h)".into(), vmin * 3.6),
        ("v_avg (km/h)".into(), vmean * 3.6),
        ("dt_max (s)".into(), max(&steps)),
        ("dt_min (s)".into(), min(&steps)),
        ("dt_avg (s)".into(), mean(&steps)),
    ])
}

fn print_infos(bundle: &Bundle, options: &Options, kind: Kind, console: &Console) -> Result<()> {
    let trajectories = bundle.trajectories.iter().map(|(n, t)| (n, t, false));
    let reference = bundle.reference.iter().map(|(n, t)| (n, t, true));
    for (name, t, is_reference) in trajectories.chain(reference) {
        // Transformed poses (not the reference) have quaternions re-derived from their
        // matrices (unit norm).
        let unit =
            !bundle.off_unit.contains(name) || (!is_reference && rederives_quaternions(options));
        print_traj_info(
            &compact(name, options, bundle.from_bag),
            t,
            unit,
            bundle.frames.get(name).map(String::as_str),
            options,
            kind,
            console,
        )?;
    }
    Ok(())
}

/// Whether evo re-derives the (non-reference) trajectories' quaternions from transformed
/// pose matrices: any alignment, transformation or projection.
fn rederives_quaternions(options: &Options) -> bool {
    options.align
        || options.correct_scale
        || options.align_origin
        || options.transform_left.is_some()
        || options.transform_right.is_some()
        || options.project_to_plane.is_some()
}

/// The file stem evo exports a trajectory under.
fn file_stem(name: &str) -> String {
    Path::new(name)
        .file_stem()
        .map_or_else(|| name.to_owned(), |s| s.to_string_lossy().into_owned())
}

/// evo's file stem of a trajectory: a bag topic without its leading slash, `/` and `:`
/// turned into `_`; a file's stem.
fn export_stem(name: &str, from_bag: bool) -> String {
    if from_bag {
        let name = name.strip_prefix('/').unwrap_or(name);
        name.replace([':', '/'], "_")
    } else {
        file_stem(name)
    }
}

/// evo's topic for a trajectory saved in a bag: a bag topic with `:` turned into `/`; a
/// file's stem with spaces as `_` behind a slash.
fn export_topic(name: &str, from_bag: bool) -> String {
    if from_bag {
        name.replace(':', "/")
    } else {
        format!("/{}", file_stem(name).replace(' ', "_"))
    }
}

/// `--save_as_bag` / `--save_as_bag2`: the trajectories (reference last) as PoseStamped
/// topics in `<date>.bag` and the bag directory `<date>` (MCAP), named as evo names them
/// (the date in UTC).
fn save_bags(
    bundle: &Bundle,
    named: &[(&String, Trajectory)],
    options: &Options,
    console: &Console,
) -> Result<()> {
    let date = jiff::Timestamp::now()
        .strftime("%Y-%m-%d-%H-%M-%S")
        .to_string();
    let topics: Vec<(String, String)> = named
        .iter()
        .map(|(name, _)| {
            let frame = bundle.frames.get(*name).map_or("world", String::as_str);
            (export_topic(name, bundle.from_bag), frame.to_owned())
        })
        .collect();
    let poses: Vec<sitar_estimator::PoseTopic<'_>> = named
        .iter()
        .zip(&topics)
        .map(|((_, t), (topic, frame))| sitar_estimator::PoseTopic {
            topic,
            frame_id: frame,
            trajectory: t,
        })
        .collect();
    let saved = |topics: &[(String, String)]| -> Result<()> {
        for (topic, _) in topics {
            console.info(&format!("Saved geometry_msgs/PoseStamped topic: {topic}"))?;
        }
        Ok(())
    };
    if options.save_as_bag {
        let dest = PathBuf::from(format!("{date}.bag"));
        console.info(SEP)?;
        console.info(&format!("Saving trajectories to {}...", dest.display()))?;
        if dest.exists() {
            bail!("{}: exists already, not overwriting", dest.display());
        }
        std::fs::write(&dest, sitar_estimator::ros1_bag(&poses))
            .with_context(|| format!("{}: cannot write", dest.display()))?;
        saved(&topics)?;
    }
    if options.save_as_bag2 {
        let dest = PathBuf::from(&date);
        console.info(SEP)?;
        console.info(&format!("Saving trajectories to {}...", dest.display()))?;
        if dest.exists() {
            bail!("{}: exists already, not overwriting", dest.display());
        }
        let file = format!("{date}.mcap");
        let bytes = sitar_estimator::mcap_bag(&poses)?;
        std::fs::create_dir(&dest).with_context(|| format!("{}: cannot create", dest.display()))?;
        std::fs::write(dest.join(&file), bytes)
            .with_context(|| format!("{}: cannot write", dest.join(&file).display()))?;
        std::fs::write(
            dest.join("metadata.yaml"),
            sitar_estimator::rosbag2_metadata(&file, &poses),
        )
        .with_context(|| format!("{}: cannot write", dest.display()))?;
        saved(&topics)?;
    }
    Ok(())
}

fn export(bundle: &Bundle, options: &Options, kind: Kind, console: &Console) -> Result<()> {
    // evo re-derives quaternions from the pose matrices once it has transformed the poses,
    // with w ≥ 0; sitar writes the same sign.
    let transformed = rederives_quaternions(options);
    let canonical = |name: &String, t: &Trajectory| -> Trajectory {
        let mut t = t.clone();
        let is_reference = bundle.reference.as_ref().is_some_and(|(r, _)| r == name);
        if transformed && !is_reference {
            for q in &mut t.orientations {
                if q.w < 0.0 {
                    *q = -*q;
                }
            }
        }
        t
    };
    let named = || bundle.trajectories.iter().chain(bundle.reference.iter());
    let overwrite = |path: &Path| {
        if path.exists() {
            console.warn(&format!("{} exists, overwriting", path.display()));
        }
    };
    if options.save_as_tum {
        console.info(SEP)?;
        if kind == Kind::Kitti {
            bail!("KITTI poses have no timestamps: --save_as_tum needs tum or euroc input");
        }
        for (name, t) in named() {
            let dest = PathBuf::from(format!("{}.tum", export_stem(name, bundle.from_bag)));
            overwrite(&dest);
            let mut out = Vec::new();
            write_tum(&canonical(name, t), &mut out).context("writing TUM")?;
            std::fs::write(&dest, out)
                .with_context(|| format!("{}: cannot write", dest.display()))?;
            console.info(&format!("Trajectory saved to: {}", dest.display()))?;
        }
    }
    if options.save_as_kitti {
        console.info(SEP)?;
        for (name, t) in named() {
            let dest = PathBuf::from(format!("{}.kitti", export_stem(name, bundle.from_bag)));
            overwrite(&dest);
            std::fs::write(&dest, kitti_text(t))
                .with_context(|| format!("{}: cannot write", dest.display()))?;
            console.info(&format!("Poses saved to: {}", dest.display()))?;
        }
    }
    if options.save_as_bag || options.save_as_bag2 {
        if kind == Kind::Kitti {
            bail!(
                "KITTI poses have no timestamps: --save_as_bag and --save_as_bag2 need stamped input"
            );
        }
        let all: Vec<(&String, Trajectory)> = named().map(|(n, t)| (n, canonical(n, t))).collect();
        save_bags(bundle, &all, options, console)?;
    }
    if let Some(path) = &options.save_table {
        console.debug(SEP)?;
        overwrite(path);
        std::fs::write(path, stats_table(bundle, kind)?)
            .with_context(|| format!("{}: cannot write the table", path.display()))?;
    }
    Ok(())
}

/// KITTI lines: the first three rows of each pose matrix, full precision.
fn kitti_text(t: &Trajectory) -> String {
    let mut out = String::with_capacity(t.len() * 200);
    for i in 0..t.len() {
        let r = DMat3::from_quat(t.orientations[i]);
        let p = t.positions[i];
        let row = |k: usize| [r.col(0)[k], r.col(1)[k], r.col(2)[k], p[k]];
        let values: Vec<String> = (0..3).flat_map(row).map(|v| format!("{v:e}")).collect();
        out += &values.join(" ");
        out.push('\n');
    }
    out
}

/// evo's `--save_table` CSV: one column per trajectory, one row per number (transposed, as
/// evo's default `table_export_transpose`).
fn stats_table(bundle: &Bundle, kind: Kind) -> Result<String> {
    let timed = kind != Kind::Kitti;
    let mut columns = Vec::new();
    for (name, t) in &bundle.trajectories {
        let mut rows = vec![
            ("nr. of poses".to_owned(), t.len() as f64),
            ("path length (m)".to_owned(), t.path_length()),
        ];
        if timed {
            let (first, last) = (t.stamps[0], t.stamps[t.len() - 1]);
            rows.push((
                "duration (s)".into(),
                t.time_unit.seconds(last) - t.time_unit.seconds(first),
            ));
            rows.push(("t_start (s)".into(), t.time_unit.seconds(first)));
            rows.push(("t_end (s)".into(), t.time_unit.seconds(last)));
        }
        rows.extend(statistics(t, timed).unwrap_or_default());
        columns.push((name.clone(), rows));
    }
    let mut out = String::from(",");
    out += &columns
        .iter()
        .map(|c| c.0.clone())
        .collect::<Vec<_>>()
        .join(",");
    out.push('\n');
    let keys: Vec<String> = columns
        .first()
        .map(|c| c.1.iter().map(|r| r.0.clone()).collect())
        .unwrap_or_default();
    for key in keys {
        out += &key;
        for (_, rows) in &columns {
            out.push(',');
            if let Some((_, v)) = rows.iter().find(|r| r.0 == key) {
                out += &sitar_evo::pyfmt::repr(*v);
            }
        }
        out.push('\n');
    }
    Ok(out)
}

/// evo's speeds plot of `t`: the speed between each pose and the one before, at the newer
/// pose's `x`. As evo, a step whose stamps do not increase leaves the whole trajectory out
/// of the plot: `Err` carries the first such pair of stamps (seconds) for the warning.
fn speeds(t: &Trajectory, x: impl Fn(usize) -> f64) -> Result<Vec<(f64, f64)>, (f64, f64)> {
    (1..t.len())
        .map(|i| {
            let (t0, t1) = (
                t.time_unit.seconds(t.stamps[i - 1]),
                t.time_unit.seconds(t.stamps[i]),
            );
            if t1 - t0 > 0.0 {
                Ok((
                    x(i),
                    (t.positions[i] - t.positions[i - 1]).length() / (t1 - t0),
                ))
            } else {
                Err((t0, t1))
            }
        })
        .collect()
}

/// A float as Python's `str` prints it (shortest round trip, `1.0` not `1`), for evo's
/// words in warnings.
fn python_str(v: f64) -> String {
    let s = v.to_string();
    if v.is_finite() && !s.contains(['.', 'e']) {
        format!("{s}.0")
    } else {
        s
    }
}

/// evo_traj's figures: trajectories, xyz, rpy and (with stamps) speeds.
fn plot(bundle: &Bundle, options: &Options, kind: Kind, console: &Console) -> Result<()> {
    let timed = kind != Kind::Kitti;
    let start = if options.plot_relative_time && timed {
        bundle
            .reference
            .as_ref()
            .map(|(_, r)| r.stamps[0])
            .or_else(|| bundle.trajectories.iter().map(|(_, t)| t.stamps[0]).min())
    } else {
        None
    };
    let x = |t: &Trajectory, i: usize| -> f64 {
        if timed {
            t.time_unit.seconds(t.stamps[i]) - t.time_unit.seconds(start.unwrap_or(0))
        } else {
            i as f64
        }
    };
    let mut all: Vec<(String, &Trajectory, RGBColor3, bool)> = Vec::new();
    if let Some((name, r)) = &bundle.reference {
        all.push((
            compact(name, options, bundle.from_bag),
            r,
            RGBColor3(0x44, 0x44, 0x44),
            true,
        ));
    }
    for (k, (name, t)) in bundle.trajectories.iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        all.push((
            compact(name, options, bundle.from_bag),
            t,
            RGBColor3(c.0, c.1, c.2),
            false,
        ));
    }
    let colour = |c: &RGBColor3| plotters::style::RGBColor(c.0, c.1, c.2);
    let trajectories = Drawing::Trajectories {
        title: "evo_traj - trajectory plot".into(),
        mode: options.plot_mode,
        paths: all
            .iter()
            .map(|(name, t, c, dashed)| Path3 {
                name: name.clone(),
                points: t.positions.iter().map(|p| p.to_array()).collect(),
                colour: colour(c),
                dashed: *dashed,
            })
            .collect(),
    };
    let x_label = if timed { "t (s)" } else { "index" };
    let panel = |label: &str, value: &dyn Fn(&Trajectory, usize) -> f64| -> (String, Vec<Series>) {
        (
            label.to_owned(),
            all.iter()
                .map(|(name, t, c, dashed)| Series {
                    name: name.clone(),
                    points: (0..t.len()).map(|i| (x(t, i), value(t, i))).collect(),
                    colour: colour(c),
                    dashed: *dashed,
                    markers: false,
                })
                .collect(),
        )
    };
    let xyz = Drawing::Panels {
        title: "xyz".into(),
        x_label: x_label.into(),
        panels: vec![
            panel("x (m)", &|t, i| t.positions[i].x),
            panel("y (m)", &|t, i| t.positions[i].y),
            panel("z (m)", &|t, i| t.positions[i].z),
        ],
        y_from_zero: false,
    };
    let euler = |t: &Trajectory, i: usize, k: usize| {
        sitar_estimator::euler_sxyz(DMat3::from_quat(t.orientations[i]))[k].to_degrees()
    };
    let rpy = Drawing::Panels {
        title: "rpy (euler_angle_sequence: sxyz)".into(),
        x_label: x_label.into(),
        panels: vec![
            panel("roll (deg)", &|t, i| euler(t, i, 0)),
            panel("pitch (deg)", &|t, i| euler(t, i, 1)),
            panel("yaw (deg)", &|t, i| euler(t, i, 2)),
        ],
        y_from_zero: false,
    };
    let mut speed_series = Vec::new();
    for (name, t, c, dashed) in &all {
        let points = match speeds(t, |i| x(t, i)) {
            Ok(points) => points,
            Err((t0, t1)) => {
                console.warn(&format!(
                    "Can't plot speeds of {name}: bad timestamps: {} & {}",
                    python_str(t0),
                    python_str(t1)
                ));
                continue;
            }
        };
        speed_series.push(Series {
            name: name.clone(),
            points,
            colour: colour(c),
            dashed: *dashed,
            markers: false,
        });
    }
    let speeds = Drawing::Panels {
        title: "speeds".into(),
        x_label: x_label.into(),
        panels: vec![("v (m/s)".to_owned(), speed_series)],
        y_from_zero: false,
    };
    let mut pages = vec![
        ("trajectories", Page::Other(&trajectories)),
        ("xyz", Page::Other(&xyz)),
        ("rpy", Page::Other(&rpy)),
    ];
    if timed && all.iter().all(|(_, t, _, _)| t.len() >= 2) {
        pages.push(("speeds", Page::Other(&speeds)));
    }
    if options.plot {
        canvas::show(PAGE, &pages, console)?;
    }
    if let Some(path) = &options.save_plot {
        console.info(SEP)?;
        for file in canvas::save_collection(path, PAGE, &pages)? {
            console.info(&format!("Plot saved to {}", file.display()))?;
        }
    }
    Ok(())
}

/// A colour as three bytes (copyable into closures).
#[derive(Clone, Copy)]
struct RGBColor3(u8, u8, u8);

#[cfg(test)]
mod tests {
    use super::*;

    fn quiet() -> Console {
        Console::new(&UsabilityArgs {
            no_warnings: true,
            silent: true,
            ..Default::default()
        })
        .unwrap()
    }

    fn line(stamps: Vec<i64>, time_unit: TimeUnit) -> Trajectory {
        let n = stamps.len();
        Trajectory {
            stamps,
            positions: (0..n)
                .map(|i| DVec3::new(i as f64, (i * i) as f64, 0.0))
                .collect(),
            orientations: vec![DQuat::IDENTITY; n],
            time_unit,
        }
    }

    fn bundle(trajectories: Vec<Trajectory>, reference: Option<Trajectory>) -> Bundle {
        Bundle {
            trajectories: trajectories
                .into_iter()
                .enumerate()
                .map(|(i, t)| (format!("t{i}"), t))
                .collect(),
            reference: reference.map(|r| ("ref".to_owned(), r)),
            synced_refs: BTreeMap::new(),
            synced: false,
            off_unit: Default::default(),
            from_bag: false,
            frames: BTreeMap::new(),
        }
    }

    #[test]
    fn speeds_leave_out_a_trajectory_with_a_repeated_stamp_as_evo() {
        let s = TimeUnit::Seconds;
        let t = line(vec![0, 1_000_000_000, 3_000_000_000], s);
        let points = speeds(&t, |i| i as f64).unwrap();
        // (1,1)-(0,0) over 1 s; (2,4)-(1,1) over 2 s, each at the newer pose.
        assert_eq!(points, vec![(1.0, 2f64.sqrt()), (2.0, 10f64.sqrt() / 2.0)]);
        let repeated = line(vec![0, 1_000_000_000, 1_000_000_000, 3_000_000_000], s);
        assert_eq!(speeds(&repeated, |i| i as f64), Err((1.0, 1.0)));
        assert_eq!(python_str(1.0), "1.0");
        assert_eq!(python_str(1311868229.576), "1311868229.576");
    }

    #[test]
    fn merge_and_time_offset_steps() {
        let s = TimeUnit::Seconds;
        let mut b = bundle(vec![line(vec![0, 20], s), line(vec![10], s)], None);
        merge(&mut b, Kind::Tum).unwrap();
        assert_eq!(b.trajectories.len(), 1);
        assert_eq!(b.trajectories[0].1.stamps, [0, 10, 20]);
        assert!(merge(&mut bundle(vec![], None), Kind::Tum).is_err());
        assert!(merge(&mut bundle(vec![line(vec![0], s)], None), Kind::Kitti).is_err());
        // Seconds: evo's float addition (1311868226.31095 + 0.5 rounds to a float 238 ns
        // apart from its neighbours); nanoseconds: integers.
        let stamp = 1_311_868_226_310_950_000;
        let mut b = bundle(vec![line(vec![stamp], s)], Some(line(vec![stamp], s)));
        add_time_offset(&mut b, Kind::Tum, 0.5, &quiet()).unwrap();
        let want = s.seconds(stamp) + 0.5;
        assert_eq!(s.seconds(b.trajectories[0].1.stamps[0]), want);
        assert_eq!(
            b.reference.as_ref().unwrap().1.stamps,
            [stamp],
            "reference kept"
        );
        let ns = TimeUnit::Nanoseconds;
        let mut b = bundle(vec![line(vec![stamp], ns)], None);
        add_time_offset(&mut b, Kind::Tum, 0.5, &quiet()).unwrap();
        assert_eq!(b.trajectories[0].1.stamps, [stamp + 500_000_000]);
    }

    #[test]
    fn sync_align_and_project_steps() {
        let s = TimeUnit::Seconds;
        let reference = line(vec![0, 1_000_000_000, 2_000_000_000], s);
        let mut moved = line(vec![0, 1_000_000_000, 2_000_000_000, 9_000_000_000], s);
        moved.transform(DQuat::IDENTITY, DVec3::Y, 1.0);
        let mut b = bundle(vec![moved], Some(reference));
        let console = quiet();
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            args: Args,
        }
        let cli = <Cli as clap::Parser>::parse_from(["traj", "tum", "x", "--ref", "y", "-a"]);
        let Format::Tum { options, .. } = &cli.args.format else {
            panic!("parsed as tum")
        };
        sync_with_reference(&mut b, Kind::Tum, options, &console).unwrap();
        assert_eq!(
            b.trajectories[0].1.len(),
            3,
            "the unmatched pose is dropped"
        );
        align_to_reference(&mut b, options, &console).unwrap();
        let aligned = &b.trajectories[0].1;
        assert!(aligned.positions[2].abs_diff_eq(DVec3::new(2.0, 4.0, 0.0), 1e-9));
        project(&mut b, PlaneArg::Xz, &console).unwrap();
        assert!(b.trajectories[0].1.positions.iter().all(|p| p.y == 0.0));
        assert!(
            sync_with_reference(&mut bundle(vec![], None), Kind::Tum, options, &console).is_err()
        );
    }

    #[test]
    fn transforms_left_right_and_propagated() {
        let mut t = Trajectory {
            stamps: vec![0, 1, 2],
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0],
            orientations: vec![DQuat::IDENTITY; 3],
            time_unit: sitar_estimator::TimeUnit::Seconds,
        };
        let shift = DMat4::from_translation(DVec3::Y);
        let mut left = t.clone();
        apply_transform(&mut left, shift, false, false).unwrap();
        assert!(left.positions[2].abs_diff_eq(DVec3::new(2.0, 1.0, 0.0), 1e-12));
        let turn = DMat4::from_rotation_z(std::f64::consts::FRAC_PI_2);
        apply_transform(&mut t, turn, true, true).unwrap();
        // Each unit step turns a further quarter: (0,0) → (1,0) → (1,1).
        assert!(
            t.positions[2].abs_diff_eq(DVec3::new(1.0, 1.0, 0.0), 1e-12),
            "{}",
            t.positions[2]
        );
    }
}
