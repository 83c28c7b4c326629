//! `/v1/worker/…`: the routes of playback hosts (`sitar worker`, worker tokens only): register
//! with the phones, heartbeat, lease a trial per free phone (long poll), fetch the lease's
//! recording, upload the trial (committed exactly once) or report the phone's failure.

use std::time::Duration;

use axum::Json;
use axum::body::Body;
use axum::extract::{Path, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use serde_json::json;

use crate::auth::WorkerCaller;
use crate::error::Error;
use crate::http::helpers::{AppState, blocking, check_declared_length, json_value};
use crate::ingest::trials::parse_trial;
use crate::model::PlaybackKind;
use crate::storage::keys::SessionObject;
use crate::storage::now_ms;
use crate::storage::workers::{HostRow, Lease, PhoneState, Requeued, TrialFailure};
use crate::storage::{body_stream, streamed};

/// The longest a lease request waits for a trial (`wait_s`).
pub(crate) const MAX_LEASE_WAIT: Duration = Duration::from_secs(20);
/// With a shared worker store (`--database`), how often a waiting lease request looks at it
/// again besides the local wake: another instance's offers wake nobody here, so a host
/// long-polling this instance sees them within this long (one claim query per waiting phone
/// and interval).
pub(crate) const STORE_RECHECK: Duration = Duration::from_secs(1);
/// The same for the instance's own store, where every offer wakes the waiting requests: only
/// so that a stopping server answers them.
const LOCAL_RECHECK: Duration = Duration::from_secs(5);
/// Phones one host may report.
pub(crate) const MAX_PHONES: usize = 256;
/// Longest host name, phone serial or failure message kept (bytes).
const MAX_NAME: usize = 64;
const MAX_MESSAGE: usize = 2_000;

fn lease_s(shared: &crate::app_state::App) -> f64 {
    shared.config.lease_timeout.as_secs_f64()
}

/// A name a host sent: printable, short.
fn check_name(what: &str, value: &str) -> Result<(), Error> {
    let ok = !value.is_empty()
        && value.len() <= MAX_NAME
        && value
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "._-:/@".contains(c));
    if ok {
        Ok(())
    } else {
        Err(Error::BadRequest(format!(
            "{what}: {:?} is not 1–{MAX_NAME} letters, digits or ._-:/@",
            crate::error::short(value, MAX_NAME)
        )))
    }
}

fn check_phones(phones: &[String]) -> Result<(), Error> {
    if phones.len() > MAX_PHONES {
        return Err(Error::BadRequest(format!(
            "phones: {} listed, at most {MAX_PHONES}",
            phones.len()
        )));
    }
    phones.iter().try_for_each(|p| check_name("phones", p))
}

