//! `sitar traj`'s information on each trajectory: evo_traj's infos, checks and statistics.

use std::path::Path;

use anyhow::{Result, bail};
use sitar_estimator::Trajectory;

use crate::evo::traj::args::Options;
use crate::evo::traj::bundle::{Bundle, Kind};
use crate::io::console::{Console, SEP};

/// evo's compact name: the file stem unless --show_full_names (a bag's topic stays whole).
pub(super) fn compact(name: &str, options: &Options, from_bag: bool) -> String {
    if options.show_full_names || from_bag {
        name.to_owned()
    } else {
        Path::new(name)
            .file_stem()
            .map_or_else(|| name.to_owned(), |s| s.to_string_lossy().into_owned())
    }
}

/// evo's per-trajectory information lines.
pub(super) fn print_traj_info(
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

pub(super) fn dict(title: &str, entries: &[(String, String)]) -> String {
    let mut text = format!("{title}:");
    for (k, v) in entries {
        text += &format!("\n\t{k}\t{v}");
    }
    text
}

/// evo's `get_statistics`: speeds between poses and stamp steps (empty without stamps or
/// with fewer than two poses); a repeated or decreasing stamp is an error, as in evo.
pub(super) fn statistics(t: &Trajectory, timed: bool) -> Result<Vec<(String, f64)>> {
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

pub(super) fn print_infos(
    bundle: &Bundle,
    options: &Options,
    kind: Kind,
    console: &Console,
) -> Result<()> {
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
pub(super) fn rederives_quaternions(options: &Options) -> bool {
    options.align
        || options.correct_scale
        || options.align_origin
        || options.transform_left.is_some()
        || options.transform_right.is_some()
        || options.project_to_plane.is_some()
}
