//! A session's evidence: what the phone's camera saw at each sub-trajectory.
//!
//! `PUT /v1/sessions/{id}/evidence.csv` (the phone's properties table),
//! `PUT /v1/sessions/{id}/subtrajectories.csv` (the phone's sub-trajectory table: start and
//! end of each), `PUT /v1/sessions/{id}/subtrajectories/{k}/image.jpg` (one thumbnail);
//! `GET /v1/sessions/{id}/subtrajectories` (everything joined with the latest results) and
//! `GET /v1/sessions/{id}/subtrajectories/{k}/image.jpg`. Every `PUT` replaces what it
//! names, so a retried or resumed upload sends each small file again and nothing else.

use axum::body::Body;
use axum::extract::{Path, RawQuery, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde_json::{Value, json};
use sitar_core::Results;

use crate::app_state::App;
use crate::error::Error;
use crate::estimate::results_files::{self, Form};
use crate::http::helpers::{AppState, Found, json_value, small_body, utf8, visible_session};
use crate::http::pagination::PageRequest;
use crate::ingest::evidence::{
    EvidenceFiles, MAX_SUBTRAJECTORIES, MAX_TABLE_BYTES, MAX_THUMBNAIL_BYTES, check_jpeg,
    parse_evidence,
};
use crate::ingest::phone_log::parse_subtrajectories;
use crate::model::{Caller, Session};
use crate::storage::keys::SessionObject;

/// Runs `store` under the session's lock, after checking the session still exists (it may
/// have been deleted while the body was arriving: nothing is written for it then).
async fn under_lock(
    shared: &App,
    id: &str,
    store: impl FnOnce(&EvidenceFiles<'_>) -> Result<(), Error>,
) -> Result<(), Error> {
    let lock = shared.session_lock(id);
    let _held = lock.lock().await;
    shared.session(id)?;
    store(&EvidenceFiles {
        blobs: &*shared.blobs,
        id,
    })
}

/// `PUT /v1/sessions/{id}/evidence.csv`.
pub(crate) async fn put_evidence(
    State(shared): AppState,
    Found(session): Found,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, Error> {
    let rows =
        parse_evidence(&table_text(&shared, &session.id, &headers, body, "evidence.csv").await?)?;
    under_lock(&shared, &session.id, |f| f.store_evidence(&rows)).await?;
    Ok(stored(rows.len()))
}

/// `PUT /v1/sessions/{id}/subtrajectories.csv`.
pub(crate) async fn put_spans(
    State(shared): AppState,
    Found(session): Found,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, Error> {
    let text = table_text(&shared, &session.id, &headers, body, "subtrajectories.csv").await?;
    let table = parse_subtrajectories(&text)?;
    under_lock(&shared, &session.id, |f| {
        // The whole table first: a reader never sees new spans beside an old table.
        match table.depth_samples {
            Some(_) => f
                .blobs
                .put(f.id, SessionObject::Subtrajectories, text.as_bytes())?,
            None => f.blobs.remove(f.id, SessionObject::Subtrajectories)?,
        }
        f.store_spans(&table.spans)
    })
    .await?;
    // Its venue's map computes its contribution again from the new table.
    shared.db.forget_contribution(&session.id)?;
    // The scene from the phone's log takes its depth from this table.
    crate::report::scene::phone_log_changed(&*shared.blobs, &session.id);
    let mut answer = json!({"subtrajectories": table.spans.len()});
    if let Some(n) = table.depth_samples {
        answer["depth_samples"] = n.into();
    }
    Ok(json_value(StatusCode::OK, &answer))
}

/// A phone table's body as text: bounded by `MAX_TABLE_BYTES`, UTF-8, errors naming `name`.
async fn table_text(
    shared: &App,
    id: &str,
    headers: &HeaderMap,
    body: Body,
    name: &'static str,
) -> Result<String, Error> {
    utf8(
        small_body(shared, id, headers, body, MAX_TABLE_BYTES, name).await?,
        name,
    )
}

/// The answer to a stored table: how many sub-trajectories it holds.
fn stored(rows: usize) -> Response {
    json_value(StatusCode::OK, &json!({"subtrajectories": rows}))
}

/// The session and the sub-trajectory index of a `…/subtrajectories/{k}/…` route: the same
/// lookup as every per-session route, and `k` a number below the session's row count.
fn session_and_index(
    shared: &App,
    caller: &Caller,
    id: &str,
    k: &str,
) -> Result<(Session, usize), Error> {
    let session = visible_session(shared, caller, id)?;
    let k: usize = k
        .parse()
        .ok()
        .filter(|k| *k < MAX_SUBTRAJECTORIES)
        .ok_or_else(|| Error::NotFound(format!("no sub-trajectory {k:?}")))?;
    Ok((session, k))
}

/// `PUT /v1/sessions/{id}/subtrajectories/{k}/image.jpg`: after `evidence.csv`, for a row
/// that says it has an image.
pub(crate) async fn put_image(
    State(shared): AppState,
    caller: Caller,
    Path((id, k)): Path<(String, String)>,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, Error> {
    let (session, k) = session_and_index(&shared, &caller, &id, &k)?;
    let jpeg = small_body(
        &shared,
        &session.id,
        &headers,
        body,
        MAX_THUMBNAIL_BYTES,
        "image.jpg",
    )
    .await?;
    check_jpeg(&jpeg)?;
    under_lock(&shared, &session.id, |f| {
        let rows = f.evidence_rows()?.ok_or_else(|| {
            Error::Conflict(format!(
                "session {} has no evidence.csv yet: send it before the images",
                session.id
            ))
        })?;
        match rows.get(k) {
            None => Err(Error::NotFound(format!(
                "no sub-trajectory {k}: evidence.csv has {}",
                rows.len()
            ))),
            Some(row) if row.image.is_none() => Err(Error::InvalidContent(format!(
                "sub-trajectory {k} has no camera image in evidence.csv (image = 0)"
            ))),
            Some(_) => f.store_thumbnail(k, &jpeg),
        }
    })
    .await?;
    Ok(StatusCode::NO_CONTENT.into_response())
}

/// `GET /v1/sessions/{id}/subtrajectories/{k}/image.jpg`.
pub(crate) async fn get_image(
    State(shared): AppState,
    caller: Caller,
    Path((id, k)): Path<(String, String)>,
) -> Result<Response, Error> {
    let (session, k) = session_and_index(&shared, &caller, &id, &k)?;
    let jpeg = EvidenceFiles {
        blobs: &*shared.blobs,
        id: &session.id,
    }
    .read_thumbnail(k)?
    .ok_or_else(|| {
        Error::NotFound(format!(
            "session {} has no image of sub-trajectory {k}",
            session.id
        ))
    })?;
    Ok(jpeg_response(jpeg))
}

/// A thumbnail's answer (the owner's route and a share link's).
pub(crate) fn jpeg_response(jpeg: Vec<u8>) -> Response {
    let mut response = jpeg.into_response();
    response
        .headers_mut()
        .insert(header::CONTENT_TYPE, HeaderValue::from_static("image/jpeg"));
    response
}

/// `GET /v1/sessions/{id}/subtrajectories`: per sub-trajectory its start and end (ns), the
/// error and class of the latest results' window at its start (sitar-core's lookup; `null`
/// before results or when no window starts there), its properties and likely causes, and
/// its image's URL (`null` without one).
pub(crate) async fn list(
    State(shared): AppState,
    Found(session): Found,
    RawQuery(query): RawQuery,
) -> Result<Response, Error> {
    let page = PageRequest::parse(query.as_deref())?;
    let files = EvidenceFiles {
        blobs: &*shared.blobs,
        id: &session.id,
    };
    let rows = files.evidence_rows()?.unwrap_or_default();
    let spans = files.stored_spans()?.unwrap_or_default();
    let results = match session.results_trials {
        0 => None,
        _ => Some(
            Results::parse_json(&results_files::read(&*shared.blobs, &session, Form::Json)?)
                .map_err(|e| Error::Internal(format!("published results: {e}")))?,
        ),
    };
    let thresholds = session
        .settings
        .thresholds(shared.config.thresholds, shared.config.thresholds_deg);
    let n = rows.len().max(spans.len());
    let from = page.offset.min(n);
    let to = from.saturating_add(page.limit).min(n);
    let subtrajectories: Vec<Value> = (from..to)
        .map(|k| {
            let span = spans.get(k);
            let start = span.map(|s| s.start_ns);
            let end = span.and_then(|s| s.end_ns);
            let window = match (&results, start) {
                (Some(r), Some(start)) => r.lookup(start, tolerance_ns(span, r)),
                _ => None,
            };
            let row = rows.get(k);
            let image_url = row.filter(|r| r.image.is_some()).and_then(|_| {
                files
                    .has_thumbnail(k)
                    .then(|| format!("/v1/sessions/{}/subtrajectories/{k}/image.jpg", session.id))
            });
            json!({
                "index": k,
                "start_ns": start,
                "end_ns": end,
                "error": window.map(|w| w.error),
                "class": window.map(|w| thresholds.classify(w.error).name()),
                "image": row.and_then(|r| r.image),
                "thumbnail_size": row.and_then(|r| r.thumbnail_size),
                "motion": row.map(|r| json!({
                    "linear_speed_m_s": r.linear_speed_m_s,
                    "angular_speed_deg_s": r.angular_speed_deg_s,
                })),
                "depth": row.map(|r| json!({
                    "valid": r.depth_valid,
                    "distance_m": r.distance_m,
                    "valid_share": r.depth_valid_share,
                })),
                "causes": row.map(|r| r.causes.clone()).unwrap_or_default(),
                "image_url": image_url,
            })
        })
        .collect();
    let unit = results.as_ref().map(|r| r.unit());
    let mut answer = json!({
        "id": session.id,
        "unit": unit.map(|u| u.name()),
        "subtrajectories": subtrajectories,
    });
    if (from, to) != (0, n) {
        answer["page"] = json!({
            "offset": from,
            "limit": page.limit,
            "total": n,
            "next": (to < n).then_some(to),
        });
    }
    Ok(json_value(StatusCode::OK, &answer))
}

/// How far a window's start may be from the sub-trajectory's: half its mean frame interval
/// (the phone's default is half the median frame interval, which the server does not have).
fn tolerance_ns(span: Option<&crate::ingest::evidence::Span>, results: &Results) -> i64 {
    let frames = i64::from(results.window_frames.unwrap_or(10).max(1));
    span.and_then(|s| s.end_ns.map(|e| (e - s.start_ns) / frames / 2))
        .unwrap_or(0)
}
