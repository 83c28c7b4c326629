//! Disk quotas: bytes one session may keep (`session_disk_quota`, 413 beyond) and bytes all
//! of them may keep together (`disk_quota`, 507 beyond). Usage is what the store holds —
//! measured by walking the data directory (or listing the bucket: [`Measure`]), at most every
//! [`Measure::reuse_for`] — plus the bytes of uploads streaming now, counted as they are
//! written, so concurrent uploads cannot overrun it.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use crate::error::Error;

/// A walk of the data directory is reused this long (one walk stats every file).
const WALK_TTL: Duration = Duration::from_secs(5);

/// How the bytes a store holds are measured.
pub(crate) trait Measure: Send + Sync + std::fmt::Debug {
    /// Bytes the whole store holds.
    fn total(&self) -> u64;
    /// Bytes session `id` holds.
    fn session(&self, id: &str) -> u64;
    /// How long a measure of the whole store is reused.
    fn reuse_for(&self) -> Duration;
}

/// The data directory: its files, walked.
#[derive(Debug)]
struct Folder(PathBuf);

impl Measure for Folder {
    fn total(&self) -> u64 {
        disk_usage(&self.0)
    }

    fn session(&self, id: &str) -> u64 {
        disk_usage(&self.0.join("sessions").join(id))
    }

    fn reuse_for(&self) -> Duration {
        WALK_TTL
    }
}

/// The quotas and the bytes counted against them.
#[derive(Debug)]
pub(crate) struct DiskQuota {
    measure: Box<dyn Measure>,
    session_bytes: u64,
    global_bytes: u64,
    /// Bytes of uploads streaming now.
    in_flight: AtomicU64,
    /// Bytes uploads finished since the last walk (kept or not: counted until the next
    /// walk sees what is really there).
    since_walk: AtomicU64,
    walked: Mutex<Option<(Instant, u64)>>,
}

impl DiskQuota {
    /// The quotas of data directory `root`.
    pub fn new(root: &Path, session_bytes: u64, global_bytes: u64) -> DiskQuota {
        DiskQuota::measured(
            Box::new(Folder(root.to_path_buf())),
            session_bytes,
            global_bytes,
        )
    }

    /// The quotas of a store measured by `measure`.
    pub fn measured(measure: Box<dyn Measure>, session_bytes: u64, global_bytes: u64) -> DiskQuota {
        DiskQuota {
            measure,
            session_bytes,
            global_bytes,
            in_flight: AtomicU64::new(0),
            since_walk: AtomicU64::new(0),
            walked: Mutex::new(None),
        }
    }

    /// Bytes the data directory holds, uploads streaming now included.
    pub fn used(&self) -> u64 {
        let walked = {
            let mut walked = self.walked.lock().unwrap_or_else(|p| p.into_inner());
            match *walked {
                Some((at, bytes)) if at.elapsed() < self.measure.reuse_for() => bytes,
                _ => {
                    // Taken before the walk: an upload finishing during it is counted twice
                    // (for one interval), never missed.
                    let finished = self.since_walk.load(Ordering::SeqCst);
                    let bytes = self.measure.total();
                    self.since_walk.fetch_sub(finished, Ordering::SeqCst);
                    *walked = Some((Instant::now(), bytes));
                    bytes
                }
            }
        };
        walked
            .saturating_add(self.since_walk.load(Ordering::SeqCst))
            .saturating_add(self.in_flight.load(Ordering::SeqCst))
    }

    /// Room left for an upload into session `id` (`None`: an upload that makes a new
    /// session, only the global quota applies). Refuses at once when `declared` bytes would
    /// not fit.
    pub fn reserve(
        &self,
        id: Option<&str>,
        declared: Option<u64>,
    ) -> Result<Reservation<'_>, Error> {
        let session_room = match id {
            Some(id) if self.session_bytes != u64::MAX => {
                self.session_bytes.saturating_sub(self.measure.session(id))
            }
            _ => u64::MAX,
        };
        let reservation = Reservation {
            quota: self,
            session_room,
            written: 0,
        };
        if let Some(n) = declared {
            reservation.check(n)?;
        }
        Ok(reservation)
    }

    fn session_full(&self) -> Error {
        Error::QuotaExceeded(format!(
            "the session's files would pass its disk quota of {} bytes",
            self.session_bytes
        ))
    }

    fn disk_full(&self) -> Error {
        Error::InsufficientStorage(format!(
            "the server's disk quota of {} bytes is used up; retry once sessions are deleted",
            self.global_bytes
        ))
    }
}

