//! `PUT` and `HEAD /v1/sessions/{id}/recording`: recording uploads, whole, and resumed
//! after a dropped connection.
//!
//! A `PUT /v1/sessions/{id}/recording` whose body breaks off (the phone's Wi-Fi
//! dropped) keeps what arrived as `recording.part`, tied to the request's
//! `Idempotency-Key`. `HEAD` on the same URL with the same key tells how much
//! is kept (`Upload-Offset`), and a `PUT` with that key and
//! `Content-Range: bytes S-E/T` appends from byte `S`, which must be the kept
//! length. When the kept bytes reach `T` the recording is whole and is
//! accepted exactly as a whole upload is. So a 2 GiB upload that fails at 90 %
//! sends the last 10 %, not all of it again.
//!
//! The key keeps uploads apart: bytes kept from one file are never continued
//! with another (another key sees offset 0), and the latest whole upload that
//! broke off replaces any older prefix.

use std::sync::Arc;

use axum::body::Body;
use axum::extract::State;
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde_json::json;

use crate::app_state::App;
use crate::error::Error;
use crate::http::helpers::{
    AppState, CURL_DEFAULT_CONTENT_TYPE, Found, check_declared_length, content_type,
    declared_length, idempotency_key, json_response,
};
use crate::jobs::recordings::accept_recording;
use crate::model::{PlaybackKind, Session, SessionState, Step};
use crate::storage::body_stream;
use crate::storage::keys::SessionObject;

/// Response header: the bytes of an interrupted upload the server keeps.
pub const UPLOAD_OFFSET_HEADER: &str = "upload-offset";

fn recording_content_type_ok(ct: &str) -> bool {
    matches!(
        ct,
        "" | "application/octet-stream"
            | "application/x-sitar-recording"
            | CURL_DEFAULT_CONTENT_TYPE
    ) || ct.starts_with("video/")
}

