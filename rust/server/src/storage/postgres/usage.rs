//! The per-token usage ledger in Postgres (`session_creations`, `upload_usage`): counted in
//! the database, so every instance sees one count. A per-token advisory lock makes "count,
//! then record" one step across instances.

use super::PgStore;
use crate::error::Error;
use crate::model::{DAY_HOURS, HOUR_MS, UsageFull};
use crate::storage::metadata::UsageStore;

impl UsageStore for PgStore {
    fn count_session_creation(
        &self,
        token: i64,
        max: u32,
        now_ms: i64,
    ) -> Result<Result<(), UsageFull>, Error> {
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            tx.execute(
                "SELECT pg_advisory_xact_lock(hashtext('usage/' || $1::BIGINT::TEXT))",
                &[&token],
            )?;
            tx.execute(
                "DELETE FROM session_creations WHERE token_id = $1 AND created_ms <= $2",
                &[&token, &(now_ms - HOUR_MS)],
            )?;
            let row = tx.query_one(
                "SELECT COUNT(*), MIN(created_ms) FROM session_creations WHERE token_id = $1",
                &[&token],
            )?;
            let (used, oldest): (i64, Option<i64>) = (row.get(0), row.get(1));
            if used >= i64::from(max) {
                return Ok(Err(UsageFull {
                    used: used as u64,
                    frees_at_ms: oldest.unwrap_or(now_ms) + HOUR_MS,
                }));
            }
            tx.execute(
                "INSERT INTO session_creations (token_id, created_ms) VALUES ($1, $2)",
                &[&token, &now_ms],
            )?;
            tx.commit()?;
            Ok(Ok(()))
        })
    }

    fn uploaded_in_day(&self, token: i64, now_ms: i64) -> Result<UsageFull, Error> {
        let first_hour = now_ms.div_euclid(HOUR_MS) - DAY_HOURS + 1;
        self.pool.run(move |c| {
            // A float sum cannot overflow as a BIGINT one would; exact to 2^53 bytes.
            let row = c.query_one(
                "SELECT COALESCE(SUM(bytes::float8), 0), MIN(hour) FROM upload_usage \
                 WHERE token_id = $1 AND hour >= $2",
                &[&token, &first_hour],
            )?;
            let (bytes, oldest): (f64, Option<i64>) = (row.get(0), row.get(1));
            Ok(UsageFull {
                used: bytes as u64,
                frees_at_ms: (oldest.unwrap_or(first_hour) + DAY_HOURS) * HOUR_MS,
            })
        })
    }

    fn add_uploaded(&self, token: i64, bytes: u64, now_ms: i64) -> Result<(), Error> {
        let hour = now_ms.div_euclid(HOUR_MS);
        let bytes = i64::try_from(bytes).unwrap_or(i64::MAX);
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            tx.execute(
                "DELETE FROM upload_usage WHERE token_id = $1 AND hour <= $2",
                &[&token, &(hour - DAY_HOURS)],
            )?;
            // Saturating: a count never wraps.
            tx.execute(
                "INSERT INTO upload_usage (token_id, hour, bytes) VALUES ($1, $2, $3) \
                 ON CONFLICT (token_id, hour) DO UPDATE SET bytes = CASE \
                 WHEN upload_usage.bytes > 9223372036854775807 - EXCLUDED.bytes \
                 THEN 9223372036854775807 ELSE upload_usage.bytes + EXCLUDED.bytes END",
                &[&token, &hour, &bytes],
            )?;
            tx.commit()?;
            Ok(())
        })
    }
}