/// One upload's bytes, counted against the quotas while it streams.
#[derive(Debug)]
pub(crate) struct Reservation<'q> {
    quota: &'q DiskQuota,
    session_room: u64,
    written: u64,
}

impl Reservation<'_> {
    /// Whether `more` bytes still fit, without counting them.
    fn check(&self, more: u64) -> Result<(), Error> {
        if self.written.saturating_add(more) > self.session_room {
            return Err(self.quota.session_full());
        }
        // An unlimited quota measures nothing (a bucket is listed to be measured).
        if self.quota.global_bytes != u64::MAX
            && self.quota.used().saturating_add(more) > self.quota.global_bytes
        {
            return Err(self.quota.disk_full());
        }
        Ok(())
    }

    /// Counts `n` more bytes about to be written; refused (and not counted) past a quota.
    pub fn add(&mut self, n: u64) -> Result<(), Error> {
        self.check(n)?;
        self.quota.in_flight.fetch_add(n, Ordering::SeqCst);
        self.written += n;
        Ok(())
    }

    /// The bytes counted were not kept (a refused upload, cut back or removed): they stop
    /// counting at once.
    pub fn discard(&mut self) {
        self.quota
            .in_flight
            .fetch_sub(self.written, Ordering::SeqCst);
        self.written = 0;
    }
}

impl Drop for Reservation<'_> {
    fn drop(&mut self) {
        self.quota
            .in_flight
            .fetch_sub(self.written, Ordering::SeqCst);
        self.quota
            .since_walk
            .fetch_add(self.written, Ordering::SeqCst);
    }
}

/// Bytes of the regular files under `dir` (0 when it does not exist; unreadable entries are
/// skipped). Symbolic links are not followed.
fn disk_usage(dir: &Path) -> u64 {
    let mut total = 0u64;
    let mut pending = vec![dir.to_path_buf()];
    while let Some(dir) = pending.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let Ok(kind) = entry.file_type() else {
                continue;
            };
            if kind.is_dir() {
                pending.push(entry.path());
            } else if kind.is_file() {
                total = total.saturating_add(entry.metadata().map_or(0, |m| m.len()));
            }
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_session_quota_is_413_and_the_global_one_507() {
        let dir = tempfile::tempdir().unwrap();
        let session = dir.path().join("sessions/s1");
        std::fs::create_dir_all(&session).unwrap();
        std::fs::write(session.join("recording"), [0u8; 600]).unwrap();
        std::fs::write(dir.path().join("sitar.db"), [0u8; 100]).unwrap();
        let quota = DiskQuota::new(dir.path(), 1000, 2000);
        assert_eq!(quota.used(), 700);

        // 400 left in the session: declared too much is refused before reading.
        let err = quota.reserve(Some("s1"), Some(401)).unwrap_err();
        assert_eq!(err.status_and_code().0.as_u16(), 413, "{err}");
        let mut upload = quota.reserve(Some("s1"), None).unwrap();
        upload.add(400).unwrap();
        assert_eq!(upload.add(1).unwrap_err().status_and_code().0.as_u16(), 413);

        // Another, concurrent upload sees the first one's bytes in flight.
        let mut other = quota.reserve(None, None).unwrap();
        assert_eq!(quota.used(), 1100);
        other.add(900).unwrap();
        let err = other.add(1).unwrap_err();
        assert_eq!(err.status_and_code().0.as_u16(), 507, "{err}");
        drop(upload);
        // Finished uploads stay counted until a walk sees what was kept...
        assert_eq!(quota.used(), 2000);
        // ...unless they were refused and removed.
        other.discard();
        drop(other);
        assert_eq!(quota.used(), 1100);
    }
}