/// Host `id` of the calling worker token; another token's host is a 404 as an unknown one.
fn own_host(
    shared: &crate::app_state::App,
    caller: &WorkerCaller,
    id: &str,
) -> Result<HostRow, Error> {
    shared
        .workers
        .host(id)?
        .filter(|h| h.token == caller.token)
        .ok_or_else(|| {
            Error::NotFound(format!(
                "no host {:?}: register again",
                crate::error::short(id, MAX_NAME)
            ))
        })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Register {
    name: String,
    playback: String,
    #[serde(default)]
    phones: Vec<String>,
}

/// `POST /v1/worker/hosts`: 201 `{"host","lease_s","heartbeat_s"}`.
pub(crate) async fn register(
    State(shared): AppState,
    caller: WorkerCaller,
    Json(body): Json<Register>,
) -> Result<Response, Error> {
    check_name("name", &body.name)?;
    check_phones(&body.phones)?;
    let kind: PlaybackKind = body.playback.parse().map_err(|e: String| {
        Error::BadRequest(format!("playback: {}", crate::error::short(&e, 200)))
    })?;
    if kind == PlaybackKind::Upload {
        return Err(Error::BadRequest(
            "playback: a host plays sim or adb, not upload".into(),
        ));
    }
    if !shared.remote_playback() {
        log::warn!(
            "host {} registered, but this server plays its sessions itself \
             (start it with --playback-workers 0 for hosts to get work)",
            body.name
        );
    }
    let workers = shared.workers.clone();
    let token = caller.token;
    let host = blocking("register host", move || {
        workers.register_host(token, &body.name, kind.as_str(), &body.phones, now_ms())
    })
    .await?;
    shared.board.wake();
    let lease = lease_s(&shared);
    Ok(json_value(
        StatusCode::CREATED,
        &json!({"host": host, "lease_s": lease, "heartbeat_s": lease / 4.0}),
    ))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Heartbeat {
    #[serde(default)]
    phones: Vec<String>,
    #[serde(default)]
    leases: Vec<String>,
}

/// `POST /v1/worker/hosts/{host}/heartbeat`: 200 `{"abort":[lease…],"out_of_service":[serial…],"lease_s"}`.
pub(crate) async fn heartbeat(
    State(shared): AppState,
    caller: WorkerCaller,
    Path(host): Path<String>,
    Json(body): Json<Heartbeat>,
) -> Result<Response, Error> {
    check_phones(&body.phones)?;
    if body.leases.len() > MAX_PHONES {
        return Err(Error::BadRequest(format!(
            "leases: {} listed, at most one per phone ({MAX_PHONES})",
            body.leases.len()
        )));
    }
    let lease_ms = shared.config.lease_timeout.as_millis() as i64;
    let workers = shared.workers.clone();
    let (abort, out) = {
        let shared = shared.clone();
        blocking("heartbeat", move || {
            let row = own_host(&shared, &caller, &host)?;
            let abort =
                workers.heartbeat(&row.id, &body.phones, &body.leases, now_ms(), lease_ms)?;
            let out: Vec<String> = workers
                .phones()?
                .into_iter()
                .filter(|p| p.host == row.id && p.state == PhoneState::OutOfService)
                .map(|p| p.serial)
                .collect();
            Ok((abort, out))
        })
        .await?
    };
    Ok(json_value(
        StatusCode::OK,
        &json!({"abort": abort, "out_of_service": out, "lease_s": lease_s(&shared)}),
    ))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LeaseRequest {
    phone: String,
    #[serde(default)]
    wait_s: Option<f64>,
}

fn lease_json(shared: &crate::app_state::App, lease: &Lease) -> serde_json::Value {
    json!({
        "lease": lease.id,
        "session": lease.session,
        "index": lease.index,
        "phone": lease.phone,
        "recording_sha256": lease.recording_sha256,
        "lease_s": lease_s(shared),
    })
}

/// `POST /v1/worker/hosts/{host}/leases` `{"phone","wait_s"}`: 200 a lease of the next trial
/// for that phone, or 204 after `wait_s` (≤ 20 s) with nothing to play.
pub(crate) async fn claim(
    State(shared): AppState,
    caller: WorkerCaller,
    Path(host): Path<String>,
    Json(body): Json<LeaseRequest>,
) -> Result<Response, Error> {
    check_name("phone", &body.phone)?;
    let wait = body
        .wait_s
        .filter(|w| w.is_finite() && *w >= 0.0)
        .map_or(Duration::ZERO, Duration::from_secs_f64)
        .min(MAX_LEASE_WAIT);
    let deadline = tokio::time::Instant::now() + wait;
    let lease_ms = shared.config.lease_timeout.as_millis() as i64;
    loop {
        let woken = shared.board.next_wake();
        tokio::pin!(woken);
        woken.as_mut().enable();
        let lease = {
            let (shared, phone) = (shared.clone(), body.phone.clone());
            let (host, token) = (host.clone(), caller.token);
            blocking("lease", move || {
                let row = shared
                    .workers
                    .host(&host)?
                    .filter(|h| h.token == token)
                    .ok_or_else(|| Error::NotFound(format!("no host {host:?}: register again")))?;
                if !shared.remote_playback() {
                    return Ok(None);
                }
                shared
                    .workers
                    .claim(&row.id, &phone, &row.playback, now_ms(), lease_ms)
            })
            .await?
        };
        if let Some(lease) = lease {
            return Ok(json_value(StatusCode::OK, &lease_json(&shared, &lease)));
        }
        let now = tokio::time::Instant::now();
        if now >= deadline || shared.stopping() {
            return Ok(StatusCode::NO_CONTENT.into_response());
        }
        // Woken when trials are offered here, leases expire or a host registers (its phones
        // may take what waits); trials another instance offered are seen at the next look,
        // within STORE_RECHECK; a server stopping answers within that too.
        let recheck = if shared.config.database.is_some() {
            STORE_RECHECK
        } else {
            LOCAL_RECHECK
        };
        let nap = (deadline - now).min(recheck);
        let _ = tokio::time::timeout(nap, woken).await;
    }
}

/// The lease `lease` of host `host` (the calling token's), live now; else 409 naming why.
fn live_lease(
    shared: &crate::app_state::App,
    caller: &WorkerCaller,
    host: &str,
    lease: &str,
) -> Result<(HostRow, Lease), Error> {
    let row = own_host(shared, caller, host)?;
    let lease = shared
        .workers
        .live_lease(lease, &row.id, now_ms())?
        .ok_or_else(|| {
            Error::Conflict(format!(
                "lease {:?} is not live (it expired, was withdrawn or was given to another \
                 phone): drop its trial",
                crate::error::short(lease, MAX_NAME)
            ))
        })?;
    Ok((row, lease))
}

/// `GET /v1/worker/hosts/{host}/leases/{lease}/recording`: the leased trial's recording (the
/// host keeps it by `recording_sha256`, so it asks once per recording).
pub(crate) async fn recording(
    State(shared): AppState,
    caller: WorkerCaller,
    Path((host, lease)): Path<(String, String)>,
) -> Result<Response, Error> {
    let lease = {
        let shared = shared.clone();
        blocking("lease", move || {
            live_lease(&shared, &caller, &host, &lease).map(|(_, l)| l)
        })
        .await?
    };
    let (len, body) = streamed::object_body(
        shared.blobs.clone(),
        &lease.session,
        SessionObject::Recording,
    )
    .await?
    .ok_or_else(|| Error::NotFound(format!("session {} has no recording", lease.session)))?;
    Ok((
        StatusCode::OK,
        [
            (header::CONTENT_TYPE, "application/octet-stream".to_string()),
            (header::CONTENT_LENGTH, len.to_string()),
        ],
        body,
    )
        .into_response())
}

/// `PUT /v1/worker/hosts/{host}/leases/{lease}/trial` (TUM text): 201 `{"session","index"}`
/// when committed; 409 when the lease is not live (the trial was, or will be, played
/// elsewhere: exactly one upload of a trial is ever taken); 422 naming line and column when
/// it cannot be parsed (the trial is offered again, the failure shown in the session's
/// status, and counted against the phone).
pub(crate) async fn trial(
    State(shared): AppState,
    caller: WorkerCaller,
    Path((host, lease)): Path<(String, String)>,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, Error> {
    let limit = shared.config.max_trajectory_bytes;
    check_declared_length(&headers, limit, "trajectory")?;
    let (row, leased) = {
        let (shared, host, lease) = (shared.clone(), host.clone(), lease.clone());
        let caller = WorkerCaller {
            token: caller.token,
            name: caller.name.clone(),
        };
        blocking("lease", move || live_lease(&shared, &caller, &host, &lease)).await?
    };
    let room = shared.blobs.reserve(
        Some(&leased.session),
        crate::http::helpers::declared_length(&headers),
    )?;
    let bytes = shared
        .blobs
        .receive_bytes_into(
            body_stream(body.into_data_stream()),
            limit,
            "trajectory",
            room,
        )
        .await?;
    let source = format!("{}/{}", row.name, leased.phone);
    let shared2 = shared.clone();
    blocking("commit trial", move || {
        let shared = shared2;
        let workers = &shared.workers;
        if let Err(e) = parse_trial(&bytes, "trial") {
            // Only a live lease's trial counts: a late garbage upload changes nothing.
            if let Some(requeued) = workers.give_back(&leased.id, &row.id)? {
                let failure = TrialFailure {
                    index: leased.index,
                    source: source.clone(),
                    error: e.client_message(),
                    at_ms: now_ms(),
                };
                workers.record_failure(&leased.session, &failure)?;
                workers.phone_result(&row.id, &leased.phone, Some(&failure.error))?;
                if requeued == Requeued::Again {
                    shared.board.wake();
                }
            }
            return Err(e);
        }
        // The text goes into the worker store with the commit: the session's job takes it
        // from there, on whichever instance it runs.
        let tum = String::from_utf8_lossy(&bytes);
        let lease = workers
            .commit(&leased.id, &row.id, now_ms(), &tum, &source)?
            .map_err(Error::Conflict)?;
        workers.phone_result(&row.id, &lease.phone, None)?;
        Ok(json_value(
            StatusCode::CREATED,
            &json!({"session": lease.session, "index": lease.index}),
        ))
    })
    .await
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Failure {
    error: String,
}

/// `POST /v1/worker/hosts/{host}/leases/{lease}/failure` `{"error"}`: the phone could not play
/// the trial. 200 `{"requeued","phone_state"}`: the trial is offered again (or given up after
/// 3 attempts) and the phone's failure counted (2 in a row: out of service).
pub(crate) async fn failure(
    State(shared): AppState,
    caller: WorkerCaller,
    Path((host, lease)): Path<(String, String)>,
    Json(body): Json<Failure>,
) -> Result<Response, Error> {
    let error = crate::error::short(&body.error, MAX_MESSAGE);
    let shared2 = shared.clone();
    let (requeued, state) = blocking("phone failure", move || {
        let shared = shared2;
        let (row, leased) = live_lease(&shared, &caller, &host, &lease)?;
        let requeued = shared
            .workers
            .give_back(&leased.id, &row.id)?
            .ok_or_else(|| Error::Conflict(format!("lease {} is not live", leased.id)))?;
        let failure = TrialFailure {
            index: leased.index,
            source: format!("{}/{}", row.name, leased.phone),
            error: error.clone(),
            at_ms: now_ms(),
        };
        shared.workers.record_failure(&leased.session, &failure)?;
        let state = shared
            .workers
            .phone_result(&row.id, &leased.phone, Some(&error))?;
        Ok((requeued, state))
    })
    .await?;
    shared.board.wake();
    Ok(json_value(
        StatusCode::OK,
        &json!({
            "requeued": requeued == Requeued::Again,
            "phone_state": state.as_str(),
        }),
    ))
}
