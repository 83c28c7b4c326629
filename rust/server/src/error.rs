use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
#[cfg(test)]
use std::path::Path;

/// Everything that can go wrong in the backend.
///
/// Request-level variants map to a 4xx status and a JSON body
/// `{"error":{"code":…,"message":…}}`; the rest to 5xx.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No session (or resource) with that id: 404 `not_found`.
    #[error("{0}")]
    NotFound(String),
    /// The request is malformed (bad JSON, bad multipart, missing field): 400 `bad_request`.
    #[error("{0}")]
    BadRequest(String),
    /// No token, or an unknown or revoked one: 401 `unauthorized` with `WWW-Authenticate: Bearer`.
    #[error("{0}")]
    Unauthorized(String),
    /// The token's role does not allow this route: 403 `forbidden`.
    #[error("{0}")]
    Forbidden(String),
    /// Over one of the token's limits: 429 `too_many_requests` with `Retry-After`.
    #[error("{message}; retry in {retry_after_s} s")]
    TooManyRequests {
        /// Which limit, and how far it is used.
        message: String,
        /// Seconds until the request would go through.
        retry_after_s: u64,
    },
    /// The request body has a content type this route does not take: 415 `unsupported_media_type`.
    #[error("{0}")]
    UnsupportedMediaType(String),
    /// The body is larger than the configured limit: 413 `too_large`.
    #[error("{what} is larger than the limit of {limit} bytes")]
    TooLarge {
        /// What was uploaded.
        what: &'static str,
        /// The limit in bytes.
        limit: u64,
    },
    /// An upload would pass the session's disk quota: 413 `too_large`.
    #[error("{0}")]
    QuotaExceeded(String),
    /// An upload would pass the server's disk quota: 507 `insufficient_storage`.
    #[error("{0}")]
    InsufficientStorage(String),
    /// The request does not fit the session's state (e.g. estimate before 2 trials): 409 `conflict`.
    #[error("{0}")]
    Conflict(String),
    /// The session's state does not allow the step asked for: 409 `conflict`, naming the state.
    #[error("session {session} is {state}: it cannot {action}")]
    Transition {
        /// The session.
        session: String,
        /// Its state (wire name: `created`, `uploaded`, `playing`, `estimating`, `done`, `failed`).
        state: &'static str,
        /// What was asked, e.g. `take more trials`.
        action: &'static str,
    },
    /// The server holds as much as its memory bound allows and cannot take this now: 503
    /// `busy`. Retrying later (when other sessions have finished) can succeed.
    #[error("{0}")]
    Busy(String),
    /// An uploaded trajectory or recording cannot be read: 422 `invalid_content`.
    #[error("{0}")]
    InvalidContent(String),
    /// A file in the data directory could not be read or written: 500 `io`. The log gets
    /// the whole path; the client only the session-relative one.
    #[error("{context} {}: {source}", path.display())]
    Io {
        /// What was being done.
        context: String,
        /// The file.
        path: std::path::PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The metadata store failed: 500 `database`.
    #[error("database: {0}")]
    Database(String),
    /// The estimator rejected the trials: 500 `estimate` (or 422 when the input is at fault).
    #[error("estimate: {0}")]
    Estimate(String),
    /// A playback backend failed (adb missing, device lost, recording unreadable).
    #[error("playback: {0}")]
    Playback(String),
    /// The configuration is unusable (e.g. data directory not writable, bad address).
    #[error("configuration: {0}")]
    Config(String),
    /// Anything else that should not happen: 500 `internal`.
    #[error("internal: {0}")]
    Internal(String),
}

impl Error {
    pub(crate) fn io(
        context: impl Into<String>,
        path: &std::path::Path,
        source: std::io::Error,
    ) -> Error {
        Error::Io {
            context: context.into(),
            path: path.to_path_buf(),
            source,
        }
    }

    /// The message a client sees: as [`std::fmt::Display`], but a data-directory file is
    /// named relative to its session (`session ID: trials/3.tum`), never by its server path.
    pub fn client_message(&self) -> String {
        match self {
            Error::Io {
                context,
                path,
                source,
            } => format!("{context} {}: {source}", client_path(path)),
            other => other.to_string(),
        }
    }

