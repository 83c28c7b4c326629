//! The phone's own log: `PUT /v1/sessions/{id}/trajectory.txt`,
//! `PUT /v1/sessions/{id}/walk.txt` and `PUT /v1/sessions/{id}/anchors.csv`
//! (`subtrajectories.csv` is the evidence's route). Each body is checked whole before
//! anything is stored (`crate::ingest::phone_log`), then replaces the earlier upload
//! atomically. Allowed in every state, before and after the recording; the session's owner
//! (or an admin) only, as every session write.
//!
//! The walk is the live run of a session with a calibration that has a model for one run:
//! its estimate alone is published at once, as the session's first results, and every
//! later estimate has it as the live run and the trials as its replays
//! (`estimate/held_trials.rs`).

use axum::body::Body;
use axum::extract::State;
use axum::http::{HeaderMap, StatusCode};
use axum::response::Response;
use serde_json::json;

use crate::app_state::App;
use crate::error::Error;
use crate::estimate::held_trials::trial_bytes;
use crate::estimate::live_sessions::walk_unused;
use crate::http::helpers::{AppState, Found, json_value, small_body, utf8};
use crate::ingest::phone_log::{
    MAX_ANCHORS_BYTES, MAX_TRAJECTORY_BYTES, check_anchors, check_trajectory, parse_walk,
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

/// `PUT /v1/sessions/{id}/walk.txt` → 200 `{"poses"}`, with `"runs"` and `"source"` of the
/// results it published, or `"not_estimated"` saying why it published none. Bounded as a
/// trial is (`max_trajectory_bytes`): it holds every frame of the recording.
pub(crate) async fn put_walk(
    State(shared): AppState,
    Found(session): Found,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, Error> {
    const NAME: &str = "walk.txt";
    let id = session.id.clone();
    let limit = shared.config.max_trajectory_bytes;
    let bytes = small_body(&shared, &id, &headers, body, limit, NAME).await?;
    let text = utf8(bytes, NAME)?;
    // A long walk is tens of megabytes: parsed off the runtime.
    let (text, walk) = tokio::task::spawn_blocking(move || {
        let walk = parse_walk(&text);
        (text, walk)
    })
    .await
    .map_err(|e| Error::Internal(format!("reading walk.txt: {e}")))?;
    let walk = walk?;
    let poses = walk.len();
    // Whether the session estimates from it, and its memory counted, before it is stored.
    let session = shared.session(&id)?;
    let unused = if session.state.is_finished() {
        Some(format!(
            "session {id} is {}: its results stay as they are",
            session.state
        ))
    } else {
        let calibration = shared
            .config
            .calibrations
            .for_session(session.calibration.as_deref());
        walk_unused(&calibration, session.settings.window_frames as usize, &walk)
    };
    let live = match unused {
        None => Some(crate::jobs::live_session::live_session(&shared, &session).await?),
        Some(_) => None,
    };
    let reservation = match &live {
        Some(live) => Some(live.reserve(trial_bytes(&walk))?),
        None => None,
    };
    {
        let lock = shared.session_lock(&id);
        let _held = lock.lock().await;
        shared.session(&id)?;
        shared
            .blobs
            .put(&id, SessionObject::Walk, text.as_bytes())?;
    }
    let mut answer = json!({"poses": poses});
    match (&live, reservation) {
        (Some(live), Some(reservation)) => {
            live.set_walk(walk, reservation);
            match crate::jobs::playback::publish_now(&shared, live, &id).await {
                Ok(Some(published)) => {
                    answer["runs"] = json!(published.trials);
                    answer["source"] = json!(published.source);
                }
                Ok(None) => {}
                Err(e) => answer["not_estimated"] = json!(e.client_message()),
            }
        }
        _ => answer["not_estimated"] = json!(unused),
    }
    Ok(json_value(StatusCode::OK, &answer))
}
