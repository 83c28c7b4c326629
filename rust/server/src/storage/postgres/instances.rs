//! The `instances` table and the `sessions.played_by` / `stop_request` columns in Postgres.
//! A claim is one `UPDATE … WHERE` over the row: of two instances claiming one session at
//! once, the second waits for the first's row lock, re-checks the condition against the
//! row the first wrote, and finds a live player (Postgres' read-committed update rule).

use super::PgStore;
use crate::error::Error;
use crate::storage::instances::{IN_FLIGHT, InstanceStore, StopRequest, stronger_stop_request};

/// `played_by` names no instance alive since `alive` (a bound parameter such as `$3`).
fn player_dead(alive: &str) -> String {
    format!(
        "NOT EXISTS (SELECT 1 FROM instances i WHERE i.id = sessions.played_by \
         AND i.heartbeat_ms >= {alive})"
    )
}

impl InstanceStore for PgStore {
    fn heartbeat(&self, instance: &str, now_ms: i64) -> Result<(), Error> {
        let instance = instance.to_string();
        self.pool.run(move |c| {
            c.execute(
                "INSERT INTO instances (id, started_ms, heartbeat_ms) VALUES ($1, $2, $2) \
                 ON CONFLICT (id) DO UPDATE SET heartbeat_ms = \
                 GREATEST(instances.heartbeat_ms, EXCLUDED.heartbeat_ms)",
                &[&instance, &now_ms],
            )?;
            Ok(())
        })
    }

    fn claim_session(&self, id: &str, instance: &str, alive_since_ms: i64) -> Result<bool, Error> {
        let sql = format!(
            "UPDATE sessions SET progress_view = CASE WHEN played_by = $2 THEN progress_view \
             END, played_by = $2 WHERE id = $1 AND {IN_FLIGHT} \
             AND (played_by IS NULL OR played_by = $2 OR {})",
            player_dead("$3")
        );
        let (id, instance) = (id.to_string(), instance.to_string());
        self.pool
            .run(move |c| Ok(c.execute(&sql, &[&id, &instance, &alive_since_ms])? == 1))
    }

    fn release_session(&self, id: &str, instance: &str) -> Result<(), Error> {
        let (id, instance) = (id.to_string(), instance.to_string());
        self.pool.run(move |c| {
            c.execute(
                "UPDATE sessions SET played_by = NULL, stop_request = NULL, \
                 progress_view = NULL WHERE id = $1 AND played_by = $2",
                &[&id, &instance],
            )?;
            Ok(())
        })
    }

    fn session_player(&self, id: &str) -> Result<Option<String>, Error> {
        let id = id.to_string();
        self.pool.run(move |c| {
            Ok(
                c.query_opt("SELECT played_by FROM sessions WHERE id = $1", &[&id])?
                    .and_then(|row| row.get(0)),
            )
        })
    }

    fn is_alive(&self, instance: &str, alive_since_ms: i64) -> Result<bool, Error> {
        let instance = instance.to_string();
        self.pool.run(move |c| {
            Ok(c.query_one(
                "SELECT EXISTS (SELECT 1 FROM instances WHERE id = $1 AND heartbeat_ms >= $2)",
                &[&instance, &alive_since_ms],
            )?
            .get(0))
        })
    }

    fn unplayed_sessions(
        &self,
        alive_since_ms: i64,
    ) -> Result<Vec<(String, Option<String>)>, Error> {
        let sql = format!(
            "SELECT id, played_by FROM sessions WHERE {IN_FLIGHT} \
             AND (played_by IS NULL OR {}) ORDER BY seq",
            player_dead("$1")
        );
        self.pool.run(move |c| {
            Ok(c.query(&sql, &[&alive_since_ms])?
                .iter()
                .map(|r| (r.get(0), r.get(1)))
                .collect())
        })
    }

    fn request_stop(&self, id: &str, request: StopRequest) -> Result<(), Error> {
        let id = id.to_string();
        self.pool.run(move |c| {
            // The stronger request stays.
            c.execute(
                &format!(
                    "UPDATE sessions SET {} WHERE id = $1",
                    stronger_stop_request("$2::TEXT")
                ),
                &[&id, &request.as_str()],
            )?;
            Ok(())
        })
    }

    fn stop_requests(&self, instance: &str) -> Result<Vec<(String, StopRequest)>, Error> {
        let instance = instance.to_string();
        let rows: Vec<(String, String)> = self.pool.run(move |c| {
            Ok(c.query(
                &format!(
                    "SELECT id, stop_request FROM sessions WHERE played_by = $1 \
                     AND stop_request IS NOT NULL AND {IN_FLIGHT} ORDER BY seq"
                ),
                &[&instance],
            )?
            .iter()
            .map(|r| (r.get(0), r.get(1)))
            .collect())
        })?;
        Ok(rows
            .into_iter()
            .filter_map(|(id, request)| Some((id, StopRequest::from_stored(&request)?)))
            .collect())
    }

    fn publish_progress(&self, id: &str, instance: &str, view: Option<&str>) -> Result<(), Error> {
        let (id, instance) = (id.to_string(), instance.to_string());
        let view = view.map(str::to_string);
        self.pool.run(move |c| {
            c.execute(
                "UPDATE sessions SET progress_view = $3 WHERE id = $1 AND played_by = $2",
                &[&id, &instance, &view],
            )?;
            Ok(())
        })
    }

    fn published_progress(&self, id: &str) -> Result<Option<(String, String)>, Error> {
        let id = id.to_string();
        self.pool.run(move |c| {
            Ok(c.query_opt(
                "SELECT played_by, progress_view FROM sessions WHERE id = $1 \
                 AND played_by IS NOT NULL AND progress_view IS NOT NULL",
                &[&id],
            )?
            .map(|row| (row.get(0), row.get(1))))
        })
    }

    fn interrupt_jobs(&self, instance: Option<&str>, alive_since_ms: i64) -> Result<usize, Error> {
        let instance = instance.map(str::to_string);
        self.pool.run(move |c| {
            let n = c.execute(
                "UPDATE jobs SET state = 'interrupted', error = 'server stopped while the job ran', \
                 finished_ms = $3 WHERE state = 'running' AND (instance IS NULL OR instance = $1 \
                 OR NOT EXISTS (SELECT 1 FROM instances i WHERE i.id = jobs.instance \
                 AND i.heartbeat_ms >= $2))",
                &[&instance, &alive_since_ms, &crate::storage::now_ms()],
            )?;
            Ok(n as usize)
        })
    }
}
