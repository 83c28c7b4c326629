//! `GET /v1/sessions/{id}/scene.glb`: the session's scene as glTF 2.0 binary.

use axum::extract::State;
use axum::http::header;
use axum::response::Response;

use crate::error::Error;
use crate::http::helpers::{AppState, Found, attachment, blocking, rendering};
use crate::http::stored_zip::{self, StoredZip};
use crate::report::scene;
use crate::storage::keys::SessionObject;
use crate::storage::streamed;

/// `GET /v1/sessions/{id}/scene.glb`: trajectory by class, frustums, markers, surface points.
pub(crate) async fn glb(State(shared): AppState, Found(session): Found) -> Result<Response, Error> {
    let glb = rendering(shared, "scene export", move |shared| {
        let loaded = scene::load(shared.stores(), &session)?;
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
    let value = rendering(shared, "scene data", move |shared| {
        let loaded = scene::load(shared.stores(), &session)?;
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
/// when it sent one (streamed from the store as stored), else as the scene rebuilt it.
pub(crate) async fn trajectory(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    const TYPE: &str = "text/plain; charset=utf-8";
    let sent = streamed::object_body(
        shared.blobs.clone(),
        &session.id,
        SessionObject::PhoneTrajectory,
    )
    .await?;
    if let Some((len, body)) = sent {
        let mut answer = attachment(TYPE, "trajectory.tum", body);
        answer
            .headers_mut()
            .insert(header::CONTENT_LENGTH, len.into());
        return Ok(answer);
    }
    let tum = rendering(shared, "trajectory", move |shared| {
        scene::load(shared.stores(), &session).map(|loaded| loaded.0.trajectory_tum())
    })
    .await?;
    Ok(attachment(TYPE, "trajectory.tum", tum))
}

/// `GET /v1/sessions/{id}/trials.zip`: every stored trial (`trial_NNN.txt`, TUM), stored
/// uncompressed, streamed as it is written: each trial is read twice from the store (its
/// CRC-32 first, then its bytes), a chunk at a time, so the answer holds about 1.5 MiB
/// however many trials of whatever length it carries. A trial that cannot be read cuts the
/// answer off (the client sees a short body, not a complete-looking archive).
pub(crate) async fn trials_zip(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    let trials = {
        let (shared, id) = (shared.clone(), session.id.clone());
        blocking("trials.zip", move || shared.db.trials_in_order(&id)).await?
    };
    let id = session.id;
    let body = streamed::written_body("trials.zip", move |out| {
        let open = |index: u32| match shared.blobs.open(&id, SessionObject::Trial(index)) {
            Ok(Some(found)) => Ok(found.bytes),
            Ok(None) => Err(std::io::Error::other(format!("trial {index} is missing"))),
            Err(e) => Err(std::io::Error::other(e.to_string())),
        };
        let mut zip = StoredZip::new(out);
        for (index, _) in trials {
            let (crc, len) = stored_zip::crc32(&mut open(index)?)?;
            zip.add(
                &format!("trial_{index:03}.txt"),
                len,
                crc,
                &mut open(index)?,
            )?;
        }
        zip.finish().map(drop)
    });
    Ok(attachment("application/zip", "trials.zip", body))
}
