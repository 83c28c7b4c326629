//! HTTP helpers every handler uses, below all of them: JSON answers, the content type, the
//! declared body length, the idempotency key, the session lookup extractor, and blocking
//! work off the async workers.

use std::sync::Arc;

use axum::extract::{FromRequestParts, Path};
use axum::http::request::Parts;
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};

use crate::app_state::App;
use crate::error::Error;
use crate::model::{Caller, Session, Venue, is_venue_id};
use crate::storage::body_stream;
use crate::venue::Standing;

/// Runs `f` on tokio's blocking pool (file and CPU work off the async workers); a task that
/// panicked or was cancelled is an internal error naming `what`.
pub(crate) async fn blocking<T: Send + 'static>(
    what: &'static str,
    f: impl FnOnce() -> Result<T, Error> + Send + 'static,
) -> Result<T, Error> {
    tokio::task::spawn_blocking(f)
        .await
        .map_err(|e| Error::Internal(format!("{what}: {e}")))?
}

/// [`blocking`] within one of the render permits ([`App::renders`]): for answers built from
/// a session's scene, whose memory grows with the walk. `f` gets `shared`.
pub(crate) async fn rendering<T: Send + 'static>(
    shared: Arc<App>,
    what: &'static str,
    f: impl FnOnce(&App) -> Result<T, Error> + Send + 'static,
) -> Result<T, Error> {
    let gate = shared.clone();
    let _permit = gate
        .renders
        .acquire()
        .await
        .map_err(|e| Error::Internal(format!("{what}: {e}")))?;
    blocking(what, move || f(&shared)).await
}

/// The state every handler gets.
pub(crate) type AppState = axum::extract::State<Arc<App>>;

/// The header carrying a client-made key that makes a `POST` safe to retry.
pub const IDEMPOTENCY_HEADER: &str = "idempotency-key";

/// `curl --data-binary @file` labels any raw body form-urlencoded; the bytes
/// are still raw, so that label is accepted wherever a raw body is.
pub(crate) const CURL_DEFAULT_CONTENT_TYPE: &str = "application/x-www-form-urlencoded";

/// A JSON answer with `status`.
pub(crate) fn json_response(status: StatusCode, body: &str) -> Response {
    (
        status,
        [(header::CONTENT_TYPE, "application/json")],
        body.to_string(),
    )
        .into_response()
}

/// A JSON answer of `value` with `status`.
pub(crate) fn json_value(status: StatusCode, value: &serde_json::Value) -> Response {
    json_response(status, &value.to_string())
}

/// The media type of the request body, lower case, without parameters ("" when none).
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

/// The request's `Idempotency-Key` (1 to 128 ASCII characters), if it has one.
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

/// The session a route's `{id}` names, looked up before the handler runs: a handler that
/// takes it never sees an unknown or malformed id, nor another app token's session (both
/// 404, with the same message: its existence is not revealed).
pub(crate) struct Found(pub Session);

impl FromRequestParts<Arc<App>> for Found {
    type Rejection = Error;

    async fn from_request_parts(parts: &mut Parts, shared: &Arc<App>) -> Result<Self, Error> {
        let Path(id) = Path::<String>::from_request_parts(parts, shared)
            .await
            .map_err(|e| Error::NotFound(format!("no session: {e}")))?;
        let caller = Caller::from_request_parts(parts, shared).await?;
        visible_session(shared, &caller, &id).map(Found)
    }
}

/// The session `id` if `caller` may see it; otherwise the same 404 as an unknown id.
/// [`Found`] uses it; routes with more path parameters than `{id}` call it themselves.
pub(crate) fn visible_session(shared: &App, caller: &Caller, id: &str) -> Result<Session, Error> {
    let session = shared.session(id)?;
    if caller.may_see(&session) {
        Ok(session)
    } else {
        Err(Error::NotFound(format!("no session {id:?}")))
    }
}

/// Venue `id` and how `caller` stands to it, if it may see it; otherwise a 404 with the same
/// message as an unknown id (its existence is not revealed).
pub(crate) fn visible_venue(
    shared: &App,
    caller: &Caller,
    id: &str,
) -> Result<(Venue, Standing), Error> {
    let unknown = || Error::NotFound(format!("no venue {id:?}"));
    if !is_venue_id(id) {
        return Err(unknown());
    }
    let venue = shared.db.venue(id)?.ok_or_else(unknown)?;
    match Standing::of(&*shared.db, caller, &venue)? {
        Some(standing) => Ok((venue, standing)),
        None => Err(unknown()),
    }
}

/// The whole body, refused with a 413 once it passes `limit` (declared or sent) or the
/// session's disk quota (507 past the server's).
pub(crate) async fn small_body(
    shared: &App,
    id: &str,
    headers: &HeaderMap,
    body: axum::body::Body,
    limit: u64,
    what: &'static str,
) -> Result<Vec<u8>, Error> {
    check_declared_length(headers, limit, what)?;
    let room = shared.blobs.reserve(Some(id), declared_length(headers))?;
    shared
        .blobs
        .receive_bytes_into(body_stream(body.into_data_stream()), limit, what, room)
        .await
}

pub(crate) fn utf8(bytes: Vec<u8>, what: &str) -> Result<String, Error> {
    String::from_utf8(bytes).map_err(|e| {
        Error::InvalidContent(format!(
            "{what} is not UTF-8 text (byte {})",
            e.utf8_error().valid_up_to()
        ))
    })
}

/// A download: `body` (bytes, text or a streamed body) as the file `file_name` of type
/// `content_type`.
pub(crate) fn attachment(
    content_type: &'static str,
    file_name: &str,
    body: impl IntoResponse,
) -> Response {
    let disposition = format!("attachment; filename=\"{file_name}\"");
    (
        [
            (header::CONTENT_TYPE, content_type.to_owned()),
            (header::CONTENT_DISPOSITION, disposition),
        ],
        body,
    )
        .into_response()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_attachment_has_its_type_and_file_name_and_no_other_header() {
        let response = attachment("application/zip", "trials.zip", b"PK".to_vec());
        let headers = response.headers();
        assert_eq!(headers[header::CONTENT_TYPE], "application/zip");
        assert_eq!(
            headers[header::CONTENT_DISPOSITION],
            "attachment; filename=\"trials.zip\""
        );
        assert_eq!(headers.len(), 2, "{headers:?}");
    }
}
