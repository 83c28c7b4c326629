//! `--save_as_tum`, `--save_as_kitti`, `--save_as_bag`/`--save_as_bag2`: writing the
//! trajectories out as evo_traj names them.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use glam::DMat3;
use sitar_estimator::{Trajectory, write_tum};

use crate::evo::traj::args::Options;
use crate::evo::traj::bundle::{Bundle, Kind};
use crate::evo::traj::info::rederives_quaternions;
use crate::evo::traj::table::stats_table;
use crate::io::console::{Console, SEP};

/// The file stem evo exports a trajectory under.
pub(super) fn file_stem(name: &str) -> String {
    Path::new(name)
        .file_stem()
        .map_or_else(|| name.to_owned(), |s| s.to_string_lossy().into_owned())
}

/// evo's file stem of a trajectory: a bag topic without its leading slash, `/` and `:`
/// turned into `_`; a file's stem.
pub(super) fn export_stem(name: &str, from_bag: bool) -> String {
    if from_bag {
        let name = name.strip_prefix('/').unwrap_or(name);
        name.replace([':', '/'], "_")
    } else {
        file_stem(name)
    }
}

/// evo's topic for a trajectory saved in a bag: a bag topic with `:` turned into `/`; a
/// file's stem with spaces as `_` behind a slash.
pub(super) fn export_topic(name: &str, from_bag: bool) -> String {
    if from_bag {
        name.replace(':', "/")
    } else {
        format!("/{}", file_stem(name).replace(' ', "_"))
    }
}

/// `--save_as_bag` / `--save_as_bag2`: the trajectories (reference last) as PoseStamped
/// topics in `<date>.bag` and the bag directory `<date>` (MCAP), named as evo names them
/// (the date in UTC).
pub(super) fn save_bags(
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

pub(super) fn export(
    bundle: &Bundle,
    options: &Options,
    kind: Kind,
    console: &Console,
) -> Result<()> {
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
pub(super) fn kitti_text(t: &Trajectory) -> String {
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
