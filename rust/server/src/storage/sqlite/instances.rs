//! The `instances` table and the `sessions.played_by` / `stop_request` columns in SQLite
//! (one connection: every update here is atomic with any other).

use rusqlite::{OptionalExtension, params};

use super::{CachedSql, SqliteStore};
use crate::error::Error;
use crate::storage::instances::{IN_FLIGHT, InstanceStore, StopRequest, stronger_stop_request};

/// `played_by` names no instance alive since `?ALIVE` (a parameter the statement binds).
fn player_dead(alive: &str) -> String {
    format!(
        "NOT EXISTS (SELECT 1 FROM instances i WHERE i.id = sessions.played_by \
         AND i.heartbeat_ms >= {alive})"
    )
}

impl InstanceStore for SqliteStore {
    fn heartbeat(&self, instance: &str, now_ms: i64) -> Result<(), Error> {
        self.with(|c| {
            c.execute_cached(
                "INSERT INTO instances (id, started_ms, heartbeat_ms) VALUES (?1, ?2, ?2) \
                 ON CONFLICT (id) DO UPDATE SET heartbeat_ms = MAX(heartbeat_ms, ?2)",
                params![instance, now_ms],
            )
        })
        .map(drop)
    }

    fn claim_session(&self, id: &str, instance: &str, alive_since_ms: i64) -> Result<bool, Error> {
        let sql = format!(
            "UPDATE sessions SET progress_view = CASE WHEN played_by = ?2 THEN progress_view \
             END, played_by = ?2 WHERE id = ?1 AND {IN_FLIGHT} \
             AND (played_by IS NULL OR played_by = ?2 OR {})",
            player_dead("?3")
        );
        self.with(|c| c.execute_cached(&sql, params![id, instance, alive_since_ms]))
            .map(|n| n == 1)
    }

    fn release_session(&self, id: &str, instance: &str) -> Result<(), Error> {
        self.with(|c| {
            c.execute_cached(
                "UPDATE sessions SET played_by = NULL, stop_request = NULL, \
                 progress_view = NULL WHERE id = ?1 AND played_by = ?2",
                params![id, instance],
            )
        })
        .map(drop)
    }

    fn session_player(&self, id: &str) -> Result<Option<String>, Error> {
        self.with(|c| {
            c.query_row_cached("SELECT played_by FROM sessions WHERE id = ?1", [id], |r| {
                r.get(0)
            })
            .optional()
        })
        .map(Option::flatten)
    }

    fn is_alive(&self, instance: &str, alive_since_ms: i64) -> Result<bool, Error> {
        self.with(|c| {
            c.query_row_cached(
                "SELECT EXISTS (SELECT 1 FROM instances WHERE id = ?1 AND heartbeat_ms >= ?2)",
                params![instance, alive_since_ms],
                |r| r.get(0),
            )
        })
    }

    fn unplayed_sessions(
        &self,
        alive_since_ms: i64,
    ) -> Result<Vec<(String, Option<String>)>, Error> {
        let sql = format!(
            "SELECT id, played_by FROM sessions WHERE {IN_FLIGHT} \
             AND (played_by IS NULL OR {}) ORDER BY created_ms, rowid",
            player_dead("?1")
        );
        self.with(|c| {
            let mut stmt = c.prepare_cached(&sql)?;
            let rows = stmt.query_map([alive_since_ms], |r| Ok((r.get(0)?, r.get(1)?)))?;
            rows.collect()
        })
    }

    fn request_stop(&self, id: &str, request: StopRequest) -> Result<(), Error> {
        // The stronger request stays.
        self.with(|c| {
            c.execute_cached(
                &format!(
                    "UPDATE sessions SET {} WHERE id = ?1",
                    stronger_stop_request("?2")
                ),
                params![id, request.as_str()],
            )
        })
        .map(drop)
    }

    fn stop_requests(&self, instance: &str) -> Result<Vec<(String, StopRequest)>, Error> {
        let rows: Vec<(String, String)> = self.with(|c| {
            let mut stmt = c.prepare_cached(&format!(
                "SELECT id, stop_request FROM sessions WHERE played_by = ?1 \
                 AND stop_request IS NOT NULL AND {IN_FLIGHT} ORDER BY created_ms, rowid"
            ))?;
            let rows = stmt.query_map([instance], |r| Ok((r.get(0)?, r.get(1)?)))?;
            rows.collect()
        })?;
        Ok(rows
            .into_iter()
            .filter_map(|(id, request)| Some((id, StopRequest::from_stored(&request)?)))
            .collect())
    }

    fn publish_progress(&self, id: &str, instance: &str, view: Option<&str>) -> Result<(), Error> {
        self.with(|c| {
            c.execute_cached(
                "UPDATE sessions SET progress_view = ?3 WHERE id = ?1 AND played_by = ?2",
                params![id, instance, view],
            )
        })
        .map(drop)
    }

    fn published_progress(&self, id: &str) -> Result<Option<(String, String)>, Error> {
        self.with(|c| {
            c.query_row_cached(
                "SELECT played_by, progress_view FROM sessions WHERE id = ?1 \
                 AND played_by IS NOT NULL AND progress_view IS NOT NULL",
                [id],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .optional()
        })
    }

    fn interrupt_jobs(&self, instance: Option<&str>, alive_since_ms: i64) -> Result<usize, Error> {
        self.with(|c| {
            c.execute_cached(
                "UPDATE jobs SET state = 'interrupted', error = 'server stopped while the job ran', \
                 finished_ms = ?3 WHERE state = 'running' AND (instance IS NULL OR instance = ?1 \
                 OR NOT EXISTS (SELECT 1 FROM instances i WHERE i.id = jobs.instance \
                 AND i.heartbeat_ms >= ?2))",
                params![instance, alive_since_ms, crate::storage::now_ms()],
            )
        })
    }
}
