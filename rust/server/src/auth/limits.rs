//! Limits per token: sessions created per hour, bytes uploaded per day, uploads in progress
//! at once. The first two are counted in SQLite (`usage.rs`), so a restart does not reset
//! them; uploads in progress are counted in memory (none survive a restart). A request over
//! a limit gets 429 with `Retry-After`, and the same request later goes through.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use axum::body::Body;
use axum::extract::{Request, State};
use axum::http::Method;
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use futures_util::StreamExt;

use crate::Error;
use crate::app_state::App;
use crate::model::Caller;
use crate::model::UsageFull;
use crate::storage::{UsageStore, now_ms};

/// The limits every token has (`sitar serve --max-sessions-per-hour`, `--max-upload-gib-per-day`,
/// `--max-concurrent-uploads`). The defaults are generous for one lab: a phone that records
/// and uploads a session a minute, with 2 GiB recordings, stays under them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Sessions a token may create in any hour (default 120; the legacy `POST /recording`
    /// creates one too). Kept in the database: a restart does not reset it.
    pub sessions_per_hour: u32,
    /// Bytes a token may upload in the last 24 hours, counted per whole hour (recordings,
    /// trials, timestamps; default 200 GiB). An upload that starts under it is finished; its
    /// bytes count when its body ends. Kept in the database: a restart does not reset it.
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

/// Whole seconds from `now_ms` until `at_ms`, at least 1, for `Retry-After`.
fn seconds_until(at_ms: i64, now_ms: i64) -> u64 {
    let ms = (at_ms - now_ms).max(1) as u64;
    ms.div_ceil(1000)
}

/// The counters of every token.
pub(crate) struct UploadLimiter {
    limits: Limits,
    /// Upload bodies being read, per token.
    uploading: Mutex<HashMap<i64, u32>>,
}

impl UploadLimiter {
    pub fn new(limits: Limits) -> UploadLimiter {
        UploadLimiter {
            limits,
            uploading: Mutex::new(HashMap::new()),
        }
    }

    /// Counts a session creation at `now_ms`, or refuses it with the seconds until one is
    /// allowed.
    fn create_session(&self, db: &dyn UsageStore, token: i64, now_ms: i64) -> Result<(), Error> {
        let max = self.limits.sessions_per_hour;
        match db.count_session_creation(token, max, now_ms)? {
            Ok(()) => Ok(()),
            Err(UsageFull { frees_at_ms, .. }) => Err(Error::TooManyRequests {
                message: format!("this token created {max} sessions in the last hour"),
                retry_after_s: seconds_until(frees_at_ms, now_ms),
            }),
        }
    }

    /// Starts an upload at `now_ms`, or refuses it (too many at once, or the day's bytes are
    /// used up).
    fn start_upload(
        &self,
        shared: &Arc<App>,
        token: i64,
        now_ms: i64,
    ) -> Result<UploadGuard, Error> {
        let limits = self.limits;
        let day = shared.db.uploaded_in_day(token, now_ms)?;
        if day.used >= limits.upload_bytes_per_day {
            return Err(Error::TooManyRequests {
                message: format!(
                    "this token uploaded {} bytes in the last 24 hours (limit {})",
                    day.used, limits.upload_bytes_per_day
                ),
                retry_after_s: seconds_until(day.frees_at_ms, now_ms),
            });
        }
        let mut uploading = self.uploading.lock().unwrap_or_else(|e| e.into_inner());
        let count = uploading.entry(token).or_default();
        if *count >= limits.concurrent_uploads {
            return Err(Error::TooManyRequests {
                message: format!(
                    "this token has {} uploads in progress already",
                    limits.concurrent_uploads
                ),
                retry_after_s: 5,
            });
        }
        *count += 1;
        Ok(UploadGuard {
            shared: shared.clone(),
            token,
            bytes: 0,
        })
    }

    /// An upload's body is done with: its bytes go into the ledger, its slot is free.
    fn finish_upload(&self, db: &dyn UsageStore, token: i64, bytes: u64) {
        if bytes > 0
            && let Err(e) = db.add_uploaded(token, bytes, now_ms())
        {
            log::warn!("cannot count {bytes} uploaded bytes: {e}");
        }
        let mut uploading = self.uploading.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(count) = uploading.get_mut(&token) {
            *count = count.saturating_sub(1);
            if *count == 0 {
                uploading.remove(&token);
            }
        }
    }
}

