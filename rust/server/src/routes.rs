//! The HTTP API: versioned routes, legacy routes, JSON errors.

use std::sync::Arc;

use axum::Router;
use axum::body::Body;
use axum::extract::multipart::MultipartRejection;
use axum::extract::{DefaultBodyLimit, Multipart, Path, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post, put};
use serde::Deserialize;
use serde_json::json;

use crate::Error;
use crate::db::{NewSessionRow, SessionRow};
use crate::deletion;
use crate::estimation;
use crate::files::{TempFile, is_server_id, new_id};
use crate::jobs;
use crate::overview;
use crate::recording::{self, accept_recording};
use crate::report;
use crate::state::Shared;

type AppState = State<Arc<Shared>>;

/// The header carrying a client-made key that makes a `POST` safe to retry.
pub const IDEMPOTENCY_HEADER: &str = "idempotency-key";

pub(crate) fn router(shared: Arc<Shared>) -> Router {
    Router::new()
        .route("/healthz", get(health))
        .route("/", get(overview::page))
        // Browsers ask for it on every refresh of the page; no icon, no log noise.
        .route("/favicon.ico", get(|| async { StatusCode::NO_CONTENT }))
        .route("/v1/sessions", post(create_session).get(overview::list))
        .route(
            "/v1/sessions/{id}",
            get(session_status).delete(deletion::delete_session),
        )
        .route(
            "/v1/sessions/{id}/recording",
            put(recording::put_recording).head(recording::kept_offset),
        )
        .route("/v1/sessions/{id}/trials", post(post_trial))
        .route("/v1/sessions/{id}/estimate", post(post_estimate))
        .route("/v1/sessions/{id}/results.csv", get(results_csv))
        .route("/v1/sessions/{id}/results.json", get(results_json))
        .route("/v1/sessions/{id}/report", get(report_page))
        .route("/v1/devices", get(devices))
        .route("/recording", post(legacy_recording))
        .route("/timestamps", post(legacy_timestamps))
        .route("/results.csv", get(legacy_results))
        .fallback(|| async { Error::NotFound("no such route".into()) })
        .method_not_allowed_fallback(|| async {
            json_response(
                StatusCode::METHOD_NOT_ALLOWED,
                &crate::error::error_body("method_not_allowed", "method not allowed on this route"),
            )
        })
        // Limits are ours, per route, checked while streaming.
        .layer(DefaultBodyLimit::disable())
        .layer(axum::middleware::from_fn(log_request))
        .with_state(shared)
}

/// One log line per request: method, path (server-made ids only, no query), status, time.
/// Successful `GET`/`HEAD`s log at debug: phones poll their status every half second.
async fn log_request(request: axum::extract::Request, next: axum::middleware::Next) -> Response {
    let method = request.method().clone();
    let path = request.uri().path().to_owned();
    let started = std::time::Instant::now();
    let response = next.run(request).await;
    let status = response.status();
    let quiet =
        matches!(method, axum::http::Method::GET | axum::http::Method::HEAD) && status.is_success();
    let level = if quiet {
        log::Level::Debug
    } else {
        log::Level::Info
    };
    log::log!(
        level,
        "{method} {path} → {} in {:.1} ms",
        status.as_u16(),
        started.elapsed().as_secs_f64() * 1e3
    );
    response
}

pub(crate) fn json_response(status: StatusCode, body: &str) -> Response {
    (
        status,
        [(header::CONTENT_TYPE, "application/json")],
        body.to_string(),
    )
        .into_response()
}

pub(crate) fn content_type(headers: &HeaderMap) -> String {
    headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .map(|v| {
            v.split(';')
                .next()
                .unwrap_or("")
                .trim()
                .to_ascii_lowercase()
        })
        .unwrap_or_default()
}

