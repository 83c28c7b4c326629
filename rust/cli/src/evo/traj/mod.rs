//! `sitar traj`: trajectory information and manipulation, as `evo_traj`: per-trajectory
//! information, checks and statistics; synchronisation with and alignment to `--ref`;
//! merge, time offset, transformations, projection; TUM/KITTI export, a statistics table and
//! the plots.

mod args;
mod bag_topics;
mod bundle;
mod export;
mod info;
mod manipulate;
mod plot;
mod table;
mod transforms;

pub use args::Args;

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Result, bail};
use sitar_estimator::Trajectory;

use crate::evo::traj::args::Format;
use crate::evo::traj::bag_topics::{BagSelection, read_bag_topics};
use crate::evo::traj::bundle::{Bundle, Kind};
use crate::evo::traj::export::export;
use crate::evo::traj::info::print_infos;
use crate::evo::traj::manipulate::manipulate;
use crate::evo::traj::plot::plot;
use crate::io::console::{Console, SEP};
use sitar_evo::read::{read_euroc_evo, read_kitti_evo, read_tum_evo};

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
