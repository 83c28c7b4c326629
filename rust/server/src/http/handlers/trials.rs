//! `POST /v1/sessions/{id}/trials`: one trial of an `upload` session per request.

use axum::body::Body;
use axum::extract::State;
use axum::http::{HeaderMap, StatusCode};
use axum::response::Response;
use serde_json::json;

use crate::error::Error;
use crate::http::helpers::{
    AppState, CURL_DEFAULT_CONTENT_TYPE, Found, check_declared_length, content_type,
    idempotency_key, json_value,
};
use crate::ingest::trials::{self, Arrival};
use crate::jobs::playback as jobs;
use crate::model::{PlaybackKind, Step};
use crate::storage::body_stream;

/// Takes one TUM text as the raw body: parsed from the bytes received, stored once, kept in
/// memory; from the 2nd trial on (the 1st, with the phone's walk) a progressive estimate
/// follows in the background.
pub(crate) async fn post(
    State(shared): AppState,
    Found(session): Found,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, Error> {
    let id = session.id.clone();
    let ct = content_type(&headers);
    if !matches!(
        ct.as_str(),
        "" | "text/plain" | "text/x-tum" | "application/octet-stream" | CURL_DEFAULT_CONTENT_TYPE
    ) {
        return Err(Error::UnsupportedMediaType(format!(
            "a trial is TUM text (text/plain), not {ct}"
        )));
    }
    if session.playback != PlaybackKind::Upload {
        return Err(Error::Conflict(format!(
            "session {id} uses {} playback: its trials come from the server",
            session.playback.as_str()
        )));
    }
    session.require(Step::AddTrial)?;
    let limit = shared.config.max_trajectory_bytes;
    check_declared_length(&headers, limit, "trajectory")?;
    let key = idempotency_key(&headers)?;
    let room = shared
        .blobs
        .reserve(Some(&id), crate::http::helpers::declared_length(&headers))?;
    let bytes = shared
        .blobs
        .receive_bytes_into(
            body_stream(body.into_data_stream()),
            limit,
            "trajectory",
            room,
        )
        .await?;
    let trial = trials::parse_trial(&bytes, "trial")?;
    let lock = shared.session_lock(&id);
    let _held = lock.lock().await;
    // Deleted, or estimated, while the body was arriving?
    let session = shared.session(&id)?;
    session.require(Step::AddTrial)?;
    let live = crate::jobs::live_session::live_session(&shared, &session).await?;
    let arrival = Arrival {
        key: key.as_deref(),
        play_index: None,
        source: "upload",
        retried: false,
    };
    let (index, created) =
        trials::store_trial(shared.stores(), &live, &id, arrival, &bytes, trial)?;
    if created && (live.has_walk() || shared.db.trial_count(&id)? >= 2) {
        jobs::spawn_progressive(shared.clone(), live, id);
    }
    // A replayed request (same Idempotency-Key) gets the answer of the first one.
    Ok(json_value(StatusCode::CREATED, &json!({"index": index})))
}