pub(crate) fn idempotency_key(headers: &HeaderMap) -> Result<Option<String>, Error> {
    match headers.get(IDEMPOTENCY_HEADER) {
        None => Ok(None),
        Some(v) => {
            let key = v
                .to_str()
                .map_err(|_| Error::BadRequest("Idempotency-Key is not ASCII".into()))?;
            if key.is_empty() || key.len() > 128 {
                return Err(Error::BadRequest(
                    "Idempotency-Key must have 1 to 128 characters".into(),
                ));
            }
            Ok(Some(key.to_string()))
        }
    }
}

/// The body length the request declares (`Content-Length`), if it declares one.
pub(crate) fn declared_length(headers: &HeaderMap) -> Option<u64> {
    headers
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse().ok())
}

/// Refuses a body whose declared length is over the limit before reading it.
pub(crate) fn check_declared_length(
    headers: &HeaderMap,
    limit: u64,
    what: &'static str,
) -> Result<(), Error> {
    match declared_length(headers) {
        Some(n) if n > limit => Err(Error::TooLarge { what, limit }),
        _ => Ok(()),
    }
}

pub(crate) fn session_row(shared: &Shared, id: &str) -> Result<SessionRow, Error> {
    if !is_server_id(id) {
        return Err(Error::NotFound(format!("no session {id:?}")));
    }
    shared
        .db
        .session(id)?
        .ok_or_else(|| Error::NotFound(format!("no session {id:?}")))
}

