//! `GET /v1/sessions/{id}/scene.glb`: the session's scene as glTF 2.0 binary.

use axum::extract::State;
use axum::response::Response;

use crate::Error;
use crate::http::helpers::{AppState, Found, attachment, blocking};
use crate::report::scene;
use crate::storage::keys::SessionObject;

/// `GET /v1/sessions/{id}/scene.glb`: trajectory by class, frustums, markers, surface points.
pub(crate) async fn glb(State(shared): AppState, Found(session): Found) -> Result<Response, Error> {
    let glb = blocking("scene export", move || {
        let loaded = scene::load(&shared, &session)?;
        sitar_scene::to_glb(&sitar_scene::SceneParts::from_session(&loaded.0))
            .map_err(|e| Error::Conflict(format!("no scene for session {}: {e}", session.id)))
    })
    .await?;
    Ok(attachment("model/gltf-binary", "scene.glb", glb))
}

/// `GET /v1/sessions/{id}/scene.json`: what the report's 3-D view draws
/// (`crate::report::scene_view`, bounded for any walk length).
pub(crate) async fn json(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    let value = blocking("scene data", move || {
        let loaded = scene::load(&shared, &session)?;
        let (phone, source) = (&loaded.0, loaded.1);
        let thresholds = session
            .settings
            .thresholds(shared.config.thresholds, shared.config.thresholds_deg);
        let subs = crate::report::regions::sub_rows(phone, thresholds);
        Ok(crate::report::scene_view::scene_json(
            phone,
            &subs,
            thresholds,
            &crate::report::page::Unit::of(&session),
            source.describe(),
        ))
    })
    .await?;
    Ok(crate::http::helpers::json_value(
        axum::http::StatusCode::OK,
        &value,
    ))
}

/// `GET /v1/sessions/{id}/trajectory.tum`: the user's trajectory as the phone logged it
/// (start, midpoints, endpoints; TUM, integer nanoseconds): the phone's own `trajectory.txt`
/// when it sent one, else as the scene rebuilt it.
pub(crate) async fn trajectory(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    let tum = blocking("trajectory", move || {
        if let Some(sent) = shared
            .blobs
            .get(&session.id, SessionObject::PhoneTrajectory)?
        {
            return String::from_utf8(sent)
                .map_err(|e| Error::Internal(format!("stored trajectory.txt: {e}")));
        }
        scene::load(&shared, &session).map(|loaded| loaded.0.trajectory_tum())
    })
    .await?;
    Ok(attachment(
        "text/plain; charset=utf-8",
        "trajectory.tum",
        tum.into_bytes(),
    ))
}

/// `GET /v1/sessions/{id}/trials.zip`: every stored trial (`trial_NNN.txt`, TUM), stored
/// uncompressed. Trials were bounded on the way in; the zip is built in memory.
pub(crate) async fn trials_zip(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    let bytes = blocking("trials.zip", move || {
        use std::io::Write as _;
        let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Stored);
        let fail = |e: zip::result::ZipError| Error::Internal(format!("trials.zip: {e}"));
        for (index, _) in shared.db.trials_in_order(&session.id)? {
            let text = crate::ingest::trials::read_trial(&shared, &session.id, index)?;
            zip.start_file(format!("trial_{index:03}.txt"), options)
                .map_err(fail)?;
            zip.write_all(&text)
                .map_err(|e| Error::Internal(format!("trials.zip: trial {index}: {e}")))?;
        }
        Ok(zip.finish().map_err(fail)?.into_inner())
    })
    .await?;
    Ok(attachment("application/zip", "trials.zip", bytes))
}
