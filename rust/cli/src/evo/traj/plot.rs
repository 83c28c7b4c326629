//! `sitar traj`'s plots: the trajectories, their xyz and rpy over time, and their speeds.

use anyhow::Result;
use glam::DMat3;
use sitar_estimator::Trajectory;

use crate::evo::traj::args::Options;
use crate::evo::traj::bundle::{Bundle, Kind};
use crate::evo::traj::info::compact;
use crate::evo::traj::table::{python_str, speeds};
use crate::figures::canvas::{self, Page};
use crate::figures::figure::{Drawing, PAGE, PALETTE, Path3, Series};
use crate::io::console::{Console, SEP};

/// evo_traj's figures: trajectories, xyz, rpy and (with stamps) speeds.
pub(super) fn plot(
    bundle: &Bundle,
    options: &Options,
    kind: Kind,
    console: &Console,
) -> Result<()> {
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
pub(super) struct RGBColor3(u8, u8, u8);
