//! The session resource: `POST /v1/sessions`, `GET /v1/sessions[?limit=N]`,
//! `GET /v1/sessions/{id}`, `DELETE /v1/sessions/{id}`, `POST /v1/sessions/{id}/cancel`.

use axum::extract::{RawQuery, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use serde_json::json;
use sitar_core::Convention;
use sitar_estimator::ApplyCalibration as _;

use crate::error::Error;
use crate::error::short;
use crate::http::helpers::{
    AppState, Found, check_declared_length, content_type, idempotency_key, json_value,
    visible_venue,
};
use crate::http::pagination::list_limit as limit;
use crate::http::session_status::status_json;
use crate::jobs::deletion;
use crate::jobs::playback::{self as jobs, EndEarly, Stopped};
use crate::jobs::stop_requests;
use crate::model::{
    Caller, NewSession, PlaybackKind, SessionState, estimate_settings::EstimateSettings,
};
use crate::playback::queue::Intent;
use crate::storage::body_stream;

/// The largest `POST /v1/sessions` body: a few short keys need far less.
pub(crate) const MAX_REQUEST_BYTES: u64 = 64 * 1024;
/// How much of a client's input an error message quotes at most.
pub(crate) const QUOTE_LIMIT: usize = 200;

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
    /// The venue the session joins (one the token can see).
    #[serde(default)]
    venue: Option<String>,
    /// The phone's coordinate convention: `unity` (default) or `arcore`.
    #[serde(default)]
    convention: Option<String>,
    /// A calibration this server was started with (`--calibration NAME=FILE`), fitted for
    /// the session's settings: every estimate of the session is calibrated with it.
    #[serde(default)]
    calibration: Option<String>,
}

/// The `POST /v1/sessions` body as a typed request: one JSON object and nothing after it
/// (serde would also take an array of the fields in order, and stop reading after the first
/// value). Errors name the key at fault first (`window_frames: invalid type: string "20", …`)
/// and quote the client's input in short prefixes only.
pub(crate) fn parse_create_request(body: &[u8]) -> Result<CreateRequest, Error> {
    let bad = |key: &str, inner: &str| {
        let (key, inner) = (short(key, QUOTE_LIMIT), short(inner, QUOTE_LIMIT));
        match key.as_str() {
            "." => Error::BadRequest(format!("session request: {inner}")),
            _ => Error::BadRequest(format!("{key}: {inner}")),
        }
    };
    let first = body.iter().find(|b| !b.is_ascii_whitespace());
    if first != Some(&b'{') {
        return Err(bad(".", "the body must be one JSON object"));
    }
    let mut de = serde_json::Deserializer::from_slice(body);
    let req: CreateRequest = serde_path_to_error::deserialize(&mut de)
        .map_err(|e| bad(&e.path().to_string(), &e.inner().to_string()))?;
    de.end()
        .map_err(|e| bad(".", &format!("after the JSON object: {e}")))?;
    Ok(req)
}

