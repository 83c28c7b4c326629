//! Limits per token: sessions created per hour, bytes uploaded per day, uploads in progress
//! at once. The first two are counted in SQLite (`usage.rs`), so a restart does not reset
//! them; uploads in progress are counted in memory (none survive a restart). A request over
//! a limit gets 429 with `Retry-After`, and the same request later goes through.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use crate::error::Error;
use crate::model::UsageFull;
use crate::storage::{MetadataStore, UsageStore, now_ms};

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
    pub fn create_session(
        &self,
        db: &dyn UsageStore,
        token: i64,
        now_ms: i64,
    ) -> Result<(), Error> {
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
    pub fn start_upload(
        self: &Arc<Self>,
        db: Arc<dyn MetadataStore>,
        token: i64,
        now_ms: i64,
    ) -> Result<UploadGuard, Error> {
        let limits = self.limits;
        let day = db.uploaded_in_day(token, now_ms)?;
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
            limiter: self.clone(),
            db,
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
pub(crate) struct UploadGuard {
    limiter: Arc<UploadLimiter>,
    db: Arc<dyn MetadataStore>,
    token: i64,
    /// Bytes read so far.
    pub bytes: u64,
}

impl Drop for UploadGuard {
    fn drop(&mut self) {
        self.limiter
            .finish_upload(&*self.db, self.token, self.bytes);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::model::HOUR_MS;

    fn usage_store(dir: &std::path::Path) -> Arc<dyn MetadataStore> {
        crate::storage::open::open_metadata(dir, None).unwrap()
    }

    #[test]
    fn each_limit_refuses_with_a_retry_after_and_frees_up() {
        let dir = tempfile::tempdir().unwrap();
        let limits = Limits {
            sessions_per_hour: 2,
            upload_bytes_per_day: 100,
            concurrent_uploads: 1,
        };
        let store = usage_store(dir.path());
        let (limiter, db) = (&Arc::new(UploadLimiter::new(limits)), &*store);
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

        let mut first = limiter.start_upload(store.clone(), 1, t0).unwrap();
        assert!(matches!(
            limiter.start_upload(store.clone(), 1, t0),
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
        }) = limiter.start_upload(store.clone(), 1, now)
        else {
            panic!("over the day's bytes");
        };
        assert!(message.contains("150 bytes"), "{message}");
        assert!(
            (82_800..=86_400).contains(&retry_after_s),
            "{retry_after_s}"
        );
        assert!(limiter.start_upload(store.clone(), 2, now).is_ok());
        // A day later the bytes have left the window.
        assert!(
            limiter
                .start_upload(store.clone(), 1, now + 24 * HOUR_MS)
                .is_ok()
        );
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
            let (store, limiter) = (
                usage_store(dir.path()),
                Arc::new(UploadLimiter::new(limits)),
            );
            limiter.create_session(&*store, 7, t0).unwrap();
            let mut upload = limiter.start_upload(store.clone(), 7, t0).unwrap();
            upload.bytes = 11;
        }
        // A new server on the same data directory: both limits still apply.
        let (store, limiter) = (
            usage_store(dir.path()),
            Arc::new(UploadLimiter::new(limits)),
        );
        assert!(limiter.create_session(&*store, 7, t0 + 1).is_err());
        assert!(limiter.start_upload(store.clone(), 7, t0 + 1).is_err());
        assert!(limiter.create_session(&*store, 8, t0 + 1).is_ok());
    }
}
