//! The `jobs` and `devices` tables: the work run on sessions and the phones that ran it.

use rusqlite::params;

use super::{CachedSql, SqliteStore};
use crate::error::Error;
use crate::storage::metadata::{DeviceRow, DeviceStore, JobEnd, JobStore};
use crate::storage::now_ms;

impl JobStore for SqliteStore {
    fn start_job(&self, session: &str, kind: &str, instance: &str) -> Result<i64, Error> {
        self.with(|c| {
            c.execute_cached(
                "INSERT INTO jobs (session_id, kind, state, started_ms, instance) \
                 VALUES (?1, ?2, 'running', ?3, ?4)",
                params![session, kind, now_ms(), instance],
            )?;
            Ok(c.last_insert_rowid())
        })
    }

    fn finish_job(&self, job: i64, end: JobEnd, error: Option<&str>) -> Result<(), Error> {
        self.with(|c| {
            c.execute_cached(
                "UPDATE jobs SET state = ?2, error = ?3, finished_ms = ?4 WHERE id = ?1",
                params![job, end.as_str(), error, now_ms()],
            )
        })
        .map(|_| ())
    }

    fn jobs_of(&self, session: &str) -> Result<Vec<(String, String)>, Error> {
        self.with(|c| {
            let mut stmt =
                c.prepare_cached("SELECT kind, state FROM jobs WHERE session_id = ?1 ORDER BY id")?;
            let rows = stmt.query_map([session], |r| Ok((r.get(0)?, r.get(1)?)))?;
            rows.collect()
        })
    }
}

impl DeviceStore for SqliteStore {
    fn upsert_device(&self, serial: &str, state: &str, session: Option<&str>) -> Result<(), Error> {
        self.with(|c| {
            c.execute_cached(
                "INSERT INTO devices (serial, state, session_id, last_seen_ms) VALUES (?1, ?2, ?3, ?4) \
                 ON CONFLICT(serial) DO UPDATE SET state = ?2, session_id = ?3, last_seen_ms = ?4",
                params![serial, state, session, now_ms()],
            )
        })
        .map(|_| ())
    }

    fn devices(&self) -> Result<Vec<DeviceRow>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT serial, state, session_id, last_seen_ms FROM devices ORDER BY serial",
            )?;
            let rows = stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?)))?;
            rows.collect()
        })
    }
}
