//! The `jobs` and `devices` tables in Postgres.

use super::PgStore;
use crate::error::Error;
use crate::storage::metadata::{DeviceRow, DeviceStore, JobEnd, JobStore};
use crate::storage::now_ms;

impl JobStore for PgStore {
    fn start_job(&self, session: &str, kind: &str, instance: &str) -> Result<i64, Error> {
        let (id, kind, instance) = (session.to_string(), kind.to_string(), instance.to_string());
        self.pool.run(move |c| {
            Ok(c.query_one(
                "INSERT INTO jobs (session_id, kind, state, started_ms, instance) \
                 VALUES ($1, $2, 'running', $3, $4) RETURNING id",
                &[&id, &kind, &now_ms(), &instance],
            )?
            .get(0))
        })
    }

    fn finish_job(&self, job: i64, end: JobEnd, error: Option<&str>) -> Result<(), Error> {
        let error = error.map(str::to_string);
        self.pool.run(move |c| {
            c.execute(
                "UPDATE jobs SET state = $2, error = $3, finished_ms = $4 WHERE id = $1",
                &[&job, &end.as_str(), &error, &now_ms()],
            )?;
            Ok(())
        })
    }

    fn jobs_of(&self, session: &str) -> Result<Vec<(String, String)>, Error> {
        let id = session.to_string();
        self.pool.run(move |c| {
            Ok(c.query(
                "SELECT kind, state FROM jobs WHERE session_id = $1 ORDER BY id",
                &[&id],
            )?
            .iter()
            .map(|r| (r.get(0), r.get(1)))
            .collect())
        })
    }
}

impl DeviceStore for PgStore {
    fn upsert_device(&self, serial: &str, state: &str, session: Option<&str>) -> Result<(), Error> {
        let (serial, state, session) = (
            serial.to_string(),
            state.to_string(),
            session.map(str::to_string),
        );
        self.pool.run(move |c| {
            c.execute(
                "INSERT INTO devices (serial, state, session_id, last_seen_ms) VALUES ($1, $2, $3, $4) \
                 ON CONFLICT (serial) DO UPDATE SET state = $2, session_id = $3, last_seen_ms = $4",
                &[&serial, &state, &session, &now_ms()],
            )?;
            Ok(())
        })
    }

    fn devices(&self) -> Result<Vec<DeviceRow>, Error> {
        self.pool.run(|c| {
            Ok(c.query(
                "SELECT serial, state, session_id, last_seen_ms FROM devices ORDER BY serial",
                &[],
            )?
            .iter()
            .map(|r| (r.get(0), r.get(1), r.get(2), r.get(3)))
            .collect())
        })
    }
}