/// `PUT /v1/sessions/{id}/recording`: a whole recording, or with `Content-Range`
/// the rest of an interrupted one.
pub(crate) async fn put_recording(
    State(shared): AppState,
    Found(row): Found,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, Error> {
    let ct = content_type(&headers);
    if !recording_content_type_ok(&ct) {
        return Err(Error::UnsupportedMediaType(format!(
            "a recording is a raw body (application/octet-stream or video/mp4), not {ct}"
        )));
    }
    if row.playback == PlaybackKind::Upload {
        row.require(Step::AcceptRecording)?;
    }
    let limit = shared.config.max_recording_bytes;
    let key = idempotency_key(&headers)?;
    match content_range(&headers)? {
        Some(range) => resume(&shared, &row, &headers, key, range, body).await,
        None => {
            check_declared_length(&headers, limit, "recording")?;
            whole(&shared, &row, &headers, key, body).await
        }
    }
}

/// `HEAD /v1/sessions/{id}/recording`: `Upload-Offset` is the length of the kept prefix
/// of the interrupted upload with the request's `Idempotency-Key` (0 when there is none).
pub(crate) async fn kept_offset(
    State(shared): AppState,
    Found(row): Found,
    headers: HeaderMap,
) -> Result<Response, Error> {
    let key = idempotency_key(&headers)?;
    // An upload still writing the prefix (its client may already have given up: the server
    // sees the break a moment later) holds the lock; its final length is the one to resume
    // from. If it holds on, the length so far is a valid prefix too.
    let lock = shared.session_lock(&row.id);
    let _held = tokio::time::timeout(UPLOAD_LOCK_WAIT, lock.lock()).await;
    let kept = kept_for(&shared, &row.id, key.as_deref())?.unwrap_or(0);
    let mut response = StatusCode::OK.into_response();
    let headers = response.headers_mut();
    headers.insert(UPLOAD_OFFSET_HEADER, HeaderValue::from(kept));
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    Ok(response)
}

/// A plain `PUT`: streamed straight into `recording.part` under the request's key (total
/// and key written first), so a body broken off — even by a crash of the server — leaves a
/// prefix a range `PUT` with the same key resumes from.
async fn whole(
    shared: &Arc<App>,
    row: &Session,
    headers: &HeaderMap,
    key: Option<String>,
    body: Body,
) -> Result<Response, Error> {
    let limit = shared.config.max_recording_bytes;
    let lock = shared.session_lock(&row.id);
    let Ok(_held) = tokio::time::timeout(UPLOAD_LOCK_WAIT, lock.lock()).await else {
        return Err(busy_uploading(&row.id));
    };
    // The session may have been deleted, or moved on, since the request was routed.
    let row = &shared.session(&row.id)?;
    let id = &row.id;
    // The latest upload's prefix replaces any older one: a retry resumes from it.
    discard_part(shared, id)?;
    let declared = declared_length(headers);
    let room = shared.blobs.reserve(Some(id), declared)?;
    if let Some(total) = declared.filter(|&n| n > 0) {
        shared.blobs.put(
            id,
            SessionObject::RecordingPartTotal,
            total.to_string().as_bytes(),
        )?;
    }
    write_key(shared, id, key.as_deref())?;
    let appended = shared
        .blobs
        .append_to(
            body_stream(body.into_data_stream()),
            id,
            SessionObject::RecordingPart,
            0,
            limit,
            "recording",
            room,
        )
        .await;
    let appended = match appended {
        Ok(appended) => appended,
        Err(error) => {
            discard_part(shared, id)?;
            return Err(error);
        }
    };
    if let Some(error) = appended.broken {
        if appended.len == 0 || shared.blobs.exists(id, SessionObject::Recording) {
            discard_part(shared, id)?;
        }
        return Err(error);
    }
    let temp = shared.blobs.staged_part(id, appended.len);
    let accepted = accept_recording(shared, row, temp);
    discard_part(shared, id)?;
    accepted?;
    Ok(uploaded(id))
}

/// How long an upload waits for an earlier one to the same session to end (a client that
/// retries right after its connection dropped: the server may not have seen the drop yet).
const UPLOAD_LOCK_WAIT: std::time::Duration = std::time::Duration::from_secs(5);

fn busy_uploading(id: &str) -> Error {
    Error::Conflict(format!(
        "another upload to session {id} is still being received; try again shortly"
    ))
}

async fn resume(
    shared: &Arc<App>,
    row: &Session,
    headers: &HeaderMap,
    key: Option<String>,
    range: ContentRange,
    body: Body,
) -> Result<Response, Error> {
    let limit = shared.config.max_recording_bytes;
    if range.total > limit {
        return Err(Error::TooLarge {
            what: "recording",
            limit,
        });
    }
    if let Some(n) = declared_length(headers)
        && n != range.len()
    {
        return Err(Error::BadRequest(format!(
            "Content-Length {n} does not match Content-Range bytes {}-{}/{} ({} bytes)",
            range.start,
            range.last,
            range.total,
            range.len()
        )));
    }
    let lock = shared.session_lock(&row.id);
    let Ok(_held) = tokio::time::timeout(UPLOAD_LOCK_WAIT, lock.lock()).await else {
        return Err(busy_uploading(&row.id));
    };
    let row = &shared.session(&row.id)?;
    let kept = match kept_for(shared, &row.id, key.as_deref())? {
        Some(kept) => kept,
        None if range.start == 0 => {
            // A chunked upload from byte 0 under a new key: it starts a fresh prefix.
            discard_part(shared, &row.id)?;
            write_key(shared, &row.id, key.as_deref())?;
            0
        }
        None => 0,
    };
    if range.start != kept {
        let mut response = Error::Conflict(format!(
            "Content-Range starts at byte {}, but {kept} bytes of session {}'s recording are kept: \
             resume from byte {kept}",
            range.start, row.id
        ))
        .into_response();
        response
            .headers_mut()
            .insert(UPLOAD_OFFSET_HEADER, HeaderValue::from(kept));
        return Ok(response);
    }
    check_total(shared, &row.id, range.total)?;
    let end = range.last + 1;
    let room = shared.blobs.reserve(Some(&row.id), Some(range.len()))?;
    let now = shared
        .blobs
        .append_to(
            body_stream(body.into_data_stream()),
            &row.id,
            SessionObject::RecordingPart,
            kept,
            end,
            "recording",
            room,
        )
        .await?
        .len;
    if now == range.total {
        let temp = shared.blobs.staged_part(&row.id, now);
        let accepted = accept_recording(shared, row, temp);
        discard_part(shared, &row.id)?;
        accepted?;
        return Ok(uploaded(&row.id));
    }
    if now < end {
        return Err(Error::BadRequest(format!(
            "recording: the body ended at byte {now}, before the end of its Content-Range \
             ({end}); the {now} bytes are kept"
        )));
    }
    let mut response = json_response(
        StatusCode::OK,
        &json!({"id": row.id, "state": row.state.as_str(), "received": now, "total": range.total})
            .to_string(),
    );
    response
        .headers_mut()
        .insert(UPLOAD_OFFSET_HEADER, HeaderValue::from(now));
    Ok(response)
}

fn uploaded(id: &str) -> Response {
    json_response(
        StatusCode::ACCEPTED,
        &json!({"id": id, "state": SessionState::Uploaded.as_str()}).to_string(),
    )
}

/// The kept prefix's length if it belongs to the upload with `key` (no key is the empty
/// key); `None` when the prefix is another upload's, or has no key file.
fn kept_for(shared: &App, id: &str, key: Option<&str>) -> Result<Option<u64>, Error> {
    let Some(stored) = shared.blobs.get(id, SessionObject::RecordingPartKey)? else {
        return Ok(None);
    };
    if stored != key.unwrap_or("").as_bytes() {
        return Ok(None);
    }
    Ok(Some(
        shared
            .blobs
            .len(id, SessionObject::RecordingPart)?
            .unwrap_or(0),
    ))
}

fn write_key(shared: &App, id: &str, key: Option<&str>) -> Result<(), Error> {
    shared.blobs.put(
        id,
        SessionObject::RecordingPartKey,
        key.unwrap_or("").as_bytes(),
    )
}

/// The first chunk of a prefix fixes the recording's total size; a later chunk declaring
/// another total is a conflict naming both (the bytes kept so far stay).
fn check_total(shared: &App, id: &str, total: u64) -> Result<(), Error> {
    let stored = shared.blobs.get(id, SessionObject::RecordingPartTotal)?;
    let fixed = stored.and_then(|bytes| String::from_utf8_lossy(&bytes).trim().parse::<u64>().ok());
    match fixed {
        Some(fixed) if fixed == total => Ok(()),
        Some(fixed) => Err(Error::Conflict(format!(
            "Content-Range total {total} differs from the total {fixed} the upload's first \
             chunk declared"
        ))),
        // None yet, or unreadable: this chunk fixes it.
        None => shared.blobs.put(
            id,
            SessionObject::RecordingPartTotal,
            total.to_string().as_bytes(),
        ),
    }
}

/// Removes the kept prefix and its key (key first: a prefix without a key is never used).
fn discard_part(shared: &App, id: &str) -> Result<(), Error> {
    for object in [
        SessionObject::RecordingPartKey,
        SessionObject::RecordingPartTotal,
        SessionObject::RecordingPart,
    ] {
        shared.blobs.remove(id, object)?;
    }
    Ok(())
}

/// `Content-Range: bytes START-LAST/TOTAL` (inclusive `LAST`, as in RFC 9110).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ContentRange {
    pub(crate) start: u64,
    pub(crate) last: u64,
    pub(crate) total: u64,
}

