//! The `trials` table in Postgres. Adding a trial holds one connection across the caller's
//! `store` (the trial's bytes go into the blob store before the row commits): the index is
//! taken under a per-session advisory lock, so two instances adding trials to one session
//! queue instead of taking the same index.

use super::{PgStore, u32_column};
use crate::error::Error;
use crate::storage::metadata::TrialStore;
use crate::storage::now_ms;

impl TrialStore for PgStore {
    fn add_trial(
        &self,
        session: &str,
        key: Option<&str>,
        play_index: Option<u32>,
        poses: usize,
        source: &str,
        store: &mut dyn FnMut(u32) -> Result<(), Error>,
    ) -> Result<(u32, bool), Error> {
        let (session, key) = (session.to_string(), key.map(str::to_string));
        let mut lease = self.pool.lease()?;
        lease.begin()?;
        let (id, k) = (session.clone(), key.clone());
        let (idx, earlier) = lease.run(move |c| {
            c.execute(
                "SELECT pg_advisory_xact_lock(hashtext('trials/' || $1))",
                &[&id],
            )?;
            if let Some(k) = &k {
                let row = c.query_opt(
                    "SELECT idx FROM trials WHERE session_id = $1 AND idempotency_key = $2",
                    &[&id, k],
                )?;
                if let Some(row) = row {
                    return Ok((
                        u32_column(&row, 0, "trials.idx").map_err(Error::Database)?,
                        true,
                    ));
                }
            }
            let row = c.query_one("SELECT COUNT(*) FROM trials WHERE session_id = $1", &[&id])?;
            Ok((
                u32_column(&row, 0, "trials count").map_err(Error::Database)?,
                false,
            ))
        })?;
        if earlier {
            return Ok((idx, false));
        }
        // The bytes go into place before the row commits: a row never points at no object.
        store(idx)?;
        let source = source.to_string();
        let poses = i64::try_from(poses).unwrap_or(i64::MAX);
        let play = i64::from(play_index.unwrap_or(idx));
        lease.run(move |c| {
            c.execute(
                "INSERT INTO trials (session_id, idx, play_index, idempotency_key, poses, source, \
                 created_ms) VALUES ($1, $2, $3, $4, $5, $6, $7)",
                &[
                    &session,
                    &i64::from(idx),
                    &play,
                    &key,
                    &poses,
                    &source,
                    &now_ms(),
                ],
            )?;
            Ok(())
        })?;
        lease.commit()?;
        Ok((idx, true))
    }

    fn trial_count(&self, session: &str) -> Result<u32, Error> {
        let id = session.to_string();
        self.pool.run(move |c| {
            let row = c.query_one("SELECT COUNT(*) FROM trials WHERE session_id = $1", &[&id])?;
            u32_column(&row, 0, "trials count").map_err(Error::Database)
        })
    }

    fn trials_in_order(&self, session: &str) -> Result<Vec<(u32, u32)>, Error> {
        let id = session.to_string();
        self.pool.run(move |c| {
            c.query(
                "SELECT idx, play_index FROM trials WHERE session_id = $1 ORDER BY play_index, idx",
                &[&id],
            )?
            .iter()
            .map(|r| {
                Ok((
                    u32_column(r, 0, "trials.idx").map_err(Error::Database)?,
                    u32_column(r, 1, "trials.play_index").map_err(Error::Database)?,
                ))
            })
            .collect()
        })
    }

    fn trial_sources(&self, session: &str) -> Result<Vec<(String, Vec<u32>)>, Error> {
        let id = session.to_string();
        self.pool.run(move |c| {
            let rows = c.query(
                "SELECT source, idx FROM trials WHERE session_id = $1 ORDER BY idx",
                &[&id],
            )?;
            let mut out: Vec<(String, Vec<u32>)> = Vec::new();
            for row in &rows {
                let source: String = row.get(0);
                let idx = u32_column(row, 1, "trials.idx").map_err(Error::Database)?;
                match out.iter_mut().find(|(s, _)| *s == source) {
                    Some((_, list)) => list.push(idx),
                    None => out.push((source, vec![idx])),
                }
            }
            Ok(out)
        })
    }
}
