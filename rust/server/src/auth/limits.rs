//! Limits per token, counted in memory (a restart starts them afresh): sessions created per
//! hour, bytes uploaded per day, uploads in progress at once. A request over a limit gets 429
//! with `Retry-After`, and the same request later goes through.

use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use axum::body::Body;
use axum::extract::{Request, State};
use axum::http::Method;
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use futures_util::StreamExt;

use crate::Error;
use crate::auth::caller::Caller;
use crate::shared::Shared;

/// The limits every token has (`sitar serve --max-sessions-per-hour`, `--max-upload-gib-per-day`,
/// `--max-concurrent-uploads`). The defaults are generous for one lab: a phone that records
/// and uploads a session a minute, with 2 GiB recordings, stays under them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Sessions a token may create in any hour (default 120; the legacy `POST /recording`
    /// creates one too).
    pub sessions_per_hour: u32,
    /// Bytes a token may upload in any 24 hours (recordings, trials, timestamps; default
    /// 200 GiB). An upload that starts under it is finished.
    pub upload_bytes_per_day: u64,
    /// Upload bodies a token may send at once (default 8: a lab's phones sharing one token).
    pub concurrent_uploads: u32,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            sessions_per_hour: 120,
            upload_bytes_per_day: 200 << 30,
            concurrent_uploads: 8,
        }
    }
}

const HOUR: Duration = Duration::from_secs(3600);
const DAY: Duration = Duration::from_secs(86_400);
/// Uploaded bytes are summed per minute: a token's ledger has at most 1440 entries.
const BUCKET: Duration = Duration::from_secs(60);

#[derive(Default)]
struct Usage {
    created: VecDeque<Instant>,
    /// (start of the minute, bytes), oldest first.
    uploaded: VecDeque<(Instant, u64)>,
    uploading: u32,
}

impl Usage {
    fn forget_before(&mut self, now: Instant) {
        while self.created.front().is_some_and(|t| now - *t >= HOUR) {
            self.created.pop_front();
        }
        while self.uploaded.front().is_some_and(|(t, _)| now - *t >= DAY) {
            self.uploaded.pop_front();
        }
    }
}

/// The counters of every token.
pub(crate) struct UploadLimiter {
    limits: Limits,
    usage: Mutex<HashMap<i64, Usage>>,
}

/// Whole seconds, at least 1, for `Retry-After`.
fn seconds(d: Duration) -> u64 {
    d.as_secs() + u64::from(d.subsec_nanos() > 0)
}

impl UploadLimiter {
    pub fn new(limits: Limits) -> UploadLimiter {
        UploadLimiter {
            limits,
            usage: Mutex::new(HashMap::new()),
        }
    }

    fn with<T>(&self, token: i64, f: impl FnOnce(&mut Usage, Instant) -> T) -> T {
        let mut usage = self.usage.lock().unwrap_or_else(|e| e.into_inner());
        let now = Instant::now();
        let entry = usage.entry(token).or_default();
        entry.forget_before(now);
        f(entry, now)
    }

    /// Counts a session creation, or refuses it with the seconds until one is allowed.
    fn create_session(&self, token: i64) -> Result<(), Error> {
        let max = self.limits.sessions_per_hour;
        self.with(token, |usage, now| {
            if usage.created.len() as u64 >= u64::from(max) {
                let oldest = usage.created.front().copied().unwrap_or(now);
                return Err(Error::TooManyRequests {
                    message: format!("this token created {max} sessions in the last hour"),
                    retry_after_s: seconds(HOUR.saturating_sub(now - oldest)).max(1),
                });
            }
            usage.created.push_back(now);
            Ok(())
        })
    }

    /// Starts an upload, or refuses it (too many at once, or the day's bytes are used up).
    fn start_upload(self: &Arc<Self>, token: i64) -> Result<UploadGuard, Error> {
        let limits = self.limits;
        self.with(token, |usage, now| {
            if usage.uploading >= limits.concurrent_uploads {
                return Err(Error::TooManyRequests {
                    message: format!(
                        "this token has {} uploads in progress already",
                        limits.concurrent_uploads
                    ),
                    retry_after_s: 5,
                });
            }
            let used: u64 = usage.uploaded.iter().map(|(_, b)| b).sum();
            if used >= limits.upload_bytes_per_day {
                let oldest = usage.uploaded.front().map_or(now, |(t, _)| *t);
                return Err(Error::TooManyRequests {
                    message: format!(
                        "this token uploaded {used} bytes in the last 24 hours (limit {})",
                        limits.upload_bytes_per_day
                    ),
                    retry_after_s: seconds(DAY.saturating_sub(now - oldest)).max(1),
                });
            }
            usage.uploading += 1;
            Ok(())
        })?;
        Ok(UploadGuard {
            limiter: self.clone(),
            token,
            bytes: 0,
        })
    }

