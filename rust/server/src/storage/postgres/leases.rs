//! The worker store's offered trials and leases (`trial_leases`, `lease_turns`) and failed
//! trials (`trial_failures`) in Postgres, shared by every instance. The states are SQLite's
//! (`storage/sqlite/leases.rs`); what changes is that several instances write at once:
//! - a claim picks its row with `FOR UPDATE … SKIP LOCKED`, so two instances never lease one
//!   trial and neither waits on the other's pick;
//! - a commit, a give-back and an expiry are each one conditional `UPDATE … WHERE state =
//!   'leased'` (the row lock makes the second of two racing writers see the first's result:
//!   a trial is committed exactly once, and an expired lease never commits);
//! - offers and owners' turns are ordered by sequences (`trial_offer_seq`, `lease_turn_seq`),
//!   not `MAX + 1`, which two instances could both read.

use super::{PgStore, u32_column};
use crate::error::Error;
use crate::storage::workers::{
    CommittedTrial, Expired, Lease, LeaseCounts, LeaseStore, MAX_ATTEMPTS, MAX_FAILURES_KEPT,
    MAX_TAKEN_PER_CALL, Requeued, TrialFailure, random_id,
};

/// The round-robin key of an owner (a token id, or none), as SQLite writes it.
fn owner_key(owner: Option<i64>) -> String {
    owner.map_or_else(|| "-".to_string(), |id| format!("t{id}"))
}

const LEASE_COLUMNS: &str =
    "lease_id, session_id, play_index, host_id, phone, expires_ms, recording_sha256";

fn lease_row(r: &postgres::Row) -> Result<Lease, Error> {
    Ok(Lease {
        id: r.get(0),
        session: r.get(1),
        index: u32_column(r, 2, "trial_leases.play_index").map_err(Error::Database)?,
        host: r.get(3),
        phone: r.get(4),
        expires_ms: r.get(5),
        recording_sha256: r.get(6),
    })
}

/// What became of a trial given back, from the `given_up` its `UPDATE` returned.
fn requeued(given_up: bool) -> Requeued {
    if given_up {
        Requeued::GivenUp
    } else {
        Requeued::Again
    }
}

/// The `SET` of a trial given back: pending again, or failed at [`MAX_ATTEMPTS`] (`$ATTEMPTS`
/// is the parameter holding it).
fn requeue_set(attempts_param: &str) -> String {
    format!(
        "attempts = trial_leases.attempts + 1, lease_id = NULL, expires_ms = NULL, \
         state = CASE WHEN trial_leases.attempts + 1 >= {attempts_param} THEN 'failed' \
         ELSE 'pending' END"
    )
}

