//! The worker store's offered trials and leases (`trial_leases`, `lease_turns`) and failed
//! trials (`trial_failures`). A trial row is `pending`, `leased` (to one phone, until its
//! `expires_ms`), `done` (committed: exactly once, by one atomic `UPDATE … WHERE state =
//! 'leased'`, which stores the trial's text until its job takes it), `failed` (given up) or
//! `withdrawn`.

use rusqlite::{OptionalExtension, Transaction, params};

use super::{CachedSql, SqliteStore};
use crate::error::Error;
use crate::storage::workers::{
    CommittedTrial, Expired, Lease, LeaseCounts, LeaseStore, MAX_ATTEMPTS, MAX_FAILURES_KEPT,
    MAX_TAKEN_PER_CALL, Requeued, TrialFailure, random_id,
};

/// The round-robin key of an owner (a token id, or none).
fn owner_key(owner: Option<i64>) -> String {
    owner.map_or_else(|| "-".to_string(), |id| format!("t{id}"))
}

const LEASE_COLUMNS: &str =
    "lease_id, session_id, play_index, host_id, phone, expires_ms, recording_sha256";

fn lease_row(r: &rusqlite::Row<'_>) -> rusqlite::Result<Lease> {
    Ok(Lease {
        id: r.get(0)?,
        session: r.get(1)?,
        index: r.get(2)?,
        host: r.get(3)?,
        phone: r.get(4)?,
        expires_ms: r.get(5)?,
        recording_sha256: r.get(6)?,
    })
}

/// Gives the trial of a leased row back: pending again, or failed after [`MAX_ATTEMPTS`].
fn requeue(tx: &Transaction<'_>, session: &str, index: u32) -> rusqlite::Result<Requeued> {
    let attempts: u32 = tx.query_row_cached(
        "UPDATE trial_leases SET attempts = attempts + 1, lease_id = NULL, expires_ms = NULL, \
         state = CASE WHEN attempts + 1 >= ?3 THEN 'failed' ELSE 'pending' END \
         WHERE session_id = ?1 AND play_index = ?2 RETURNING attempts",
        params![session, index, MAX_ATTEMPTS],
        |r| r.get(0),
    )?;
    Ok(if attempts >= MAX_ATTEMPTS {
        Requeued::GivenUp
    } else {
        Requeued::Again
    })
}

impl LeaseStore for SqliteStore {
    fn offer(
        &self,
        session: &str,
        owner: Option<i64>,
        playback: &str,
        indices: &[u32],
        recording_sha256: &str,
        _now_ms: i64,
    ) -> Result<(), Error> {
        let owner = owner_key(owner);
        self.transaction(|tx| {
            tx.execute_cached(
                "UPDATE trial_leases SET state = 'withdrawn', lease_id = NULL, expires_ms = NULL \
                 WHERE session_id = ?1 AND state IN ('pending', 'leased')",
                [session],
            )?;
            tx.execute_cached(
                "UPDATE trial_leases SET taken = 1, trial_text = NULL \
                 WHERE session_id = ?1 AND state = 'done' AND taken = 0",
                [session],
            )?;
            let seq: i64 = tx.query_row_cached(
                "SELECT COALESCE(MAX(offered_seq), 0) + 1 FROM trial_leases",
                [],
                |r| r.get(0),
            )?;
            for index in indices {
                tx.execute_cached(
                    "INSERT INTO trial_leases (session_id, play_index, owner_key, playback, \
                     recording_sha256, offered_seq, state) VALUES (?1, ?2, ?3, ?4, ?5, ?6, 'pending') \
                     ON CONFLICT (session_id, play_index) DO UPDATE SET state = 'pending', \
                     owner_key = excluded.owner_key, playback = excluded.playback, \
                     recording_sha256 = excluded.recording_sha256, offered_seq = excluded.offered_seq, \
                     attempts = 0, lease_id = NULL, host_id = NULL, phone = NULL, expires_ms = NULL, \
                     trial_text = NULL, trial_source = NULL, taken = 0",
                    params![session, index, owner, playback, recording_sha256, seq],
                )?;
            }
            Ok(())
        })
    }