/// Held while an upload body is read: its bytes are counted, and the slot is freed when the
/// body is done with (read to the end, or dropped).
struct UploadGuard {
    shared: Arc<App>,
    token: i64,
    bytes: u64,
}

impl Drop for UploadGuard {
    fn drop(&mut self) {
        self.shared
            .limiter
            .finish_upload(&*self.shared.db, self.token, self.bytes);
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
    State(shared): State<Arc<App>>,
    request: Request,
    next: Next,
) -> Response {
    let Some(Caller::Token { id, .. }) = request.extensions().get::<Caller>().cloned() else {
        return next.run(request).await;
    };
    let (method, path) = (request.method().clone(), request.uri().path().to_owned());
    if creates_session(&method, &path)
        && let Err(e) = shared.limiter.create_session(&*shared.db, id, now_ms())
    {
        return e.into_response();
    }
    if !is_upload(&method, &path) {
        return next.run(request).await;
    }
    let mut guard = match shared.limiter.start_upload(&shared, id, now_ms()) {
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

    use crate::config::ServerConfig;
    use crate::model::HOUR_MS;

    fn shared(dir: &std::path::Path, limits: Limits) -> Arc<App> {
        let mut config = ServerConfig::new(dir);
        config.limits = limits;
        Arc::new(App::open(config).unwrap())
    }

    #[test]
    fn each_limit_refuses_with_a_retry_after_and_frees_up() {
        let dir = tempfile::tempdir().unwrap();
        let limits = Limits {
            sessions_per_hour: 2,
            upload_bytes_per_day: 100,
            concurrent_uploads: 1,
        };
        let shared = shared(dir.path(), limits);
        let (limiter, db) = (&shared.limiter, &*shared.db);
        let t0 = 500_000 * HOUR_MS + 1_000;
        limiter.create_session(db, 1, t0).unwrap();
        limiter.create_session(db, 1, t0 + 1).unwrap();
        let Err(Error::TooManyRequests { retry_after_s, .. }) =
            limiter.create_session(db, 1, t0 + 2)
        else {
            panic!("the third session in an hour is refused");
        };
        assert_eq!(retry_after_s, 3600);
        // Another token has its own counters; an hour later the first may create again.
        limiter.create_session(db, 2, t0 + 2).unwrap();
        limiter.create_session(db, 1, t0 + HOUR_MS).unwrap();

        let mut first = limiter.start_upload(&shared, 1, t0).unwrap();
        assert!(matches!(
            limiter.start_upload(&shared, 1, t0),
            Err(Error::TooManyRequests {
                retry_after_s: 5,
                ..
            })
        ));
        first.bytes = 150;
        drop(first);
        // The slot is free again, but the day's bytes are used up (counted in the hour of
        // the clock, so asked at the real time).
        let now = now_ms();
        let Err(Error::TooManyRequests {
            retry_after_s,
            message,
        }) = limiter.start_upload(&shared, 1, now)
        else {
            panic!("over the day's bytes");
        };
        assert!(message.contains("150 bytes"), "{message}");
        assert!(
            (82_800..=86_400).contains(&retry_after_s),
            "{retry_after_s}"
        );
        assert!(limiter.start_upload(&shared, 2, now).is_ok());
        // A day later the bytes have left the window.
        assert!(limiter.start_upload(&shared, 1, now + 24 * HOUR_MS).is_ok());
    }

    #[test]
    fn the_counts_outlive_the_limiter() {
        let dir = tempfile::tempdir().unwrap();
        let limits = Limits {
            sessions_per_hour: 1,
            upload_bytes_per_day: 10,
            concurrent_uploads: 4,
        };
        let t0 = now_ms();
        {
            let shared = shared(dir.path(), limits);
            shared.limiter.create_session(&*shared.db, 7, t0).unwrap();
            let mut upload = shared.limiter.start_upload(&shared, 7, t0).unwrap();
            upload.bytes = 11;
        }
        // A new server on the same data directory: both limits still apply.
        let shared = shared(dir.path(), limits);
        assert!(
            shared
                .limiter
                .create_session(&*shared.db, 7, t0 + 1)
                .is_err()
        );
        assert!(shared.limiter.start_upload(&shared, 7, t0 + 1).is_err());
        assert!(
            shared
                .limiter
                .create_session(&*shared.db, 8, t0 + 1)
                .is_ok()
        );
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
