//! The session resource: `POST /v1/sessions`, `GET /v1/sessions[?limit=N]`,
//! `GET /v1/sessions/{id}`, `DELETE /v1/sessions/{id}`.

use axum::extract::{RawQuery, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use serde_json::json;

use crate::Error;
use crate::auth::Caller;
use crate::config::PlaybackKind;
use crate::deletion;
use crate::error::short;
use crate::http::{
    AppState, Found, check_declared_length, content_type, idempotency_key, json_value,
};
use crate::session::NewSession;
use crate::settings::EstimateSettings;
use crate::status::status_json;

/// The largest `POST /v1/sessions` body: a few short keys need far less.
pub(crate) const MAX_REQUEST_BYTES: u64 = 64 * 1024;
/// How much of a client's input an error message quotes at most.
pub(crate) const QUOTE_LIMIT: usize = 200;

const DEFAULT_LIMIT: u32 = 50;
const MAX_LIMIT: u32 = 500;

/// The JSON body of `POST /v1/sessions`; every key optional.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CreateRequest {
    /// Defaults to the server's trial count.
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
    /// Window length in frames (default 10).
    #[serde(default)]
    window_frames: Option<u32>,
    /// `trans_part` (default) or `angle_deg`.
    #[serde(default)]
    pose_relation: Option<String>,
}

/// `POST /v1/sessions`: a new session, its settings checked and stored typed.
pub(crate) async fn create(
    State(shared): AppState,
    caller: Caller,
    headers: HeaderMap,
    body: axum::body::Body,
) -> Result<Response, Error> {
    if content_type(&headers) != "application/json" {
        return Err(Error::UnsupportedMediaType(
            "POST /v1/sessions takes application/json".into(),
        ));
    }
    // Checked before reading (the declared length) and while reading (the bytes).
    check_declared_length(&headers, MAX_REQUEST_BYTES, "session request")?;
    let body = shared
        .files
        .receive_bytes(
            body.into_data_stream(),
            MAX_REQUEST_BYTES,
            "session request",
        )
        .await?;
    let req: CreateRequest =
        serde_path_to_error::deserialize(&mut serde_json::Deserializer::from_slice(&body))
            .map_err(|e| {
                // The key at fault first: `window_frames: invalid type: string "20", …`.
                // Both may quote the client's input: short prefixes only.
                let key = short(&e.path().to_string(), QUOTE_LIMIT);
                let inner = short(&e.inner().to_string(), QUOTE_LIMIT);
                match key.as_str() {
                    "." => Error::BadRequest(format!("session request: {inner}")),
                    _ => Error::BadRequest(format!("{key}: {inner}")),
                }
            })?;
    let trials = req.trials.unwrap_or(shared.config.default_trials);
    if !(1..=1000).contains(&trials) {
        return Err(Error::BadRequest(format!(
            "trials: {trials} is not in 1..=1000"
        )));
    }
    let playback = match req.playback.as_deref() {
        None => shared.config.playback,
        Some(name) => name.parse::<PlaybackKind>().map_err(|e| {
            Error::BadRequest(format!("playback: {}", short(&e.to_string(), QUOTE_LIMIT)))
        })?,
    };
    let settings = EstimateSettings::from_request(
        &shared.config,
        req.setting.as_deref(),
        req.window_frames,
        req.pose_relation.as_deref(),
    )?;
    if let Some(min) = req.adaptive_min_trials
        && min < 2
    {
        return Err(Error::BadRequest(format!(
            "adaptive_min_trials: {min} is below 2"
        )));
    }
    // Keys are per token: another token's key never returns (or reveals) its session.
    let key = idempotency_key(&headers)?.map(|key| match caller.owner() {
        Some(owner) => format!("{owner}/{key}"),
        None => key,
    });
    let (id, _created) = shared.create_session(&NewSession {
        idempotency_key: key.as_deref(),
        trials_total: trials,
        playback,
        settings,
        adaptive_min: req.adaptive_min_trials,
        adaptive_k: req.adaptive_k.unwrap_or(shared.config.default_adaptive_k),
        legacy: false,
        owner: caller.owner(),
    })?;
    // A replayed request (same Idempotency-Key) gets the answer of the first one.
    Ok((
        StatusCode::CREATED,
        [(header::LOCATION, format!("/v1/sessions/{id}"))],
        axum::Json(json!({"id": id})),
    )
        .into_response())
}

/// `GET /v1/sessions/{id}`.
pub(crate) async fn status(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    Ok(axum::Json(status_json(&shared, &session)?).into_response())
}

/// `?limit=N` (1 … 500, default 50); anything else is a 400 naming the parameter.
fn limit(query: Option<&str>) -> Result<u32, Error> {
    let mut limit = DEFAULT_LIMIT;
    for pair in query.unwrap_or("").split('&').filter(|p| !p.is_empty()) {
        let (key, value) = pair.split_once('=').unwrap_or((pair, ""));
        if key != "limit" {
            return Err(Error::BadRequest(format!(
                "unknown query parameter {key:?}: only limit is known"
            )));
        }
        limit = value
            .parse()
            .ok()
            .filter(|n| (1..=MAX_LIMIT).contains(n))
            .ok_or_else(|| {
                Error::BadRequest(format!(
                    "limit {value:?} is not a whole number from 1 to {MAX_LIMIT}"
                ))
            })?;
    }
    Ok(limit)
}

/// `GET /v1/sessions[?limit=N]`: the newest sessions, newest first, each as its status (an
/// app token's own only).
pub(crate) async fn list(
    State(shared): AppState,
    caller: Caller,
    RawQuery(query): RawQuery,
) -> Result<Response, Error> {
    let limit = limit(query.as_deref())?;
    let sessions = shared
        .db
        .recent_sessions(caller.scope(), limit)?
        .iter()
        .map(|session| status_json(&shared, session))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(json_value(StatusCode::OK, &json!({"sessions": sessions})))
}

/// `DELETE /v1/sessions/{id}`.
pub(crate) async fn delete(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    deletion::delete_idle(&shared, &session.id).await?;
    Ok(json_value(
        StatusCode::OK,
        &json!({"id": session.id, "deleted": true}),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limit_takes_one_number_in_range_and_names_what_is_wrong() {
        assert_eq!(limit(None).unwrap(), DEFAULT_LIMIT);
        assert_eq!(limit(Some("")).unwrap(), DEFAULT_LIMIT);
        assert_eq!(limit(Some("limit=7")).unwrap(), 7);
        assert_eq!(limit(Some("limit=500")).unwrap(), 500);
        for bad in [
            "limit=0",
            "limit=501",
            "limit=-1",
            "limit=",
            "limit=x",
            "page=2",
        ] {
            let err = limit(Some(bad)).unwrap_err().to_string();
            let named = if bad.starts_with("page") {
                "page"
            } else {
                "limit"
            };
            assert!(err.contains(named), "{bad}: {err}");
        }
    }
}