impl LeaseStore for PgStore {
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
        let (session, playback, sha) = (
            session.to_string(),
            playback.to_string(),
            recording_sha256.to_string(),
        );
        let indices: Vec<i64> = indices.iter().map(|&i| i64::from(i)).collect();
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            tx.execute(
                "UPDATE trial_leases SET state = 'withdrawn', lease_id = NULL, expires_ms = NULL \
                 WHERE session_id = $1 AND state IN ('pending', 'leased')",
                &[&session],
            )?;
            tx.execute(
                "UPDATE trial_leases SET taken = TRUE, trial_text = NULL \
                 WHERE session_id = $1 AND state = 'done' AND NOT taken",
                &[&session],
            )?;
            let seq: i64 = tx
                .query_one("SELECT nextval('trial_offer_seq')", &[])?
                .get(0);
            for index in &indices {
                tx.execute(
                    "INSERT INTO trial_leases (session_id, play_index, owner_key, playback, \
                     recording_sha256, offered_seq, state) VALUES ($1, $2, $3, $4, $5, $6, 'pending') \
                     ON CONFLICT (session_id, play_index) DO UPDATE SET state = 'pending', \
                     owner_key = EXCLUDED.owner_key, playback = EXCLUDED.playback, \
                     recording_sha256 = EXCLUDED.recording_sha256, \
                     offered_seq = EXCLUDED.offered_seq, attempts = 0, lease_id = NULL, \
                     host_id = NULL, phone = NULL, expires_ms = NULL, trial_text = NULL, \
                     trial_source = NULL, taken = FALSE",
                    &[&session, index, &owner, &playback, &sha, &seq],
                )?;
            }
            tx.commit()?;
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
        let (host, phone, playback) = (host.to_string(), phone.to_string(), playback.to_string());
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            // A phone asks only when free: what it still held was abandoned (no attempt lost).
            tx.execute(
                "UPDATE trial_leases SET state = 'pending', lease_id = NULL, host_id = NULL, \
                 phone = NULL, expires_ms = NULL \
                 WHERE host_id = $1 AND phone = $2 AND state = 'leased'",
                &[&host, &phone],
            )?;
            let ready = tx
                .query_opt(
                    "SELECT 1 FROM worker_phones WHERE host_id = $1 AND serial = $2 \
                     AND state = 'ready'",
                    &[&host, &phone],
                )?
                .is_some();
            if !ready {
                tx.commit()?;
                return Ok(None);
            }
            // Owners in turn, then the oldest offer, lowest index; a row another instance is
            // leasing right now is skipped, not waited for.
            let next = tx.query_opt(
                "SELECT l.session_id, l.play_index, l.owner_key FROM trial_leases l \
                 LEFT JOIN lease_turns t ON t.owner_key = l.owner_key \
                 WHERE l.state = 'pending' AND l.playback = $1 \
                 ORDER BY COALESCE(t.served_seq, 0), l.offered_seq, l.play_index \
                 LIMIT 1 FOR UPDATE OF l SKIP LOCKED",
                &[&playback],
            )?;
            let Some(next) = next else {
                tx.commit()?;
                return Ok(None);
            };
            let (session, index, owner): (String, i64, String) =
                (next.get(0), next.get(1), next.get(2));
            tx.execute(
                "INSERT INTO lease_turns (owner_key, served_seq) \
                 VALUES ($1, nextval('lease_turn_seq')) \
                 ON CONFLICT (owner_key) DO UPDATE SET served_seq = EXCLUDED.served_seq",
                &[&owner],
            )?;
            let row = tx.query_one(
                &format!(
                    "UPDATE trial_leases SET state = 'leased', lease_id = $3, host_id = $4, \
                     phone = $5, expires_ms = $6 WHERE session_id = $1 AND play_index = $2 \
                     RETURNING {LEASE_COLUMNS}"
                ),
                &[
                    &session,
                    &index,
                    &lease_id,
                    &host,
                    &phone,
                    &(now_ms + lease_ms),
                ],
            )?;
            let lease = lease_row(&row)?;
            tx.commit()?;
            Ok(Some(lease))
        })
    }

    fn live_lease(&self, lease: &str, host: &str, now_ms: i64) -> Result<Option<Lease>, Error> {
        let (lease, host) = (lease.to_string(), host.to_string());
        self.pool.run(move |c| {
            c.query_opt(
                &format!(
                    "SELECT {LEASE_COLUMNS} FROM trial_leases WHERE lease_id = $1 AND host_id = $2 \
                     AND state = 'leased' AND expires_ms >= $3"
                ),
                &[&lease, &host, &now_ms],
            )?
            .as_ref()
            .map(lease_row)
            .transpose()
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
        let (lease, host, tum, source) = (
            lease.to_string(),
            host.to_string(),
            tum.to_string(),
            source.to_string(),
        );
        self.pool.run(move |c| {
            // One statement: of two racing commits (or a commit and an expiry) the second
            // waits for the row and then finds it no longer leased.
            let committed = c.query_opt(
                &format!(
                    "UPDATE trial_leases SET state = 'done', trial_text = $4, trial_source = $5, \
                     taken = FALSE WHERE lease_id = $1 AND host_id = $2 AND state = 'leased' \
                     AND expires_ms >= $3 RETURNING {LEASE_COLUMNS}"
                ),
                &[&lease, &host, &now_ms, &tum, &source],
            )?;
            Ok(match committed {
                Some(row) => Ok(lease_row(&row)?),
                None => Err(format!(
                    "lease {lease} is not live (it expired, was withdrawn or its trial was \
                     given to another phone): its trial is not taken"
                )),
            })
        })
    }

    fn take_committed(
        &self,
        session: &str,
        player: Option<&str>,
    ) -> Result<Vec<CommittedTrial>, Error> {
        let session = session.to_string();
        let player = player.map(str::to_string);
        let limit = MAX_TAKEN_PER_CALL as i64;
        self.pool.run(move |c| {
            // Rows another instance is taking right now are skipped: each is taken once. The
            // player's row is share-locked: an adoption waits until this take is over.
            let rows = c.query(
                "WITH picked AS (SELECT session_id, play_index, trial_text, trial_source \
                 FROM trial_leases WHERE session_id = $1 AND state = 'done' AND NOT taken \
                 AND trial_text IS NOT NULL AND ($3::TEXT IS NULL OR EXISTS (SELECT 1 FROM \
                 (SELECT 1 FROM sessions s WHERE s.id = $1 AND s.played_by = $3 FOR SHARE) p)) \
                 ORDER BY play_index LIMIT $2 FOR UPDATE SKIP LOCKED) \
                 UPDATE trial_leases l SET taken = TRUE, trial_text = NULL FROM picked \
                 WHERE l.session_id = picked.session_id AND l.play_index = picked.play_index \
                 RETURNING picked.play_index, picked.trial_text, picked.trial_source",
                &[&session, &limit, &player],
            )?;
            let mut taken = rows
                .iter()
                .map(|r| {
                    Ok(CommittedTrial {
                        index: u32_column(r, 0, "trial_leases.play_index")
                            .map_err(Error::Database)?,
                        tum: r.get(1),
                        source: r.get::<_, Option<String>>(2).unwrap_or_default(),
                    })
                })
                .collect::<Result<Vec<_>, Error>>()?;
            taken.sort_by_key(|t| t.index);
            Ok(taken)
        })
    }

    fn give_back(&self, lease: &str, host: &str) -> Result<Option<Requeued>, Error> {
        let (lease, host) = (lease.to_string(), host.to_string());
        let attempts = i64::from(MAX_ATTEMPTS);
        self.pool.run(move |c| {
            let row = c.query_opt(
                &format!(
                    "UPDATE trial_leases SET {} WHERE lease_id = $1 AND host_id = $2 \
                     AND state = 'leased' RETURNING state = 'failed'",
                    requeue_set("$3")
                ),
                &[&lease, &host, &attempts],
            )?;
            Ok(row.map(|r| requeued(r.get(0))))
        })
    }

    fn expire(&self, now_ms: i64) -> Result<Vec<Expired>, Error> {
        let attempts = i64::from(MAX_ATTEMPTS);
        self.pool.run(move |c| {
            // Rows a commit holds right now are skipped: if that commit fails (the lease was
            // past its time), the next pass expires them.
            let rows = c.query(
                &format!(
                    "WITH old AS (SELECT session_id, play_index, lease_id, host_id, phone \
                     FROM trial_leases WHERE state = 'leased' AND expires_ms < $1 \
                     FOR UPDATE SKIP LOCKED) \
                     UPDATE trial_leases SET {} FROM old \
                     WHERE trial_leases.session_id = old.session_id \
                     AND trial_leases.play_index = old.play_index \
                     RETURNING old.lease_id, old.session_id, old.play_index, old.host_id, \
                     old.phone, trial_leases.state = 'failed'",
                    requeue_set("$2")
                ),
                &[&now_ms, &attempts],
            )?;
            rows.iter()
                .map(|r| {
                    Ok(Expired {
                        lease: r.get(0),
                        session: r.get(1),
                        index: u32_column(r, 2, "trial_leases.play_index")
                            .map_err(Error::Database)?,
                        host: r.get(3),
                        phone: r.get(4),
                        requeued: requeued(r.get(5)),
                    })
                })
                .collect()
        })
    }

    fn withdraw(&self, session: &str) -> Result<(), Error> {
        let session = session.to_string();
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            tx.execute(
                "UPDATE trial_leases SET state = 'withdrawn', lease_id = NULL, expires_ms = NULL \
                 WHERE session_id = $1 AND state IN ('pending', 'leased')",
                &[&session],
            )?;
            tx.execute(
                "UPDATE trial_leases SET taken = TRUE, trial_text = NULL \
                 WHERE session_id = $1 AND state = 'done' AND NOT taken",
                &[&session],
            )?;
            tx.commit()?;
            Ok(())
        })
    }

    fn counts(&self, session: &str) -> Result<LeaseCounts, Error> {
        let session = session.to_string();
        self.pool.run(move |c| {
            let r = c.query_one(
                "SELECT COUNT(*) FILTER (WHERE state = 'pending'), \
                 COUNT(*) FILTER (WHERE state = 'leased'), \
                 COUNT(*) FILTER (WHERE state = 'done'), \
                 COUNT(*) FILTER (WHERE state = 'failed') \
                 FROM trial_leases WHERE session_id = $1",
                &[&session],
            )?;
            let count = |i, what| u32_column(&r, i, what).map_err(Error::Database);
            Ok(LeaseCounts {
                pending: count(0, "pending trials")?,
                leased: count(1, "leased trials")?,
                done: count(2, "done trials")?,
                failed: count(3, "failed trials")?,
            })
        })
    }

    fn record_failure(&self, session: &str, failure: &TrialFailure) -> Result<(), Error> {
        let (session, failure) = (session.to_string(), failure.clone());
        let max = MAX_FAILURES_KEPT as i64;
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            // Instances recording failures of one session at once count in turn.
            tx.execute(
                "SELECT pg_advisory_xact_lock(hashtext('trial_failures/' || $1))",
                &[&session],
            )?;
            tx.execute(
                "INSERT INTO trial_failures (session_id, play_index, source, error, at_ms) \
                 SELECT $1, $2, $3, $4, $5 \
                 WHERE (SELECT COUNT(*) FROM trial_failures WHERE session_id = $1) < $6",
                &[
                    &session,
                    &i64::from(failure.index),
                    &failure.source,
                    &failure.error,
                    &failure.at_ms,
                    &max,
                ],
            )?;
            tx.commit()?;
            Ok(())
        })
    }

    fn failures(&self, session: &str) -> Result<Vec<TrialFailure>, Error> {
        let session = session.to_string();
        self.pool.run(move |c| {
            c.query(
                "SELECT play_index, source, error, at_ms FROM trial_failures \
                 WHERE session_id = $1 ORDER BY id",
                &[&session],
            )?
            .iter()
            .map(|r| {
                Ok(TrialFailure {
                    index: u32_column(r, 0, "trial_failures.play_index")
                        .map_err(Error::Database)?,
                    source: r.get(1),
                    error: r.get(2),
                    at_ms: r.get(3),
                })
            })
            .collect()
        })
    }

    fn forget(&self, session: &str) -> Result<(), Error> {
        let session = session.to_string();
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            tx.execute(
                "DELETE FROM trial_leases WHERE session_id = $1",
                &[&session],
            )?;
            tx.execute(
                "DELETE FROM trial_failures WHERE session_id = $1",
                &[&session],
            )?;
            tx.commit()?;
            Ok(())
        })
    }
}
