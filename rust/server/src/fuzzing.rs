//! The HTTP-facing parsers, reachable from the fuzz targets in `fuzz/` (a separate
//! workspace, so it can only call public items). Not an API: hidden from the docs, and it
//! may change with the handlers. Each function runs the same code a request runs, minus the
//! database and the network.

use axum::http::{HeaderMap, HeaderValue};

use crate::config::ServerConfig;
use crate::error::Error;
use crate::error::short;
use crate::http::handlers::sessions::QUOTE_LIMIT;
use crate::model::{PlaybackKind, estimate_settings::EstimateSettings};

pub use crate::auth::secret::{
    COOKIE_NAME, bearer, cookie, has_param, plausible, query_param, without_param,
};

/// `Content-Range: bytes START-LAST/TOTAL` of a `PUT …/recording`, as `(start, last, total)`.
pub fn content_range(text: &str) -> Option<(u64, u64, u64)> {
    crate::http::handlers::recording::parse_content_range(text).map(|r| (r.start, r.last, r.total))
}

/// The `Idempotency-Key` check of `POST /v1/sessions` on a raw header value; `Ok(None)` is
/// also the answer for bytes no HTTP header could carry (they never reach a handler).
pub fn idempotency_key(value: &[u8]) -> Result<Option<String>, Error> {
    let Ok(value) = HeaderValue::from_bytes(value) else {
        return Ok(None);
    };
    let mut headers = HeaderMap::new();
    headers.insert(crate::http::helpers::IDEMPOTENCY_HEADER, value);
    crate::http::helpers::idempotency_key(&headers)
}

/// What `POST /v1/sessions` makes of its JSON body before it touches the database: the typed
/// request (unknown keys refused), the error text quoting short prefixes only, the playback
/// kind and the estimate settings (checked against a default server configuration).
pub fn session_request(body: &[u8]) -> Result<(PlaybackKind, u32, &'static str), Error> {
    // The handler's own parser: one JSON object, unknown keys refused, nothing after it.
    crate::http::handlers::sessions::parse_create_request(body)?;
    let value: serde_json::Value = serde_json::from_slice(body)
        .map_err(|_| Error::Internal("typed but not one JSON value".into()))?;
    let text = |key: &str| value.get(key).and_then(|v| v.as_str());
    let window_frames = value
        .get("window_frames")
        .and_then(|v| v.as_u64())
        .map(|n| n as u32);
    let config = ServerConfig::new("unused");
    let playback = match text("playback") {
        None => config.playback,
        Some(name) => name
            .parse::<PlaybackKind>()
            .map_err(|e| Error::BadRequest(format!("playback: {}", short(&e, QUOTE_LIMIT))))?,
    };
    let settings = EstimateSettings::from_request(
        &config.default_setting,
        text("setting"),
        window_frames,
        text("pose_relation"),
    )?;
    Ok((playback, settings.window_frames, settings.unit()))
}

/// A trial's TUM text as `POST /v1/sessions/{id}/trials` and the playback phones' uploads
/// read it; the number of poses.
pub fn trial(bytes: &[u8]) -> Result<usize, Error> {
    crate::ingest::trials::parse_trial(bytes, "trial.txt").map(|t| t.len())
}
