//! What the report's 3-D view draws (`GET /v1/sessions/{id}/scene.json`), in glTF's frame
//! (right-handed, +Y up, metres), errors in the shown unit (cm or degrees).
//!
//! Bounded whatever the walk's length: past the `MAX_VIEW_*` counts below, the path, frustums
//! and surface points are thinned evenly for display (first and last kept), and only the
//! sub-trajectories something drawn refers to are sent (as columns: `subs.index`,
//! `subs.t0`, …). `downsampled` says what was thinned,
//! and the page says so; statistics elsewhere on the page come from all the data.

use glam::{DQuat, DVec3};
use serde_json::{Value, json};
use sitar_core::{Convention, Session as Phone, Thresholds};

use crate::report::page::Unit;
use crate::report::regions::SubRow;
use crate::report::thinning::thin;

/// Path points (logged poses) drawn: a 10-minute walk has 3 600.
pub(crate) const MAX_VIEW_JOINTS: usize = 6_000;
/// Camera frustums drawn.
pub(crate) const MAX_VIEW_FRUSTUMS: usize = 1_500;
/// Depth-sampled surface points drawn.
pub(crate) const MAX_VIEW_SURFACE: usize = 4_000;
/// Markers drawn (the phone places at most one per 0.5 m of surface).
pub(crate) const MAX_VIEW_MARKERS: usize = 500;

/// Rounds to 0.1 mm (or 1e-4 of a unit quaternion component): the view needs no more, and
/// the file of a long walk stays small.
fn r4(v: f64) -> f64 {
    (v * 1e4).round() / 1e4
}

/// Rounds to 0.01 (of a second, a metre, a cm or degree: what the page prints).
fn r2(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

fn xyz(p: DVec3) -> [f64; 3] {
    [r4(p.x), r4(p.y), r4(p.z)]
}

/// The scene of `phone` (the backend's phone sessions are `arcore`, glTF's frame already;
/// the conversion is stated all the same), its sub-trajectories `subs` as the report
/// classifies them, and where the scene came from.
pub(crate) fn scene_json(
    phone: &Phone,
    subs: &[SubRow],
    thresholds: Thresholds,
    unit: &Unit,
    source: &str,
) -> Value {
    let conv = phone.config().convention;
    let to_view = |p: DVec3| conv.convert_vector(p, Convention::Arcore);
    let quat = |q: DQuat| {
        let q = conv.convert_rotation(q, Convention::Arcore);
        [r4(q.x), r4(q.y), r4(q.z), r4(q.w)]
    };
    let plan = phone.render_plan();
    let markers = phone.markers().unwrap_or_default();
    let (surface, normals): (Vec<DVec3>, Vec<DVec3>) = phone
        .subtrajectories()
        .iter()
        .filter_map(|s| {
            s.depth
                .sample()
                .map(|d| (to_view(d.point), to_view(d.normal)))
        })
        .unzip();
    let joints = thin(plan.joints.len(), MAX_VIEW_JOINTS);
    let frustums = thin(plan.frustums.len(), MAX_VIEW_FRUSTUMS);
    let surface_kept = thin(surface.len(), MAX_VIEW_SURFACE);
    let markers_kept = &markers[..markers.len().min(MAX_VIEW_MARKERS)];
    // The sub-trajectories something drawn refers to (all of them for a short walk).
    let mut referenced: Vec<u32> = joints
        .iter()
        .map(|&i| plan.joints[i].subtrajectory)
        .chain(frustums.iter().map(|&i| plan.frustums[i].subtrajectory))
        .chain(markers_kept.iter().map(|m| m.subtrajectory))
        .collect();
    referenced.sort_unstable();
    referenced.dedup();
    let shown: Vec<&SubRow> = referenced
        .iter()
        .filter_map(|k| subs.get(*k as usize).filter(|s| s.index == *k))
        .collect();
    // Columns, not one object per sub-trajectory: half the bytes of a long walk's file.
    let column = |f: &dyn Fn(&SubRow) -> Value| shown.iter().map(|s| f(s)).collect::<Vec<_>>();
    let shown_subs = json!({
        "index": column(&|s| json!(s.index)),
        "t0": column(&|s| json!(r2(s.t0))),
        "t1": column(&|s| json!(r2(s.t1))),
        "error": column(&|s| json!(s.error.map(|e| r2(e * unit.scale)))),
        "class": column(&|s| json!(s.class.name())),
        "length": column(&|s| json!(r2(s.length_m))),
    });
    let counts = |kept: usize, total: usize| json!({"shown": kept, "total": total});
    json!({
        "unit": unit.name,
        "thresholds": [thresholds.medium * unit.scale, thresholds.high * unit.scale],
        "source": source,
        "joints": joints.iter().flat_map(|&i| xyz(to_view(plan.joints[i].position))).collect::<Vec<_>>(),
        "joint_sub": joints.iter().map(|&i| plan.joints[i].subtrajectory).collect::<Vec<_>>(),
        "subs": shown_subs,
        "frustums": frustums.iter().map(|&i| {
            let f = &plan.frustums[i];
            json!({"sub": f.subtrajectory, "p": xyz(to_view(f.pose.position)), "q": quat(f.pose.rotation)})
        }).collect::<Vec<_>>(),
        "markers": markers_kept.iter().enumerate().map(|(i, m)| json!({
            "number": i + 1, "sub": m.subtrajectory, "class": m.class.name(),
            "error": r4(m.error_m * unit.scale),
            "tier": crate::report::regions::marker_tier(phone, m.error_m).map(|t| r4(t * unit.scale)),
            "p": xyz(to_view(m.position)), "normal": xyz(to_view(m.normal)),
            "q": quat(m.rotation),
        })).collect::<Vec<_>>(),
        "surface": surface_kept.iter().flat_map(|&i| xyz(surface[i])).collect::<Vec<_>>(),
        // The faced surface's unit normal at each surface point (the view draws a patch).
        "surface_normals": surface_kept.iter().flat_map(|&i| xyz(normals[i])).collect::<Vec<_>>(),
        "start": plan.start.map(|p| xyz(to_view(p.position))),
        "stop": plan.stop.map(|p| xyz(to_view(p.position))),
        "downsampled": {
            "joints": counts(joints.len(), plan.joints.len()),
            "frustums": counts(frustums.len(), plan.frustums.len()),
            "surface": counts(surface_kept.len(), surface.len()),
            "markers": counts(markers_kept.len(), markers.len()),
            "subs": counts(shown.len(), subs.len()),
        },
    })
}
