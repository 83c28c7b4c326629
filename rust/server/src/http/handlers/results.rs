//! A session's results: `POST /v1/sessions/{id}/estimate` (the final estimate, now) and
//! `GET /v1/sessions/{id}/results.csv|results.json` (the latest published one).

use axum::extract::{RawQuery, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde_json::json;

use crate::error::Error;
use crate::estimate::results_files::{self, Form};
use crate::http::helpers::{AppState, Found, json_response, json_value};
use crate::http::pagination::{PageRequest, page_of};
use crate::jobs::{playback as jobs, stop_requests};
use crate::model::{PlaybackKind, SessionState};
use crate::storage::StopRequest;

/// `POST /v1/sessions/{id}/estimate`: `upload` sessions estimate now; sim and adb sessions
/// that are playing stop playback and estimate what is there.
pub(crate) async fn estimate(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    let id = session.id;
    let lock = shared.session_lock(&id);
    let _held = lock.lock().await;
    let session = shared.session(&id)?;
    let count = shared.db.trial_count(&id)?;
    match session.state {
        SessionState::Done | SessionState::Estimating => {}
        SessionState::Failed => {
            return Err(Error::Conflict(format!(
                "session {id} failed: {}",
                session.error.unwrap_or_default()
            )));
        }
        _ if count < 2 => {
            return Err(Error::Conflict(format!(
                "an estimate needs at least 2 trials, session {id} has {count}"
            )));
        }
        SessionState::Playing => {
            if shared.queue.remove(&id) {
                // Waiting for a worker after a restart: estimate what it has now.
                jobs::finish_dequeued(shared.clone(), id.clone(), jobs::EndEarly::Estimate)?;
            } else if let Some(job) = shared.running(&id) {
                // Estimate now: stop playback; the job publishes the final estimate.
                job.cancel.store(true, std::sync::atomic::Ordering::SeqCst);
            } else {
                // Another instance plays it: asked through the database.
                let request = Some(StopRequest::Estimate);
                stop_requests::ask_elsewhere(&shared, &id, request).await?;
            }
        }
        _ if session.playback == PlaybackKind::Upload => {
            shared.lifecycle().start_estimating(&id)?;
            jobs::spawn_estimate(shared.clone(), id.clone());
        }
        state => {
            return Err(Error::Conflict(format!(
                "session {id} is {state}: playback has not started"
            )));
        }
    }
    Ok(json_value(StatusCode::ACCEPTED, &json!({"id": id})))
}

/// `GET /v1/sessions/{id}/results.csv`.
pub(crate) async fn csv(State(shared): AppState, Found(session): Found) -> Result<Response, Error> {
    let text = results_files::read(&*shared.blobs, &session, Form::Csv)?;
    Ok(([(header::CONTENT_TYPE, "text/csv; charset=utf-8")], text).into_response())
}

/// `GET /v1/sessions/{id}/results.json[?offset=N&limit=M]`: at most
/// [`MAX_PAGE`](crate::http::pagination::MAX_PAGE) windows per answer, with a `page` object when
/// the answer does not hold them all.
pub(crate) async fn json(
    State(shared): AppState,
    Found(session): Found,
    RawQuery(query): RawQuery,
) -> Result<Response, Error> {
    let page = PageRequest::parse(query.as_deref())?;
    let doc = results_files::read(&*shared.blobs, &session, Form::Json)?;
    Ok(json_response(
        StatusCode::OK,
        &page_of(doc, "windows", page)?,
    ))
}