/// `POST /v1/sessions`: a new session, its settings checked and stored typed.
pub(crate) async fn create(
    State(shared): AppState,
    caller: Caller,
    headers: HeaderMap,
    body: axum::body::Body,
) -> Result<Response, Error> {
    // Every key is optional: no body at all is a session with the defaults, as is `{}`
    // sent unlabelled or with curl's default label (`curl -X POST`, `curl -d '{}'`).
    let ct = content_type(&headers);
    if !matches!(
        ct.as_str(),
        "application/json" | "" | crate::http::helpers::CURL_DEFAULT_CONTENT_TYPE
    ) {
        return Err(Error::UnsupportedMediaType(format!(
            "POST /v1/sessions takes application/json (or no body), not {}",
            short(&ct, QUOTE_LIMIT)
        )));
    }
    // Checked before reading (the declared length) and while reading (the bytes).
    check_declared_length(&headers, MAX_REQUEST_BYTES, "session request")?;
    let body = shared
        .blobs
        .receive_bytes(
            body_stream(body.into_data_stream()),
            MAX_REQUEST_BYTES,
            "session request",
        )
        .await?;
    let req = if body.iter().all(u8::is_ascii_whitespace) {
        parse_create_request(b"{}")?
    } else {
        parse_create_request(&body)?
    };
    let trials = req.trials.unwrap_or(shared.config.default_trials);
    if trials == 0 {
        return Err(Error::BadRequest("trials: 0 is below 1".into()));
    }
    let cap = shared.config.max_trials;
    if trials > cap {
        return Err(Error::InvalidContent(format!(
            "trials: {trials} is above this server's cap of {cap} (sitar serve --max-trials)"
        )));
    }
    let playback = match req.playback.as_deref() {
        None => shared.config.playback,
        Some(name) => name.parse::<PlaybackKind>().map_err(|e| {
            Error::BadRequest(format!("playback: {}", short(&e.to_string(), QUOTE_LIMIT)))
        })?,
    };
    let offered = offered_playback(&shared.config);
    if !offered.contains(&playback) {
        let names: Vec<_> = offered.iter().map(|kind| kind.as_str()).collect();
        let hint = match playback {
            PlaybackKind::Sim => " (sim needs sitar serve --allow-sim)",
            _ => "",
        };
        return Err(Error::InvalidContent(format!(
            "playback: this server offers {} (started with --playback {}), not {}{hint}",
            names.join(" and "),
            shared.config.playback.as_str(),
            playback.as_str()
        )));
    }
    let settings = EstimateSettings::from_request(
        &shared.config.default_setting,
        req.setting.as_deref(),
        req.window_frames,
        req.pose_relation.as_deref(),
    )?;
    if let Some(name) = req.calibration.as_deref() {
        check_calibration(&shared.config, name, &settings)?;
    }
    if let Some(min) = req.adaptive_min_trials
        && min < 2
    {
        return Err(Error::BadRequest(format!(
            "adaptive_min_trials: {min} is below 2"
        )));
    }
    let convention = match req.convention.as_deref() {
        None | Some("unity") => Convention::Unity,
        Some("arcore") => Convention::Arcore,
        Some(other) => {
            return Err(Error::InvalidContent(format!(
                "convention: {:?} is not unity or arcore",
                short(other, QUOTE_LIMIT)
            )));
        }
    };
    if let Some(venue) = req.venue.as_deref() {
        // A venue the caller cannot see is reported like one that does not exist.
        visible_venue(&shared, &caller, venue).map_err(|e| match e {
            Error::NotFound(_) => Error::InvalidContent(format!(
                "venue: no venue {:?} that this token can see",
                short(venue, QUOTE_LIMIT)
            )),
            other => other,
        })?;
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
        venue: req.venue.as_deref(),
        convention,
        calibration: req.calibration.as_deref(),
    })?;
    // A replayed request (same Idempotency-Key) gets the answer of the first one.
    Ok((
        StatusCode::CREATED,
        [(header::LOCATION, format!("/v1/sessions/{id}"))],
        axum::Json(json!({"id": id})),
    )
        .into_response())
}

/// A session's `calibration`: one this server has (else a 400 naming it and the ones it has),
/// fitted for the session's setting, window and pose relation (else a 400 with the
/// calibration's own message naming both).
fn check_calibration(
    config: &crate::config::ServerConfig,
    name: &str,
    settings: &EstimateSettings,
) -> Result<(), Error> {
    let Some(calibration) = config.calibrations.get(name) else {
        let known: Vec<&str> = config.calibrations.names().collect();
        let known = if known.is_empty() {
            "this server has none (sitar serve --calibration NAME=FILE)".to_string()
        } else {
            format!("this server has {}", known.join(", "))
        };
        return Err(Error::BadRequest(format!(
            "calibration: no calibration {:?}: {known}",
            short(name, 64)
        )));
    };
    calibration
        .check_estimate(
            settings.setting,
            settings.window_frames as usize,
            settings.pose_relation,
        )
        .map_err(|e| Error::BadRequest(format!("calibration: {name}: {e}")))
}

/// The playback kinds sessions may ask for: the server's own, `upload`, and `sim` with
/// `allow_sim`.
fn offered_playback(config: &crate::config::ServerConfig) -> Vec<PlaybackKind> {
    [PlaybackKind::Adb, PlaybackKind::Sim, PlaybackKind::Upload]
        .into_iter()
        .filter(|&kind| {
            kind == config.playback
                || kind == PlaybackKind::Upload
                || (kind == PlaybackKind::Sim && config.allow_sim)
        })
        .collect()
}

