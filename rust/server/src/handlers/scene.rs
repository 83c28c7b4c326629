//! `GET /v1/sessions/{id}/scene.glb`: the session's scene as glTF 2.0 binary.

use axum::extract::State;
use axum::http::header;
use axum::response::{IntoResponse, Response};

use crate::Error;
use crate::http::{AppState, Found};
use crate::scene;

/// `GET /v1/sessions/{id}/scene.glb`: trajectory by class, frustums, markers, surface points.
pub(crate) async fn glb(State(shared): AppState, Found(session): Found) -> Result<Response, Error> {
    let glb = tokio::task::spawn_blocking(move || {
        let loaded = scene::load(&shared, &session)?;
        sitar_scene::to_glb(&sitar_scene::SceneParts::from_session(&loaded.0))
            .map_err(|e| Error::Conflict(format!("no scene for session {}: {e}", session.id)))
    })
    .await
    .map_err(|e| Error::Internal(format!("scene export: {e}")))??;
    Ok((
        [
            (header::CONTENT_TYPE, "model/gltf-binary"),
            (
                header::CONTENT_DISPOSITION,
                "attachment; filename=\"scene.glb\"",
            ),
        ],
        glb,
    )
        .into_response())
}

/// Rounds to 0.1 mm (or 1e-4 of a unit quaternion component): the view needs no more, and
/// the file of a 10-minute walk stays small.
fn r4(v: f64) -> f64 {
    (v * 1e4).round() / 1e4
}

fn flat(points: impl Iterator<Item = glam::DVec3>) -> Vec<f64> {
    points.flat_map(|p| [r4(p.x), r4(p.y), r4(p.z)]).collect()
}

/// `GET /v1/sessions/{id}/scene.json`: what the report's 3-D view draws, in glTF's frame
/// (right-handed, +Y up, metres), errors in the shown unit (cm or degrees).
pub(crate) async fn json(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    let value = tokio::task::spawn_blocking(move || -> Result<serde_json::Value, Error> {
        use sitar_core::Convention;
        let loaded = scene::load(&shared, &session)?;
        let (phone, source) = (&loaded.0, loaded.1);
        let conv = phone.config().convention;
        let to_view = |p: glam::DVec3| conv.convert_vector(p, Convention::Arcore);
        let thresholds = session.settings.thresholds(&shared.config);
        let unit = crate::report::Unit::of(&session);
        let subs = crate::regions::sub_rows(phone, thresholds);
        let plan = phone.render_plan();
        let markers = phone.markers().unwrap_or_default();
        let quat = |q: glam::DQuat| {
            let q = conv.convert_rotation(q, Convention::Arcore);
            [r4(q.x), r4(q.y), r4(q.z), r4(q.w)]
        };
        Ok(serde_json::json!({
            "unit": unit.name,
            "thresholds": [thresholds.medium * unit.scale, thresholds.high * unit.scale],
            "source": source.describe(),
            "joints": flat(plan.joints.iter().map(|j| to_view(j.position))),
            "joint_sub": plan.joints.iter().map(|j| j.subtrajectory).collect::<Vec<_>>(),
            "subs": subs.iter().map(|s| serde_json::json!({
                "t0": r4(s.t0), "t1": r4(s.t1),
                "error": s.error.map(|e| r4(e * unit.scale)),
                "class": s.class.name(),
                "length": r4(s.length_m),
            })).collect::<Vec<_>>(),
            "frustums": plan.frustums.iter().map(|f| {
                let p = to_view(f.pose.position);
                serde_json::json!({"sub": f.subtrajectory, "p": [r4(p.x), r4(p.y), r4(p.z)], "q": quat(f.pose.rotation)})
            }).collect::<Vec<_>>(),
            "markers": markers.iter().enumerate().map(|(i, m)| {
                let (p, n) = (to_view(m.position), to_view(m.normal));
                serde_json::json!({
                    "number": i + 1, "sub": m.subtrajectory, "class": m.class.name(),
                    "error": r4(m.error_m * unit.scale),
                    "p": [r4(p.x), r4(p.y), r4(p.z)], "normal": [r4(n.x), r4(n.y), r4(n.z)],
                    "q": quat(m.rotation),
                })
            }).collect::<Vec<_>>(),
            "surface": flat(phone.subtrajectories().iter().filter_map(|s| s.depth.sample().map(|d| to_view(d.point)))),
            "start": plan.start.map(|p| { let p = to_view(p.position); [r4(p.x), r4(p.y), r4(p.z)] }),
            "stop": plan.stop.map(|p| { let p = to_view(p.position); [r4(p.x), r4(p.y), r4(p.z)] }),
        }))
    })
    .await
    .map_err(|e| Error::Internal(format!("scene data: {e}")))??;
    Ok(crate::http::json_value(axum::http::StatusCode::OK, &value))
}

/// `GET /v1/sessions/{id}/trajectory.tum`: the user's trajectory as the phone logged it
/// (start, midpoints, endpoints; TUM, integer nanoseconds, the phone session's convention).
pub(crate) async fn trajectory(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    let tum = tokio::task::spawn_blocking(move || {
        scene::load(&shared, &session).map(|loaded| loaded.0.trajectory_tum())
    })
    .await
    .map_err(|e| Error::Internal(format!("trajectory: {e}")))??;
    Ok((
        [
            (header::CONTENT_TYPE, "text/plain; charset=utf-8"),
            (
                header::CONTENT_DISPOSITION,
                "attachment; filename=\"trajectory.tum\"",
            ),
        ],
        tum,
    )
        .into_response())
}

/// `GET /v1/sessions/{id}/trials.zip`: every stored trial (`trial_NNN.txt`, TUM), stored
/// uncompressed. Trials were bounded on the way in; the zip is built in memory.
pub(crate) async fn trials_zip(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    let bytes = tokio::task::spawn_blocking(move || -> Result<Vec<u8>, Error> {
        use std::io::Write as _;
        let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Stored);
        let fail = |e: zip::result::ZipError| Error::Internal(format!("trials.zip: {e}"));
        for (index, _) in shared.db.trials_in_order(&session.id)? {
            let path = shared.files.trial(&session.id, index);
            let text = std::fs::read(&path).map_err(|e| Error::io("cannot read", &path, e))?;
            zip.start_file(format!("trial_{index:03}.txt"), options)
                .map_err(fail)?;
            zip.write_all(&text)
                .map_err(|e| Error::io("cannot zip", &path, e))?;
        }
        Ok(zip.finish().map_err(fail)?.into_inner())
    })
    .await
    .map_err(|e| Error::Internal(format!("trials.zip: {e}")))??;
    Ok((
        [
            (header::CONTENT_TYPE, "application/zip"),
            (
                header::CONTENT_DISPOSITION,
                "attachment; filename=\"trials.zip\"",
            ),
        ],
        bytes,
    )
        .into_response())
}