impl ContentRange {
    fn len(&self) -> u64 {
        self.last - self.start + 1
    }
}

fn content_range(headers: &HeaderMap) -> Result<Option<ContentRange>, Error> {
    let Some(value) = headers.get(header::CONTENT_RANGE) else {
        return Ok(None);
    };
    let text = value.to_str().unwrap_or("");
    parse_content_range(text).map(Some).ok_or_else(|| {
        Error::BadRequest(format!(
            "Content-Range {text:?} is not `bytes START-LAST/TOTAL` with START <= LAST < TOTAL"
        ))
    })
}

pub(crate) fn parse_content_range(text: &str) -> Option<ContentRange> {
    let rest = text.trim().strip_prefix("bytes ")?;
    let (span, total) = rest.split_once('/')?;
    let (start, last) = span.split_once('-')?;
    let number = |s: &str| {
        let s = s.trim();
        (!s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
            .then(|| s.parse::<u64>().ok())
            .flatten()
    };
    let range = ContentRange {
        start: number(start)?,
        last: number(last)?,
        total: number(total)?,
    };
    (range.start <= range.last && range.last < range.total).then_some(range)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn content_range_parses_only_the_whole_well_formed_form() {
        assert_eq!(
            parse_content_range("bytes 100-199/200"),
            Some(ContentRange {
                start: 100,
                last: 199,
                total: 200
            })
        );
        assert_eq!(parse_content_range("bytes 0-0/1").map(|r| r.len()), Some(1));
        for bad in [
            "bytes 5-4/10",
            "bytes 0-10/10",
            "bytes */10",
            "bytes 0-9/*",
            "bytes -1-9/10",
            "bytes +1-9/10",
            "items 0-9/10",
            "bytes 0-9",
            "bytes 0-99999999999999999999/100000000000000000000",
            "",
        ] {
            assert_eq!(parse_content_range(bad), None, "{bad}");
        }
    }

    proptest::proptest! {
        #[test]
        fn every_well_formed_range_parses_back(
            start in 0u64..u64::MAX - 1,
            len in 1u64..1 << 40,
            extra in 0u64..1 << 40,
        ) {
            let last = start.saturating_add(len - 1).min(u64::MAX - 2);
            let total = last.saturating_add(1).saturating_add(extra);
            let text = format!("bytes {start}-{last}/{total}");
            proptest::prop_assert_eq!(
                parse_content_range(&text),
                Some(ContentRange { start, last, total })
            );
        }

        #[test]
        fn any_text_parses_without_panicking_and_only_to_a_valid_range(text in ".{0,40}") {
            if let Some(r) = parse_content_range(&text) {
                proptest::prop_assert!(r.start <= r.last && r.last < r.total);
            }
        }
    }
}