/// `GET /v1/sessions/{id}`.
pub(crate) async fn status(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    Ok(axum::Json(status_json(&shared, &session)?).into_response())
}

/// `GET /v1/sessions[?limit=N]`: the newest sessions, newest first, each as its status (an
/// app token's own only).
pub(crate) async fn list(
    State(shared): AppState,
    caller: Caller,
    RawQuery(query): RawQuery,
) -> Result<Response, Error> {
    let limit = limit(query.as_deref())?;
    let rows = shared.db.recent_rows(caller.scope(), limit)?;
    let sessions = rows
        .sessions
        .iter()
        .map(|session| status_json(&shared, session))
        .collect::<Result<Vec<_>, _>>()?;
    // A row no version of the server writes is named (under `unreadable`) and skipped,
    // never a 500 for all.
    let unreadable: Vec<_> = rows
        .unreadable
        .iter()
        .map(|bad| {
            log::warn!("session {}: unreadable row, left out: {}", bad.id, bad.why);
            json!({"id": bad.id, "error": short(&bad.why, QUOTE_LIMIT)})
        })
        .collect();
    let mut doc = json!({"sessions": sessions});
    if !unreadable.is_empty() {
        doc["unreadable"] = unreadable.into();
    }
    Ok(json_value(StatusCode::OK, &doc))
}

/// `DELETE /v1/sessions/{id}`: a queued or playing session's playback is stopped first (the
/// adb backend stops the app on the phones; another instance playing it is asked through the
/// database and waited for), then the session goes.
pub(crate) async fn delete(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    match stop_requests::stop_anywhere(&shared, &session.id, Intent::Delete).await? {
        Stopped::Dequeued | Stopped::Playing => {
            deletion::delete_stopped(&shared, &session.id).await?
        }
        Stopped::Idle => deletion::delete_idle(&shared, &session.id).await?,
    }
    Ok(json_value(
        StatusCode::OK,
        &json!({"id": session.id, "deleted": true}),
    ))
}

/// `POST /v1/sessions/{id}/cancel`: stops a sim or adb session's playback and keeps what
/// was played: the session ends with an estimate over its trials (2 or more), else failed
/// with the reason. A queued session leaves the queue. Another instance playing it is asked
/// through the database (it looks every `stop_requests::POLL`).
pub(crate) async fn cancel(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    let id = session.id;
    if session.playback == PlaybackKind::Upload {
        return Err(Error::Conflict(format!(
            "session {id} is an upload session: it has no playback to cancel \
             (POST /v1/sessions/{id}/estimate ends it, DELETE removes it)"
        )));
    }
    if session.state.is_finished() {
        return Err(Error::Conflict(format!(
            "session {id} is {}: nothing to cancel",
            session.state
        )));
    }
    match stop_requests::stop_anywhere(&shared, &id, Intent::Cancel).await? {
        Stopped::Dequeued => jobs::finish_dequeued(shared.clone(), id.clone(), EndEarly::Cancel)?,
        // Its job ends the playback and estimates what was played.
        Stopped::Playing => {}
        Stopped::Idle => match session.state {
            SessionState::Created => shared
                .lifecycle()
                .fail(&id, "cancelled by the client before its recording arrived")?,
            state => {
                return Err(Error::Conflict(format!(
                    "session {id} is {state} and not playing: nothing to cancel"
                )));
            }
        },
    }
    Ok(json_value(
        StatusCode::ACCEPTED,
        &json!({"id": id, "cancelled": true}),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_session_request_is_one_json_object_and_nothing_after_it() {
        let req = parse_create_request(b" {\"trials\":2} \n").unwrap();
        assert_eq!(req.trials, Some(2));
        for (body, says) in [
            (&b"{\"trials\":2}garbage"[..], "after the JSON object"),
            (b"{\"trials\":2}{\"trials\":3}", "after the JSON object"),
            (b"[2,\"median\"]", "one JSON object"),
            (b"2", "one JSON object"),
            (b"", "one JSON object"),
            (b"{\"trials\":\"2\"}", "trials: invalid type"),
        ] {
            match parse_create_request(body) {
                Err(Error::BadRequest(message)) => assert!(message.contains(says), "{message}"),
                other => panic!("{:?}: {other:?}", String::from_utf8_lossy(body)),
            }
        }
    }
}