async fn health() -> Response {
    json_response(StatusCode::OK, r#"{"status":"ok"}"#)
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CreateRequest {
    /// Defaults to the server's trial count for legacy sessions.
    #[serde(default)]
    trials: Option<u32>,
    #[serde(default)]
    setting: Option<String>,
    /// Defaults to the server's `--playback`.
    #[serde(default)]
    playback: Option<String>,
    #[serde(default)]
    adaptive_min_trials: Option<u32>,
    #[serde(default)]
    adaptive_k: Option<u32>,
}

async fn create_session(
    State(shared): AppState,
    headers: HeaderMap,
    body: axum::body::Bytes,
) -> Result<Response, Error> {
    if content_type(&headers) != "application/json" {
        return Err(Error::UnsupportedMediaType(
            "POST /v1/sessions takes application/json".into(),
        ));
    }
    let req: CreateRequest = serde_json::from_slice(&body)
        .map_err(|e| Error::BadRequest(format!("session request: {e}")))?;
    let trials = req.trials.unwrap_or(shared.config.default_trials);
    if !(1..=1000).contains(&trials) {
        return Err(Error::BadRequest(format!(
            "trials: {trials} is not in 1..=1000"
        )));
    }
    let playback = req
        .playback
        .unwrap_or_else(|| shared.config.playback.as_str().to_owned());
    let setting = req
        .setting
        .unwrap_or_else(|| shared.config.default_setting.clone());
    estimation::check_setting(&setting)?;
    shared.backend(&playback)?;
    if let Some(min) = req.adaptive_min_trials
        && min < 2
    {
        return Err(Error::BadRequest(format!(
            "adaptive_min_trials: {min} is below 2"
        )));
    }
    let key = idempotency_key(&headers)?;
    let (id, _created) = create_row(
        &shared,
        &NewSessionRow {
            idempotency_key: key.as_deref(),
            trials_total: trials,
            setting: &setting,
            playback: &playback,
            adaptive_min: req.adaptive_min_trials,
            adaptive_k: req.adaptive_k.unwrap_or(shared.config.default_adaptive_k),
            legacy: false,
        },
    )?;
    // A replayed request (same Idempotency-Key) gets the answer of the first one.
    Ok((
        StatusCode::CREATED,
        [(header::LOCATION, format!("/v1/sessions/{id}"))],
        axum::Json(json!({"id": id})),
    )
        .into_response())
}

fn create_row(shared: &Shared, new: &NewSessionRow<'_>) -> Result<(String, bool), Error> {
    let (id, created) = shared.db.insert_session(&new_id(), new)?;
    shared.files.create_session_dirs(&id)?;
    Ok((id, created))
}

/// The status document of a session.
pub(crate) fn status_json(shared: &Shared, row: &SessionRow) -> Result<serde_json::Value, Error> {
    let done = shared.db.trial_count(&row.id)?;
    let total = row.trials_total;
    let live = shared.live(&row.id);
    let (progress, eta) = match row.state.as_str() {
        "done" => (1.0, Some(0.0)),
        "failed" => (done as f64 / total.max(1) as f64, None),
        "estimating" => (0.97, Some(0.5)),
        "playing" => match live.as_ref().and_then(|l| l.plan.map(|p| (l, p))) {
            Some((l, plan)) if plan.devices > 0 => {
                let expected = plan.seconds_for(l.needed).max(1e-9);
                let elapsed = l.started.elapsed().as_secs_f64();
                let by_time = (l.done_before as f64
                    + l.needed as f64 * (elapsed / expected).min(1.0))
                    / total.max(1) as f64;
                let by_trials = done as f64 / total.max(1) as f64;
                (
                    0.95 * by_time.max(by_trials).min(1.0),
                    Some((expected - elapsed).max(0.0) + 0.5),
                )
            }
            _ => (0.95 * done as f64 / total.max(1) as f64, None),
        },
        _ => (0.0, None),
    };
    Ok(json!({
        "id": row.id,
        "state": row.state,
        "progress": (progress * 1000.0).round() / 1000.0,
        "eta_s": eta.map(|e: f64| (e * 10.0).round() / 10.0),
        "trials_done": done,
        "trials_total": total,
        "error": row.error,
        "results_trials": row.results_trials,
        "stop_reason": row.stop_reason,
        "playback": row.playback,
        "setting": row.setting,
        "jobs": shared.db.jobs_of(&row.id)?.into_iter().map(|(kind, state)| json!({"kind": kind, "state": state})).collect::<Vec<_>>(),
    }))
}

async fn session_status(
    State(shared): AppState,
    Path(id): Path<String>,
) -> Result<Response, Error> {
    let row = session_row(&shared, &id)?;
    Ok(axum::Json(status_json(&shared, &row)?).into_response())
}

/// `curl --data-binary @file` labels any raw body form-urlencoded; the bytes
/// are still raw, so that label is accepted wherever a raw body is.
pub(crate) const CURL_DEFAULT_CONTENT_TYPE: &str = "application/x-www-form-urlencoded";

async fn post_trial(
    State(shared): AppState,
    Path(id): Path<String>,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, Error> {
    let row = session_row(&shared, &id)?;
    let ct = content_type(&headers);
    if !matches!(
        ct.as_str(),
        "" | "text/plain" | "text/x-tum" | "application/octet-stream" | CURL_DEFAULT_CONTENT_TYPE
    ) {
        return Err(Error::UnsupportedMediaType(format!(
            "a trial is TUM text (text/plain), not {ct}"
        )));
    }
    if row.playback != "upload" {
        return Err(Error::Conflict(format!(
            "session {id} uses {} playback: its trials come from the server",
            row.playback
        )));
    }
    if row.state != "created" && row.state != "uploaded" {
        return Err(Error::Conflict(format!(
            "session {id} is {}: it takes no more trials",
            row.state
        )));
    }
    let limit = shared.config.max_trajectory_bytes;
    check_declared_length(&headers, limit, "trajectory")?;
    let key = idempotency_key(&headers)?;
    let temp = shared
        .files
        .receive(body.into_data_stream(), limit, "trajectory")
        .await?;
    let text = std::fs::read(&temp.path).map_err(|e| Error::io("cannot read", &temp.path, e))?;
    let text = String::from_utf8(text)
        .map_err(|e| Error::InvalidContent(format!("trajectory is not UTF-8 text: {e}")))?;
    let lock = shared.session_lock(&id);
    let _held = lock.lock().await;
    // Deleted, or estimated, while the body was arriving?
    let row = session_row(&shared, &id)?;
    if row.state != "created" && row.state != "uploaded" {
        return Err(Error::Conflict(format!(
            "session {id} is {}: it takes no more trials",
            row.state
        )));
    }
    let (index, _created) = jobs::store_trial(&shared, &id, key.as_deref(), None, &text, "upload")?;
    // A replayed request (same Idempotency-Key) gets the answer of the first one.
    Ok(json_response(
        StatusCode::CREATED,
        &json!({"index": index}).to_string(),
    ))
}

async fn post_estimate(State(shared): AppState, Path(id): Path<String>) -> Result<Response, Error> {
    // Only a known id gets a lock (garbage ids must not grow the lock table).
    session_row(&shared, &id)?;
    let lock = shared.session_lock(&id);
    let _held = lock.lock().await;
    let row = session_row(&shared, &id)?;
    let count = shared.db.trial_count(&id)?;
    match row.state.as_str() {
        "done" | "estimating" => {}
        "failed" => {
            return Err(Error::Conflict(format!(
                "session {id} failed: {}",
                row.error.unwrap_or_default()
            )));
        }
        _ if count < 2 => {
            return Err(Error::Conflict(format!(
                "an estimate needs at least 2 trials, session {id} has {count}"
            )));
        }
        "playing" => {
            // Estimate now: stop playback; the job publishes the final estimate.
            if let Some(live) = shared.live(&id) {
                live.cancel.store(true, std::sync::atomic::Ordering::SeqCst);
            }
        }
        _ if row.playback == "upload" => {
            jobs::spawn_estimate(shared.clone(), id.clone(), row.setting.clone())
        }
        state => {
            return Err(Error::Conflict(format!(
                "session {id} is {state}: playback has not started"
            )));
        }
    }
    Ok(json_response(
        StatusCode::ACCEPTED,
        &json!({"id": id}).to_string(),
    ))
}

fn results_file(shared: &Shared, id: &str, json: bool) -> Result<String, Error> {
    let row = session_row(shared, id)?;
    if row.results_trials == 0 {
        return Err(Error::Conflict(format!(
            "session {id} has no results yet (state {})",
            row.state
        )));
    }
    let path = if json {
        shared.files.results_json(id)
    } else {
        shared.files.results_csv(id)
    };
    std::fs::read_to_string(&path).map_err(|e| Error::io("cannot read", &path, e))
}

async fn results_csv(State(shared): AppState, Path(id): Path<String>) -> Result<Response, Error> {
    let text = results_file(&shared, &id, false)?;
    Ok(([(header::CONTENT_TYPE, "text/csv; charset=utf-8")], text).into_response())
}

async fn results_json(State(shared): AppState, Path(id): Path<String>) -> Result<Response, Error> {
    Ok(json_response(
        StatusCode::OK,
        &results_file(&shared, &id, true)?,
    ))
}

async fn report_page(State(shared): AppState, Path(id): Path<String>) -> Result<Response, Error> {
    let row = session_row(&shared, &id)?;
    let json = results_file(&shared, &id, true)?;
    let first = shared
        .db
        .trials_in_order(&id)?
        .first()
        .copied()
        .unwrap_or(0);
    let reference = std::fs::read_to_string(shared.files.trial(&id, first)).unwrap_or_default();
    let html = report::render(&row, &reference, &json, &shared.config)?;
    Ok(Html(html).into_response())
}

async fn devices(State(shared): AppState) -> Result<Response, Error> {
    let backend = shared.backend(shared.config.playback.as_str())?;
    let list = tokio::task::spawn_blocking(move || backend.devices())
        .await
        .map_err(|e| Error::Internal(format!("devices task: {e}")))?;
    for d in &list {
        shared.db.upsert_device(&d.serial, &d.state, None)?;
    }
    let known = shared.db.devices()?;
    let known: Vec<_> = known
        .into_iter()
        .map(|(serial, state, session, seen)| json!({"serial": serial, "state": state, "session": session, "last_seen_ms": seen}))
        .collect();
    Ok(axum::Json(
        json!({"playback": shared.config.playback.as_str(), "devices": list, "known": known}),
    )
    .into_response())
}

/// Reads the multipart field `name` of a legacy upload into a temp file.
async fn multipart_field(
    shared: &Shared,
    multipart: Result<Multipart, MultipartRejection>,
    headers: &HeaderMap,
    name: &str,
    limit: u64,
    what: &'static str,
) -> Result<TempFile, Error> {
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
    check_declared_length(headers, limit.saturating_add(64 << 10), what)?;
    loop {
        let field = multipart
            .next_field()
            .await
            .map_err(|e| Error::BadRequest(format!("malformed multipart: {e}")))?
            .ok_or_else(|| Error::BadRequest(format!("multipart field {name:?} is missing")))?;
        // The client's file name is ignored: it never becomes a path.
        if field.name() == Some(name) {
            return shared.files.receive(field, limit, what).await;
        }
    }
}

async fn legacy_recording(
    State(shared): AppState,
    headers: HeaderMap,
    multipart: Result<Multipart, MultipartRejection>,
) -> Result<Response, Error> {
    let temp = multipart_field(
        &shared,
        multipart,
        &headers,
        "recording",
        shared.config.max_recording_bytes,
        "recording",
    )
    .await?;
    let (id, _) = create_row(
        &shared,
        &NewSessionRow {
            idempotency_key: None,
            trials_total: shared.config.default_trials,
            setting: &shared.config.default_setting,
            playback: shared.config.playback.as_str(),
            adaptive_min: None,
            adaptive_k: shared.config.default_adaptive_k,
            legacy: true,
        },
    )?;
    let row = session_row(&shared, &id)?;
    accept_recording(&shared, &row, temp)?;
    // The original app treats this answer as "evaluation complete" and then
    // fetches GET /results.csv, so the request is held until the session ends
    // (as the original backend did). A client that gives up loses nothing:
    // the session goes on and its results stay at /v1/sessions/{id}.
    loop {
        let row = session_row(&shared, &id)?;
        match row.state.as_str() {
            "done" => {
                return Ok(json_response(
                    StatusCode::OK,
                    &json!({"id": id, "state": "done", "status": format!("/v1/sessions/{id}")})
                        .to_string(),
                ));
            }
            "failed" => {
                return Err(Error::Playback(format!(
                    "session {id} failed: {}",
                    row.error.as_deref().unwrap_or("no reason recorded")
                )));
            }
            _ => tokio::time::sleep(LEGACY_POLL).await,
        }
    }
}

/// How often a held legacy `POST /recording` looks at its session's state.
const LEGACY_POLL: std::time::Duration = std::time::Duration::from_millis(100);

async fn legacy_timestamps(
    State(shared): AppState,
    headers: HeaderMap,
    multipart: Result<Multipart, MultipartRejection>,
) -> Result<Response, Error> {
    let temp = multipart_field(
        &shared,
        multipart,
        &headers,
        "timestamps",
        shared.config.max_trajectory_bytes,
        "timestamps",
    )
    .await?;
    let id = shared.db.latest_session(false, true)?.ok_or_else(|| {
        Error::Conflict("no recording uploaded yet: POST /recording first".into())
    })?;
    let lock = shared.session_lock(&id);
    let _held = lock.lock().await;
    session_row(&shared, &id)?;
    temp.publish(&shared.files.timestamps(&id))?;
    Ok(json_response(
        StatusCode::OK,
        &json!({"id": id}).to_string(),
    ))
}

async fn legacy_results(State(shared): AppState) -> Result<Response, Error> {
    let id = shared
        .db
        .latest_session(true, false)?
        .ok_or_else(|| Error::NotFound("no finished session yet".into()))?;
    let text = results_file(&shared, &id, false)?;
    Ok(([(header::CONTENT_TYPE, "text/csv; charset=utf-8")], text).into_response())
}
