//! `sitar traj`'s steps on the trajectories, in evo_traj's order: downsampling and motion
//! filter, merge, time offset, sync with and alignment to `--ref`, transformation,
//! projection.

use std::path::Path;

use anyhow::{Context, Result, bail};
use sitar_estimator::{Alignment, TimeUnit, Trajectory, align_first};

use crate::evo::traj::args::Options;
use crate::evo::traj::bundle::{Bundle, Kind};
use crate::evo::traj::transforms::{apply_transform, load_transform};
use crate::io::console::{Console, SEP};
use crate::results::metric_args::PlaneArg;

/// evo_traj's steps in its order: downsample, motion filter, merge, time offset, sync,
/// alignment, transformation, projection.
pub(super) fn manipulate(
    bundle: &mut Bundle,
    kind: Kind,
    options: &Options,
    console: &Console,
) -> Result<()> {
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
pub(super) fn each(
    bundle: &mut Bundle,
    f: &mut dyn FnMut(&mut Trajectory) -> Result<()>,
) -> Result<()> {
    for (_, t) in &mut bundle.trajectories {
        f(t)?;
    }
    if let Some((_, t)) = &mut bundle.reference {
        f(t)?;
    }
    Ok(())
}

/// `--downsample` and `--motion_filter` on every trajectory, the reference included.
pub(super) fn filter(bundle: &mut Bundle, options: &Options, console: &Console) -> Result<()> {
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
pub(super) fn merge(bundle: &mut Bundle, kind: Kind) -> Result<()> {
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
pub(super) fn add_time_offset(
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
pub(super) fn sync_with_reference(
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
pub(super) fn align_to_reference(
    bundle: &mut Bundle,
    options: &Options,
    console: &Console,
) -> Result<()> {
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
pub(super) fn transform(
    bundle: &mut Bundle,
    path: &Path,
    options: &Options,
    console: &Console,
) -> Result<()> {
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
pub(super) fn project(bundle: &mut Bundle, plane: PlaneArg, console: &Console) -> Result<()> {
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

#[cfg(test)]
mod tests {
    use crate::evo::traj::args::{Args, Format};
    use crate::io::console::UsabilityArgs;
    use glam::{DQuat, DVec3};
    use std::collections::BTreeMap;

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
}