    /// HTTP status and machine-readable code of this error.
    pub fn status_and_code(&self) -> (StatusCode, &'static str) {
        match self {
            Error::NotFound(_) => (StatusCode::NOT_FOUND, "not_found"),
            Error::BadRequest(_) => (StatusCode::BAD_REQUEST, "bad_request"),
            Error::Unauthorized(_) => (StatusCode::UNAUTHORIZED, "unauthorized"),
            Error::Forbidden(_) => (StatusCode::FORBIDDEN, "forbidden"),
            Error::TooManyRequests { .. } => (StatusCode::TOO_MANY_REQUESTS, "too_many_requests"),
            Error::UnsupportedMediaType(_) => {
                (StatusCode::UNSUPPORTED_MEDIA_TYPE, "unsupported_media_type")
            }
            Error::TooLarge { .. } | Error::QuotaExceeded(_) => {
                (StatusCode::PAYLOAD_TOO_LARGE, "too_large")
            }
            Error::InsufficientStorage(_) => {
                (StatusCode::INSUFFICIENT_STORAGE, "insufficient_storage")
            }
            Error::Conflict(_) | Error::Transition { .. } => (StatusCode::CONFLICT, "conflict"),
            Error::Busy(_) => (StatusCode::SERVICE_UNAVAILABLE, "busy"),
            Error::InvalidContent(_) => (StatusCode::UNPROCESSABLE_ENTITY, "invalid_content"),
            Error::Io { .. } => (StatusCode::INTERNAL_SERVER_ERROR, "io"),
            Error::Database(_) => (StatusCode::INTERNAL_SERVER_ERROR, "database"),
            Error::Estimate(_) => (StatusCode::INTERNAL_SERVER_ERROR, "estimate"),
            Error::Playback(_) => (StatusCode::INTERNAL_SERVER_ERROR, "playback"),
            Error::Config(_) => (StatusCode::INTERNAL_SERVER_ERROR, "config"),
            Error::Internal(_) => (StatusCode::INTERNAL_SERVER_ERROR, "internal"),
        }
    }
}

/// `sessions/ID/trials/3.tum` under any directory as `session ID: trials/3.tum`; any other
/// path as its file name alone.
fn client_path(path: &std::path::Path) -> String {
    let parts: Vec<_> = path.components().map(|c| c.as_os_str()).collect();
    if let Some(at) = parts.iter().rposition(|p| *p == "sessions")
        && at + 1 < parts.len()
    {
        let id = parts[at + 1].to_string_lossy();
        let rest: std::path::PathBuf = parts[at + 2..].iter().collect();
        return match rest.as_os_str().is_empty() {
            true => format!("session {id}"),
            false => format!("session {id}: {}", rest.display()),
        };
    }
    path.file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
}

/// At most `limit` bytes of client input to quote in a message (cut at a character
/// boundary, `…` marking the cut).
pub(crate) fn short(text: &str, limit: usize) -> String {
    if text.len() <= limit {
        return text.to_owned();
    }
    let cut = (0..=limit)
        .rev()
        .find(|&i| text.is_char_boundary(i))
        .unwrap_or(0);
    format!("{}…", &text[..cut])
}

/// The JSON error body every failing route answers with.
pub(crate) fn error_body(code: &str, message: &str) -> String {
    serde_json::json!({"error": {"code": code, "message": message}}).to_string()
}

impl IntoResponse for Error {
    fn into_response(self) -> Response {
        let (status, code) = self.status_and_code();
        if status.is_server_error() {
            log::error!("{self}");
        }
        let mut response = (status, error_body(code, &self.client_message())).into_response();
        response.headers_mut().insert(
            axum::http::header::CONTENT_TYPE,
            axum::http::HeaderValue::from_static("application/json"),
        );
        match &self {
            Error::Unauthorized(_) => {
                response.headers_mut().insert(
                    axum::http::header::WWW_AUTHENTICATE,
                    axum::http::HeaderValue::from_static("Bearer"),
                );
            }
            Error::TooManyRequests { retry_after_s, .. } => {
                response
                    .headers_mut()
                    .insert(axum::http::header::RETRY_AFTER, (*retry_after_s).into());
            }
            _ => {}
        }
        response
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_client_never_sees_a_server_path() {
        let gone = || std::io::Error::from(std::io::ErrorKind::NotFound);
        let e = Error::io(
            "cannot read",
            Path::new("/srv/data/sessions/s01/trials/3.tum"),
            gone(),
        );
        assert!(
            e.to_string()
                .contains("/srv/data/sessions/s01/trials/3.tum")
        );
        let m = e.client_message();
        assert!(
            m.starts_with("cannot read session s01: trials/3.tum: "),
            "{m}"
        );
        assert!(!m.contains("/srv"), "{m}");
        let e = Error::io("cannot open", Path::new("/srv/data/sitar.db"), gone());
        assert!(e.client_message().starts_with("cannot open sitar.db: "));
        let e = Error::io("cannot create", Path::new("/srv/data/sessions/s02"), gone());
        assert!(
            e.client_message()
                .starts_with("cannot create session s02: ")
        );
    }

    #[test]
    fn quoted_input_is_cut_at_a_character_boundary() {
        assert_eq!(short("abc", 3), "abc");
        assert_eq!(short("abcd", 3), "abc…");
        assert_eq!(short("a\u{e9}b", 2), "a…");
    }
}