    fn add_bytes(&self, token: i64, bytes: u64) {
        self.with(token, |usage, now| match usage.uploaded.back_mut() {
            Some((start, sum)) if now - *start < BUCKET => *sum += bytes,
            _ => usage.uploaded.push_back((now, bytes)),
        });
    }
}

/// Held while an upload body is read: its bytes are counted, and the slot is freed when the
/// body is done with (read to the end, or dropped).
struct UploadGuard {
    limiter: Arc<UploadLimiter>,
    token: i64,
    bytes: u64,
}

impl Drop for UploadGuard {
    fn drop(&mut self) {
        self.limiter.add_bytes(self.token, self.bytes);
        self.limiter.with(self.token, |usage, _| {
            usage.uploading = usage.uploading.saturating_sub(1)
        });
    }
}

fn creates_session(method: &Method, path: &str) -> bool {
    method == Method::POST && matches!(path, "/v1/sessions" | "/recording")
}

fn is_upload(method: &Method, path: &str) -> bool {
    let in_session = |suffix: &str| {
        path.strip_prefix("/v1/sessions/")
            .and_then(|rest| rest.strip_suffix(suffix))
            .is_some_and(|id| !id.is_empty() && !id.contains('/'))
    };
    // Every PUT under a session is an upload: the recording and the evidence files.
    (method == Method::PUT && path.starts_with("/v1/sessions/"))
        || (method == Method::POST
            && (in_session("/trials") || matches!(path, "/recording" | "/timestamps")))
}

/// The middleware: runs after authentication, on the caller's token.
pub(crate) async fn limit_uploads(
    State(shared): State<Arc<Shared>>,
    request: Request,
    next: Next,
) -> Response {
    let Some(Caller::Token { id, .. }) = request.extensions().get::<Caller>().cloned() else {
        return next.run(request).await;
    };
    let (method, path) = (request.method().clone(), request.uri().path().to_owned());
    if creates_session(&method, &path)
        && let Err(e) = shared.limiter.create_session(id)
    {
        return e.into_response();
    }
    if !is_upload(&method, &path) {
        return next.run(request).await;
    }
    let mut guard = match shared.limiter.start_upload(id) {
        Ok(guard) => guard,
        Err(e) => return e.into_response(),
    };
    let (parts, body) = request.into_parts();
    let counted = body.into_data_stream().map(move |chunk| {
        // The whole guard moves into the stream (not just its counter): the slot is held
        // until the body is done with.
        let guard = &mut guard;
        if let Ok(bytes) = &chunk {
            guard.bytes += bytes.len() as u64;
        }
        chunk
    });
    next.run(Request::from_parts(parts, Body::from_stream(counted)))
        .await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_limit_refuses_with_a_retry_after_and_frees_up() {
        let limiter = Arc::new(UploadLimiter::new(Limits {
            sessions_per_hour: 2,
            upload_bytes_per_day: 100,
            concurrent_uploads: 1,
        }));
        limiter.create_session(1).unwrap();
        limiter.create_session(1).unwrap();
        let Err(Error::TooManyRequests { retry_after_s, .. }) = limiter.create_session(1) else {
            panic!("the third session in an hour is refused");
        };
        assert!((3599..=3600).contains(&retry_after_s), "{retry_after_s}");
        // Another token has its own counters.
        limiter.create_session(2).unwrap();

        let mut first = limiter.start_upload(1).unwrap();
        assert!(matches!(
            limiter.start_upload(1),
            Err(Error::TooManyRequests {
                retry_after_s: 5,
                ..
            })
        ));
        first.bytes = 150;
        drop(first);
        // The slot is free again, but the day's bytes are used up.
        let Err(Error::TooManyRequests {
            retry_after_s,
            message,
        }) = limiter.start_upload(1)
        else {
            panic!("over the day's bytes");
        };
        assert!(message.contains("150 bytes"), "{message}");
        assert!(retry_after_s > 86_000, "{retry_after_s}");
        assert!(limiter.start_upload(2).is_ok());
    }

    #[test]
    fn upload_routes_are_recognised() {
        assert!(is_upload(&Method::PUT, "/v1/sessions/s01/recording"));
        assert!(is_upload(&Method::PUT, "/v1/sessions/s01/evidence.csv"));
        assert!(is_upload(
            &Method::PUT,
            "/v1/sessions/s01/subtrajectories/3/image.jpg"
        ));
        assert!(!is_upload(&Method::GET, "/v1/sessions/s01/subtrajectories"));
        assert!(is_upload(&Method::POST, "/v1/sessions/s01/trials"));
        assert!(is_upload(&Method::POST, "/recording"));
        assert!(is_upload(&Method::POST, "/timestamps"));
        assert!(!is_upload(&Method::HEAD, "/v1/sessions/s01/recording"));
        assert!(!is_upload(&Method::POST, "/v1/sessions"));
        assert!(creates_session(&Method::POST, "/v1/sessions"));
        assert!(!creates_session(&Method::GET, "/v1/sessions"));
    }
}
