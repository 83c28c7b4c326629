//! The `trials` table: each session's trials, their playback order, sources and keys.

use rusqlite::{OptionalExtension, params};

use super::{CachedSql, SqliteStore};
use crate::error::Error;
use crate::storage::metadata::TrialStore;
use crate::storage::now_ms;

impl TrialStore for SqliteStore {
    fn add_trial(
        &self,
        session: &str,
        key: Option<&str>,
        play_index: Option<u32>,
        poses: usize,
        source: &str,
        store: &mut dyn FnMut(u32) -> Result<(), Error>,
    ) -> Result<(u32, bool), Error> {
        let mut conn = self
            .conn
            .lock()
            .map_err(|_| Error::Internal("database lock poisoned".into()))?;
        let tx = conn.transaction()?;
        if let Some(key) = key {
            let existing: Option<u32> = tx
                .query_row_cached(
                    "SELECT idx FROM trials WHERE session_id = ?1 AND idempotency_key = ?2",
                    params![session, key],
                    |r| r.get(0),
                )
                .optional()?;
            if let Some(idx) = existing {
                return Ok((idx, false));
            }
        }
        let idx: u32 = tx.query_row_cached(
            "SELECT COUNT(*) FROM trials WHERE session_id = ?1",
            [session],
            |r| r.get(0),
        )?;
        // The file goes into place before the row commits: a row never points at a missing file.
        store(idx)?;
        tx.execute_cached(
            "INSERT INTO trials (session_id, idx, play_index, idempotency_key, poses, source, created_ms) \
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
            params![session, idx, play_index.unwrap_or(idx), key, poses as i64, source, now_ms()],
        )?;
        tx.commit()?;
        Ok((idx, true))
    }

    fn trial_count(&self, session: &str) -> Result<u32, Error> {
        self.with(|c| {
            c.query_row_cached(
                "SELECT COUNT(*) FROM trials WHERE session_id = ?1",
                [session],
                |r| r.get(0),
            )
        })
    }

    fn trials_in_order(&self, session: &str) -> Result<Vec<(u32, u32)>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT idx, play_index FROM trials WHERE session_id = ?1 ORDER BY play_index, idx",
            )?;
            let rows = stmt.query_map([session], |r| Ok((r.get(0)?, r.get(1)?)))?;
            rows.collect()
        })
    }

    fn trial_sources(&self, session: &str) -> Result<Vec<(String, Vec<u32>)>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT source, idx FROM trials WHERE session_id = ?1 ORDER BY idx",
            )?;
            let rows = stmt.query_map([session], |r| {
                Ok((r.get::<_, String>(0)?, r.get::<_, u32>(1)?))
            })?;
            let mut out: Vec<(String, Vec<u32>)> = Vec::new();
            for row in rows {
                let (source, idx) = row?;
                match out.iter_mut().find(|(s, _)| *s == source) {
                    Some((_, list)) => list.push(idx),
                    None => out.push((source, vec![idx])),
                }
            }
            Ok(out)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trials_are_idempotent_and_survive_a_reopen() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sitar.db");
        {
            let db = SqliteStore::open(&path).unwrap();
            // Trials belong to a session (a foreign key).
            db.with(|c| {
                c.execute(
                    "INSERT INTO sessions (id, created_ms, trials_total, setting, playback, state, \
                     adaptive_k) VALUES ('a', 0, 5, 'median', 'upload', 'created', 3)",
                    [],
                )
            })
            .unwrap();
            let add = |key, play| db.add_trial("a", key, play, 10, "upload", &mut |_| Ok(()));
            assert_eq!(add(Some("t1"), None).unwrap(), (0, true));
            assert_eq!(add(Some("t2"), None).unwrap(), (1, true));
            assert_eq!(add(Some("t1"), None).unwrap(), (0, false));
            // A failed store leaves no row behind.
            assert!(
                db.add_trial("a", None, Some(0), 10, "upload", &mut |_| Err(
                    Error::Internal("disk".into())
                ))
                .is_err()
            );
        }
        let db = SqliteStore::open(&path).unwrap();
        assert_eq!(db.trial_count("a").unwrap(), 2);
        assert_eq!(
            db.add_trial("a", None, Some(0), 10, "sim", &mut |_| Ok(()))
                .unwrap(),
            (2, true)
        );
        assert_eq!(
            db.trials_in_order("a").unwrap(),
            vec![(0, 0), (2, 0), (1, 1)]
        );
        assert_eq!(db.trial_count("b").unwrap(), 0);
    }
}
