//! The original Unity app's routes, unchanged for it: `POST /recording`, `POST /timestamps`
//! (multipart form uploads) and `GET /results.csv`.

use std::marker::PhantomData;
use std::sync::Arc;

use axum::extract::multipart::MultipartRejection;
use axum::extract::{FromRequest, Multipart, Request, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde_json::json;

use crate::app_state::App;
use crate::config::ServerConfig;
use crate::error::Error;
use crate::estimate::results_files::{self, Form};
use crate::http::helpers::{AppState, check_declared_length, content_type, json_value};
use crate::jobs::recordings::accept_recording;
use crate::model::{Caller, NewSession, SessionState, estimate_settings::EstimateSettings};
use crate::storage::body_stream;
use crate::storage::keys::SessionObject;
use crate::storage::staged::TempFile;

/// How often a held legacy `POST /recording` looks at its session's state.
const LEGACY_POLL: std::time::Duration = std::time::Duration::from_millis(100);

/// The one field of a legacy upload: its multipart name and the size limit it takes.
pub(crate) struct Field {
    name: &'static str,
    limit: fn(&ServerConfig) -> u64,
}

/// What a legacy upload route receives.
pub(crate) trait Upload {
    const FIELD: Field;
}

/// `POST /recording`'s field.
pub(crate) struct Recording;

impl Upload for Recording {
    const FIELD: Field = Field {
        name: "recording",
        limit: |config| config.max_recording_bytes,
    };
}

/// `POST /timestamps`'s field.
pub(crate) struct Timestamps;

impl Upload for Timestamps {
    const FIELD: Field = Field {
        name: "timestamps",
        limit: |config| config.max_trajectory_bytes,
    };
}

/// The body of a legacy upload route: its field `U::FIELD`, in a temp file. As the last
/// extractor, it reads the body only after the caller is known.
pub(crate) struct Received<U>(TempFile, PhantomData<U>);

impl<U: Upload> FromRequest<Arc<App>> for Received<U> {
    type Rejection = Error;

    async fn from_request(request: Request, shared: &Arc<App>) -> Result<Self, Error> {
        let headers = request.headers().clone();
        let multipart = Multipart::from_request(request, shared).await;
        let temp = multipart_field(shared, multipart, &headers, U::FIELD).await?;
        Ok(Received(temp, PhantomData))
    }
}

/// Reads the multipart field `field` of a legacy upload into a temp file.
async fn multipart_field(
    shared: &App,
    multipart: Result<Multipart, MultipartRejection>,
    headers: &HeaderMap,
    field: Field,
) -> Result<TempFile, Error> {
    let Field { name, limit } = field;
    let limit = limit(&shared.config);
    let mut multipart = multipart.map_err(|e| {
        if content_type(headers) != "multipart/form-data" {
            Error::UnsupportedMediaType(format!(
                "this route takes multipart/form-data with a field {name:?}"
            ))
        } else {
            Error::BadRequest(format!("malformed multipart: {e}"))
        }
    })?;
    // Multipart framing adds a little; the field itself is limited exactly.
    check_declared_length(headers, limit.saturating_add(64 << 10), name)?;
    loop {
        let field = multipart
            .next_field()
            .await
            .map_err(|e| Error::BadRequest(format!("malformed multipart: {e}")))?
            .ok_or_else(|| Error::BadRequest(format!("multipart field {name:?} is missing")))?;
        // The client's file name is ignored: it never becomes a path.
        if field.name() == Some(name) {
            return shared.blobs.receive(body_stream(field), limit, name).await;
        }
    }
}

/// `POST /recording`: a new session with the server's defaults; playback starts.
pub(crate) async fn recording(
    State(shared): AppState,
    caller: Caller,
    Received(temp, _): Received<Recording>,
) -> Result<Response, Error> {
    let (id, _) = shared.create_session(&NewSession {
        idempotency_key: None,
        trials_total: shared.config.default_trials,
        playback: shared.config.playback,
        settings: EstimateSettings::defaults(&shared.config.default_setting)?,
        adaptive_min: None,
        adaptive_k: shared.config.default_adaptive_k,
        legacy: true,
        owner: caller.owner(),
        venue: None,
        convention: sitar_core::Convention::Unity,
        calibration: None,
    })?;
    accept_recording(&shared, &shared.session(&id)?, temp)?;
    // The original app treats this answer as "evaluation complete" and then
    // fetches GET /results.csv, so the request is held until the session ends
    // (as the original backend did). A client that gives up loses nothing:
    // the session goes on and its results stay at /v1/sessions/{id}.
    loop {
        let session = shared.session(&id)?;
        match session.state {
            SessionState::Done => {
                return Ok(json_value(
                    StatusCode::OK,
                    &json!({
                        "id": id,
                        "state": SessionState::Done.as_str(),
                        "status": format!("/v1/sessions/{id}"),
                    }),
                ));
            }
            SessionState::Failed => {
                return Err(Error::Playback(format!(
                    "session {id} failed: {}",
                    session.error.as_deref().unwrap_or("no reason recorded")
                )));
            }
            _ => tokio::time::sleep(LEGACY_POLL).await,
        }
    }
}

/// `POST /timestamps`: stored with the latest legacy session of the caller's token.
pub(crate) async fn timestamps(
    State(shared): AppState,
    caller: Caller,
    Received(temp, _): Received<Timestamps>,
) -> Result<Response, Error> {
    let id = shared
        .db
        .latest_session(false, true, caller.owner())?
        .ok_or_else(|| {
            Error::Conflict("no recording uploaded yet: POST /recording first".into())
        })?;
    let lock = shared.session_lock(&id);
    let _held = lock.lock().await;
    shared.session(&id)?;
    shared.blobs.publish(temp, &id, SessionObject::Timestamps)?;
    Ok(json_value(StatusCode::OK, &json!({"id": id})))
}

/// `GET /results.csv`: the results of the latest finished session the caller's token made
/// through `POST /recording` (never a v1 session, nor another token's).
pub(crate) async fn results(State(shared): AppState, caller: Caller) -> Result<Response, Error> {
    let id = shared
        .db
        .latest_session(true, true, caller.owner())?
        .ok_or_else(|| Error::NotFound("no finished session yet".into()))?;
    let text = results_files::read(&*shared.blobs, &shared.session(&id)?, Form::Csv)?;
    Ok(([(header::CONTENT_TYPE, "text/csv; charset=utf-8")], text).into_response())
}
