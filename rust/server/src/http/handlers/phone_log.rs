//! The phone's own log: `PUT /v1/sessions/{id}/trajectory.txt` and
//! `PUT /v1/sessions/{id}/anchors.csv` (`subtrajectories.csv` is the evidence's route).
//! Each body is checked whole before anything is stored (`crate::ingest::phone_log`), then
//! replaces the earlier upload atomically. Allowed in every state, before and after the
//! recording; the session's owner (or an admin) only, as every session write.

use axum::body::Body;
use axum::extract::State;
use axum::http::{HeaderMap, StatusCode};
use axum::response::Response;
use serde_json::json;

use crate::app_state::App;
use crate::error::Error;
use crate::http::helpers::{AppState, Found, json_value, small_body, utf8};
use crate::ingest::phone_log::{
    MAX_ANCHORS_BYTES, MAX_TRAJECTORY_BYTES, check_anchors, check_trajectory,
};
use crate::storage::keys::SessionObject;

/// Stores `text` as session `id`'s `object` under the session's lock, after checking the
/// session still exists (it may have been deleted while the body arrived).
async fn store(shared: &App, id: &str, object: SessionObject, text: &str) -> Result<(), Error> {
    let lock = shared.session_lock(id);
    let _held = lock.lock().await;
    shared.session(id)?;
    shared.blobs.put(id, object, text.as_bytes())?;
    // Its venue's map computes its contribution again from the new file.
    shared.db.forget_contribution(id)
}

/// `PUT /v1/sessions/{id}/trajectory.txt` → 200 `{"poses"}`.
pub(crate) async fn put_trajectory(
    State(shared): AppState,
    Found(session): Found,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, Error> {
    const NAME: &str = "trajectory.txt";
    let bytes = small_body(
        &shared,
        &session.id,
        &headers,
        body,
        MAX_TRAJECTORY_BYTES,
        NAME,
    )
    .await?;
    let text = utf8(bytes, NAME)?;
    let poses = check_trajectory(&text)?;
    store(&shared, &session.id, SessionObject::PhoneTrajectory, &text).await?;
    // The session's scene is the phone's log from now on.
    crate::report::scene::phone_log_changed(&*shared.blobs, &session.id);
    Ok(json_value(StatusCode::OK, &json!({"poses": poses})))
}

/// `PUT /v1/sessions/{id}/anchors.csv` → 200 `{"observations"}`.
pub(crate) async fn put_anchors(
    State(shared): AppState,
    Found(session): Found,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, Error> {
    const NAME: &str = "anchors.csv";
    let bytes = small_body(
        &shared,
        &session.id,
        &headers,
        body,
        MAX_ANCHORS_BYTES,
        NAME,
    )
    .await?;
    let text = utf8(bytes, NAME)?;
    let observations = check_anchors(&text)?;
    store(&shared, &session.id, SessionObject::Anchors, &text).await?;
    Ok(json_value(
        StatusCode::OK,
        &json!({"observations": observations}),
    ))
}
