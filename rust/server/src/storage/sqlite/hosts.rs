//! The worker store's hosts and phones (`worker_hosts`, `worker_phones`).

use rusqlite::{OptionalExtension, params};

use super::{CachedSql, SqliteStore};
use crate::error::Error;
use crate::storage::workers::{
    FAILURES_OUT_OF_SERVICE, HostRow, HostStore, PhoneRow, PhoneState, random_id,
};

fn host_row(r: &rusqlite::Row<'_>) -> rusqlite::Result<HostRow> {
    Ok(HostRow {
        id: r.get(0)?,
        name: r.get(1)?,
        token: r.get(2)?,
        playback: r.get(3)?,
        last_seen_ms: r.get(4)?,
    })
}

impl HostStore for SqliteStore {
    fn register_host(
        &self,
        token: i64,
        name: &str,
        playback: &str,
        phones: &[String],
        now_ms: i64,
    ) -> Result<String, Error> {
        let fresh = random_id('h')?;
        self.transaction(|tx| {
            let id: Option<String> = tx
                .query_row_cached(
                    "SELECT id FROM worker_hosts WHERE token_id = ?1 AND name = ?2",
                    params![token, name],
                    |r| r.get(0),
                )
                .optional()?;
            let id = match id {
                Some(id) => {
                    tx.execute_cached(
                        "UPDATE worker_hosts SET playback = ?2, last_seen_ms = ?3 WHERE id = ?1",
                        params![id, playback, now_ms],
                    )?;
                    id
                }
                None => {
                    tx.execute_cached(
                        "INSERT INTO worker_hosts (id, token_id, name, playback, registered_ms, last_seen_ms) \
                         VALUES (?1, ?2, ?3, ?4, ?5, ?5)",
                        params![fresh, token, name, playback, now_ms],
                    )?;
                    fresh
                }
            };
            // A restarted worker: its phones are back in service, its old leases played by
            // nobody now.
            tx.execute_cached("DELETE FROM worker_phones WHERE host_id = ?1", [&id])?;
            for serial in phones {
                tx.execute_cached(
                    "INSERT INTO worker_phones (host_id, serial, state) VALUES (?1, ?2, 'ready')",
                    params![id, serial],
                )?;
            }
            tx.execute_cached(
                "UPDATE trial_leases SET state = 'pending', lease_id = NULL, host_id = NULL, \
                 phone = NULL, expires_ms = NULL WHERE host_id = ?1 AND state = 'leased'",
                [&id],
            )?;
            Ok(id)
        })
    }

    fn host(&self, id: &str) -> Result<Option<HostRow>, Error> {
        self.with(|c| {
            c.query_row_cached(
                "SELECT id, name, token_id, playback, last_seen_ms FROM worker_hosts WHERE id = ?1",
                [id],
                host_row,
            )
            .optional()
        })
    }

    fn heartbeat(
        &self,
        id: &str,
        phones: &[String],
        held: &[String],
        now_ms: i64,
        lease_ms: i64,
    ) -> Result<Vec<String>, Error> {
        self.transaction(|tx| {
            let seen = tx.execute_cached(
                "UPDATE worker_hosts SET last_seen_ms = ?2 WHERE id = ?1",
                params![id, now_ms],
            )?;
            if seen == 0 {
                return Err(Error::NotFound(format!("no host {id:?}: register again")));
            }
            // Unlisted phones are missing; listed ones present (a missing one ready again,
            // one out of service stays so).
            tx.execute_cached(
                "UPDATE worker_phones SET state = 'missing' WHERE host_id = ?1 AND state = 'ready'",
                [id],
            )?;
            for serial in phones {
                tx.execute_cached(
                    "INSERT INTO worker_phones (host_id, serial, state) VALUES (?1, ?2, 'ready') \
                     ON CONFLICT (host_id, serial) DO UPDATE SET state = \
                     CASE WHEN state = 'out_of_service' THEN state ELSE 'ready' END",
                    params![id, serial],
                )?;
            }
            // Only live leases are renewed: one past its time belongs to the reaper.
            tx.execute_cached(
                "UPDATE trial_leases SET expires_ms = ?2 \
                 WHERE host_id = ?1 AND state = 'leased' AND expires_ms >= ?3",
                params![id, now_ms + lease_ms, now_ms],
            )?;
            let mut abort = Vec::new();
            for lease in held {
                let live: bool = tx
                    .prepare_cached(
                        "SELECT 1 FROM trial_leases WHERE lease_id = ?1 AND host_id = ?2 \
                         AND state = 'leased'",
                    )?
                    .exists(params![lease, id])?;
                if !live {
                    abort.push(lease.clone());
                }
            }
            Ok(abort)
        })
    }

    fn hosts(&self) -> Result<Vec<HostRow>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT id, name, token_id, playback, last_seen_ms FROM worker_hosts ORDER BY name, id",
            )?;
            let rows = stmt.query_map([], host_row)?;
            rows.collect()
        })
    }

    fn phones(&self) -> Result<Vec<PhoneRow>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT p.host_id, p.serial, p.state, p.failures, p.last_error \
                 FROM worker_phones p JOIN worker_hosts h ON h.id = p.host_id \
                 ORDER BY h.name, p.host_id, p.serial",
            )?;
            let rows = stmt.query_map([], |r| {
                Ok(PhoneRow {
                    host: r.get(0)?,
                    serial: r.get(1)?,
                    state: PhoneState::parse(&r.get::<_, String>(2)?),
                    failures: r.get(3)?,
                    last_error: r.get(4)?,
                })
            })?;
            rows.collect()
        })
    }

    fn phone_result(
        &self,
        host: &str,
        serial: &str,
        error: Option<&str>,
    ) -> Result<PhoneState, Error> {
        self.transaction(|tx| {
            let changed = match error {
                None => tx.execute_cached(
                    "UPDATE worker_phones SET failures = 0 WHERE host_id = ?1 AND serial = ?2",
                    params![host, serial],
                )?,
                Some(why) => tx.execute_cached(
                    "UPDATE worker_phones SET failures = failures + 1, last_error = ?3, \
                     state = CASE WHEN failures + 1 >= ?4 THEN 'out_of_service' ELSE state END \
                     WHERE host_id = ?1 AND serial = ?2",
                    params![host, serial, why, FAILURES_OUT_OF_SERVICE],
                )?,
            };
            if changed == 0 {
                return Ok(PhoneState::Missing);
            }
            let state: String = tx.query_row_cached(
                "SELECT state FROM worker_phones WHERE host_id = ?1 AND serial = ?2",
                params![host, serial],
                |r| r.get(0),
            )?;
            Ok(PhoneState::parse(&state))
        })
    }
}
