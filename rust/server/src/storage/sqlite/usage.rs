//! The per-token usage ledger: every session a token created in the last hour
//! (`session_creations`) and the bytes it uploaded per hour (`upload_usage`). Rows older than
//! the window are deleted whenever a token's rows are written, so each token keeps at most
//! `sessions_per_hour` creations and 25 hourly byte counts.

use rusqlite::{OptionalExtension, params};

use super::{CachedSql, SqliteStore};
use crate::error::Error;
use crate::model::{DAY_HOURS, HOUR_MS, UsageFull};
use crate::storage::metadata::UsageStore;

impl UsageStore for SqliteStore {
    /// Records a session creation by `token` at `now_ms` if it made fewer than `max` in the
    /// hour before; else the refusal.
    fn count_session_creation(
        &self,
        token: i64,
        max: u32,
        now_ms: i64,
    ) -> Result<Result<(), UsageFull>, Error> {
        self.transaction(|tx| {
            tx.execute_cached(
                "DELETE FROM session_creations WHERE token_id = ?1 AND created_ms <= ?2",
                params![token, now_ms - HOUR_MS],
            )?;
            let (used, oldest): (i64, Option<i64>) = tx.query_row_cached(
                "SELECT COUNT(*), MIN(created_ms) FROM session_creations WHERE token_id = ?1",
                [token],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )?;
            if used >= i64::from(max) {
                return Ok(Err(UsageFull {
                    used: used as u64,
                    frees_at_ms: oldest.unwrap_or(now_ms) + HOUR_MS,
                }));
            }
            tx.execute_cached(
                "INSERT INTO session_creations (token_id, created_ms) VALUES (?1, ?2)",
                params![token, now_ms],
            )?;
            Ok(Ok(()))
        })
    }

    /// Bytes `token` uploaded in the last [`DAY_HOURS`] hourly buckets, and when the oldest
    /// of them leaves the window (`None` when there are none).
    fn uploaded_in_day(&self, token: i64, now_ms: i64) -> Result<UsageFull, Error> {
        let first_hour = now_ms.div_euclid(HOUR_MS) - DAY_HOURS + 1;
        self.with(|c| {
            // TOTAL (a float) cannot overflow as SUM would; exact to 2^53 bytes.
            let (bytes, oldest): (f64, Option<i64>) = c.query_row_cached(
                "SELECT TOTAL(bytes), MIN(hour) FROM upload_usage WHERE token_id = ?1 AND hour >= ?2",
                params![token, first_hour],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )?;
            Ok(UsageFull {
                used: bytes as u64,
                frees_at_ms: (oldest.unwrap_or(first_hour) + DAY_HOURS) * HOUR_MS,
            })
        })
    }

    /// Adds `bytes` to `token`'s count of the hour of `now_ms`, and forgets the hours that
    /// left the window.
    fn add_uploaded(&self, token: i64, bytes: u64, now_ms: i64) -> Result<(), Error> {
        let hour = now_ms.div_euclid(HOUR_MS);
        let bytes = i64::try_from(bytes).unwrap_or(i64::MAX);
        self.transaction(|tx| {
            tx.execute_cached(
                "DELETE FROM upload_usage WHERE token_id = ?1 AND hour <= ?2",
                params![token, hour - DAY_HOURS],
            )?;
            let before: Option<i64> = tx
                .query_row_cached(
                    "SELECT bytes FROM upload_usage WHERE token_id = ?1 AND hour = ?2",
                    params![token, hour],
                    |r| r.get(0),
                )
                .optional()?;
            tx.execute_cached(
                "INSERT INTO upload_usage (token_id, hour, bytes) VALUES (?1, ?2, ?3) \
                 ON CONFLICT(token_id, hour) DO UPDATE SET bytes = ?3",
                params![token, hour, before.unwrap_or(0).saturating_add(bytes)],
            )?;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn db() -> (tempfile::TempDir, SqliteStore) {
        let dir = tempfile::tempdir().unwrap();
        let db = SqliteStore::open(&dir.path().join("sitar.db")).unwrap();
        (dir, db)
    }

    #[test]
    fn creations_are_counted_per_token_over_the_last_hour() {
        let (_dir, db) = db();
        let t0 = 1_000 * HOUR_MS + 5;
        assert_eq!(db.count_session_creation(1, 2, t0).unwrap(), Ok(()));
        assert_eq!(db.count_session_creation(1, 2, t0 + 10).unwrap(), Ok(()));
        assert_eq!(
            db.count_session_creation(1, 2, t0 + 20).unwrap(),
            Err(UsageFull {
                used: 2,
                frees_at_ms: t0 + HOUR_MS
            })
        );
        // Another token has its own count; an hour after the first, one frees up.
        assert_eq!(db.count_session_creation(2, 2, t0 + 20).unwrap(), Ok(()));
        assert_eq!(
            db.count_session_creation(1, 2, t0 + HOUR_MS).unwrap(),
            Ok(())
        );
        assert!(
            db.count_session_creation(1, 2, t0 + HOUR_MS + 1)
                .unwrap()
                .is_err()
        );
        // Old rows are gone: only the window's are kept.
        let rows: i64 = db
            .with(|c| {
                c.query_row(
                    "SELECT COUNT(*) FROM session_creations WHERE token_id = 1",
                    [],
                    |r| r.get(0),
                )
            })
            .unwrap();
        assert_eq!(rows, 2);
    }

    #[test]
    fn bytes_are_summed_over_the_last_24_hourly_buckets() {
        let (_dir, db) = db();
        let t0 = 1_000 * HOUR_MS + 7;
        db.add_uploaded(1, 100, t0).unwrap();
        db.add_uploaded(1, 50, t0 + 1).unwrap();
        db.add_uploaded(1, 25, t0 + 3 * HOUR_MS).unwrap();
        db.add_uploaded(2, 1_000, t0).unwrap();
        let day = db.uploaded_in_day(1, t0 + 3 * HOUR_MS).unwrap();
        assert_eq!(day.used, 175);
        assert_eq!(day.frees_at_ms, 1_024 * HOUR_MS);
        // 24 hours on, the first hour's 150 bytes have left the window.
        let later = db.uploaded_in_day(1, 1_024 * HOUR_MS).unwrap();
        assert_eq!(later.used, 25);
        assert_eq!(db.uploaded_in_day(3, t0).unwrap().used, 0);
        // Huge counts saturate instead of wrapping, in one hour and over several.
        db.add_uploaded(4, u64::MAX, t0).unwrap();
        db.add_uploaded(4, u64::MAX, t0).unwrap();
        db.add_uploaded(4, u64::MAX, t0 + HOUR_MS).unwrap();
        assert!(db.uploaded_in_day(4, t0 + HOUR_MS).unwrap().used >= i64::MAX as u64);
    }
}