    fn claim(
        &self,
        host: &str,
        phone: &str,
        playback: &str,
        now_ms: i64,
        lease_ms: i64,
    ) -> Result<Option<Lease>, Error> {
        let lease_id = random_id('l')?;
        self.transaction(|tx| {
            // A phone asks only when free: what it still held was abandoned (no attempt lost).
            tx.execute_cached(
                "UPDATE trial_leases SET state = 'pending', lease_id = NULL, host_id = NULL, \
                 phone = NULL, expires_ms = NULL \
                 WHERE host_id = ?1 AND phone = ?2 AND state = 'leased'",
                params![host, phone],
            )?;
            let ready: bool = tx
                .prepare_cached(
                    "SELECT 1 FROM worker_phones WHERE host_id = ?1 AND serial = ?2 AND state = 'ready'",
                )?
                .exists(params![host, phone])?;
            if !ready {
                return Ok(None);
            }
            let next: Option<(String, u32, String)> = tx
                .query_row_cached(
                    "SELECT l.session_id, l.play_index, l.owner_key FROM trial_leases l \
                     LEFT JOIN lease_turns t ON t.owner_key = l.owner_key \
                     WHERE l.state = 'pending' AND l.playback = ?1 \
                     ORDER BY COALESCE(t.served_seq, 0), l.offered_seq, l.play_index LIMIT 1",
                    [playback],
                    |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)),
                )
                .optional()?;
            let Some((session, index, owner)) = next else {
                return Ok(None);
            };
            tx.execute_cached(
                "INSERT INTO lease_turns (owner_key, served_seq) \
                 VALUES (?1, (SELECT COALESCE(MAX(served_seq), 0) + 1 FROM lease_turns)) \
                 ON CONFLICT (owner_key) DO UPDATE SET served_seq = excluded.served_seq",
                [&owner],
            )?;
            let lease = tx.query_row_cached(
                &format!(
                    "UPDATE trial_leases SET state = 'leased', lease_id = ?3, host_id = ?4, \
                     phone = ?5, expires_ms = ?6 WHERE session_id = ?1 AND play_index = ?2 \
                     RETURNING {LEASE_COLUMNS}"
                ),
                params![session, index, lease_id, host, phone, now_ms + lease_ms],
                lease_row,
            )?;
            Ok(Some(lease))
        })
    }

    fn live_lease(&self, lease: &str, host: &str, now_ms: i64) -> Result<Option<Lease>, Error> {
        self.with(|c| {
            c.query_row_cached(
                &format!(
                    "SELECT {LEASE_COLUMNS} FROM trial_leases WHERE lease_id = ?1 AND host_id = ?2 \
                     AND state = 'leased' AND expires_ms >= ?3"
                ),
                params![lease, host, now_ms],
                lease_row,
            )
            .optional()
        })
    }

    fn commit(
        &self,
        lease: &str,
        host: &str,
        now_ms: i64,
        tum: &str,
        source: &str,
    ) -> Result<Result<Lease, String>, Error> {
        self.transaction(|tx| {
            let committed = tx
                .query_row_cached(
                    &format!(
                        "UPDATE trial_leases SET state = 'done', trial_text = ?4, \
                         trial_source = ?5, taken = 0 WHERE lease_id = ?1 AND host_id = ?2 \
                         AND state = 'leased' AND expires_ms >= ?3 RETURNING {LEASE_COLUMNS}"
                    ),
                    params![lease, host, now_ms, tum, source],
                    lease_row,
                )
                .optional()?;
            Ok(committed.ok_or_else(|| {
                format!(
                    "lease {lease} is not live (it expired, was withdrawn or its trial was \
                     given to another phone): its trial is not taken"
                )
            }))
        })
    }

    fn take_committed(
        &self,
        session: &str,
        player: Option<&str>,
    ) -> Result<Vec<CommittedTrial>, Error> {
        self.transaction(|tx| {
            let taken: Vec<CommittedTrial> = {
                let mut stmt = tx.prepare_cached(
                    "SELECT play_index, trial_text, trial_source FROM trial_leases \
                     WHERE session_id = ?1 AND state = 'done' AND taken = 0 \
                     AND trial_text IS NOT NULL AND (?3 IS NULL OR EXISTS (SELECT 1 FROM \
                     sessions s WHERE s.id = ?1 AND s.played_by = ?3)) \
                     ORDER BY play_index LIMIT ?2",
                )?;
                let limit = MAX_TAKEN_PER_CALL as i64;
                let rows = stmt.query_map(params![session, limit, player], |r| {
                    Ok(CommittedTrial {
                        index: r.get(0)?,
                        tum: r.get(1)?,
                        source: r.get::<_, Option<String>>(2)?.unwrap_or_default(),
                    })
                })?;
                rows.collect::<rusqlite::Result<_>>()?
            };
            for trial in &taken {
                tx.execute_cached(
                    "UPDATE trial_leases SET taken = 1, trial_text = NULL \
                     WHERE session_id = ?1 AND play_index = ?2",
                    params![session, trial.index],
                )?;
            }
            Ok(taken)
        })
    }

    fn give_back(&self, lease: &str, host: &str) -> Result<Option<Requeued>, Error> {
        self.transaction(|tx| {
            let row: Option<(String, u32)> = tx
                .query_row_cached(
                    "SELECT session_id, play_index FROM trial_leases \
                     WHERE lease_id = ?1 AND host_id = ?2 AND state = 'leased'",
                    params![lease, host],
                    |r| Ok((r.get(0)?, r.get(1)?)),
                )
                .optional()?;
            match row {
                Some((session, index)) => Ok(Some(requeue(tx, &session, index)?)),
                None => Ok(None),
            }
        })
    }

    fn expire(&self, now_ms: i64) -> Result<Vec<Expired>, Error> {
        self.transaction(|tx| {
            let rows: Vec<(String, String, u32, String, String)> = {
                let mut stmt = tx.prepare_cached(
                    "SELECT lease_id, session_id, play_index, host_id, phone FROM trial_leases \
                     WHERE state = 'leased' AND expires_ms < ?1",
                )?;
                let rows = stmt.query_map([now_ms], |r| {
                    Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?, r.get(4)?))
                })?;
                rows.collect::<rusqlite::Result<_>>()?
            };
            let mut expired = Vec::with_capacity(rows.len());
            for (lease, session, index, host, phone) in rows {
                let requeued = requeue(tx, &session, index)?;
                expired.push(Expired {
                    lease,
                    session,
                    index,
                    host,
                    phone,
                    requeued,
                });
            }
            Ok(expired)
        })
    }

    fn withdraw(&self, session: &str) -> Result<(), Error> {
        self.transaction(|tx| {
            tx.execute_cached(
                "UPDATE trial_leases SET state = 'withdrawn', lease_id = NULL, expires_ms = NULL \
                 WHERE session_id = ?1 AND state IN ('pending', 'leased')",
                [session],
            )?;
            tx.execute_cached(
                "UPDATE trial_leases SET taken = 1, trial_text = NULL \
                 WHERE session_id = ?1 AND state = 'done' AND taken = 0",
                [session],
            )?;
            Ok(())
        })
    }

    fn counts(&self, session: &str) -> Result<LeaseCounts, Error> {
        self.with(|c| {
            c.query_row_cached(
                "SELECT COALESCE(SUM(state = 'pending'), 0), COALESCE(SUM(state = 'leased'), 0), \
                 COALESCE(SUM(state = 'done'), 0), COALESCE(SUM(state = 'failed'), 0) \
                 FROM trial_leases WHERE session_id = ?1",
                [session],
                |r| {
                    Ok(LeaseCounts {
                        pending: r.get(0)?,
                        leased: r.get(1)?,
                        done: r.get(2)?,
                        failed: r.get(3)?,
                    })
                },
            )
        })
    }

    fn record_failure(&self, session: &str, failure: &TrialFailure) -> Result<(), Error> {
        self.with(|c| {
            let kept: i64 = c.query_row_cached(
                "SELECT COUNT(*) FROM trial_failures WHERE session_id = ?1",
                [session],
                |r| r.get(0),
            )?;
            if kept < MAX_FAILURES_KEPT as i64 {
                c.execute_cached(
                    "INSERT INTO trial_failures (session_id, play_index, source, error, at_ms) \
                     VALUES (?1, ?2, ?3, ?4, ?5)",
                    params![
                        session,
                        failure.index,
                        failure.source,
                        failure.error,
                        failure.at_ms
                    ],
                )?;
            }
            Ok(())
        })
    }

    fn failures(&self, session: &str) -> Result<Vec<TrialFailure>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT play_index, source, error, at_ms FROM trial_failures \
                 WHERE session_id = ?1 ORDER BY id",
            )?;
            let rows = stmt.query_map([session], |r| {
                Ok(TrialFailure {
                    index: r.get(0)?,
                    source: r.get(1)?,
                    error: r.get(2)?,
                    at_ms: r.get(3)?,
                })
            })?;
            rows.collect()
        })
    }

    fn forget(&self, session: &str) -> Result<(), Error> {
        self.transaction(|tx| {
            tx.execute_cached("DELETE FROM trial_leases WHERE session_id = ?1", [session])?;
            tx.execute_cached(
                "DELETE FROM trial_failures WHERE session_id = ?1",
                [session],
            )?;
            Ok(())
        })
    }
}
