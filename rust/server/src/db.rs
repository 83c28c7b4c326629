use std::path::Path;
use std::sync::Mutex;
use std::time::{SystemTime, UNIX_EPOCH};

use rusqlite::{Connection, OptionalExtension, params};

use crate::Error;

/// One row of the `sessions` table.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SessionRow {
    pub id: String,
    pub trials_total: u32,
    pub setting: String,
    pub playback: String,
    pub state: String,
    pub error: Option<String>,
    pub stop_reason: Option<String>,
    pub adaptive_min: Option<u32>,
    pub adaptive_k: u32,
    pub recording_bytes: Option<u64>,
    pub results_trials: u32,
    pub legacy: bool,
}

/// serial, state, session, last seen (ms since the epoch).
pub(crate) type DeviceRow = (String, String, Option<String>, i64);

/// What a new session needs.
pub(crate) struct NewSessionRow<'a> {
    pub idempotency_key: Option<&'a str>,
    pub trials_total: u32,
    pub setting: &'a str,
    pub playback: &'a str,
    pub adaptive_min: Option<u32>,
    pub adaptive_k: u32,
    pub legacy: bool,
}

/// The SQLite database: sessions, trials, jobs, devices.
pub(crate) struct Db {
    conn: Mutex<Connection>,
}

const SCHEMA: &str = "
PRAGMA journal_mode = WAL;
PRAGMA synchronous = NORMAL;
CREATE TABLE IF NOT EXISTS sessions (
    id TEXT PRIMARY KEY,
    idempotency_key TEXT UNIQUE,
    created_ms INTEGER NOT NULL,
    trials_total INTEGER NOT NULL,
    setting TEXT NOT NULL,
    playback TEXT NOT NULL,
    state TEXT NOT NULL,
    error TEXT,
    stop_reason TEXT,
    adaptive_min INTEGER,
    adaptive_k INTEGER NOT NULL,
    recording_bytes INTEGER,
    results_trials INTEGER NOT NULL DEFAULT 0,
    legacy INTEGER NOT NULL DEFAULT 0,
    finished_ms INTEGER
);
CREATE TABLE IF NOT EXISTS trials (
    session_id TEXT NOT NULL REFERENCES sessions(id),
    idx INTEGER NOT NULL,
    play_index INTEGER NOT NULL,
    idempotency_key TEXT,
    poses INTEGER NOT NULL,
    source TEXT NOT NULL,
    created_ms INTEGER NOT NULL,
    PRIMARY KEY (session_id, idx),
    UNIQUE (session_id, idempotency_key)
);
CREATE TABLE IF NOT EXISTS jobs (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    session_id TEXT NOT NULL REFERENCES sessions(id),
    kind TEXT NOT NULL,
    state TEXT NOT NULL,
    started_ms INTEGER NOT NULL,
    finished_ms INTEGER,
    error TEXT
);
CREATE TABLE IF NOT EXISTS devices (
    serial TEXT PRIMARY KEY,
    state TEXT NOT NULL,
    session_id TEXT,
    last_seen_ms INTEGER NOT NULL
);
";

pub(crate) fn now_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}

fn session_from_row(r: &rusqlite::Row<'_>) -> rusqlite::Result<SessionRow> {
    Ok(SessionRow {
        id: r.get(0)?,
        trials_total: r.get(1)?,
        setting: r.get(2)?,
        playback: r.get(3)?,
        state: r.get(4)?,
        error: r.get(5)?,
        stop_reason: r.get(6)?,
        adaptive_min: r.get(7)?,
        adaptive_k: r.get(8)?,
        recording_bytes: r.get::<_, Option<i64>>(9)?.map(|b| b as u64),
        results_trials: r.get(10)?,
        legacy: r.get::<_, i64>(11)? != 0,
    })
}

const SESSION_COLUMNS: &str = "id, trials_total, setting, playback, state, error, stop_reason, adaptive_min, \
     adaptive_k, recording_bytes, results_trials, legacy";

impl Db {
    pub fn open(path: &Path) -> Result<Db, Error> {
        let conn = Connection::open(path)?;
        conn.busy_timeout(std::time::Duration::from_secs(5))?;
        conn.execute_batch(SCHEMA)?;
        Ok(Db {
            conn: Mutex::new(conn),
        })
    }

    fn with<T>(&self, f: impl FnOnce(&mut Connection) -> rusqlite::Result<T>) -> Result<T, Error> {
        let mut conn = self
            .conn
            .lock()
            .map_err(|_| Error::Internal("database lock poisoned".into()))?;
        Ok(f(&mut conn)?)
    }

    /// Inserts a session, or returns the one created earlier with the same idempotency key.
    /// The bool is true when a new row was made.
    pub fn insert_session(
        &self,
        id: &str,
        new: &NewSessionRow<'_>,
    ) -> Result<(String, bool), Error> {
        self.with(|c| {
            let tx = c.transaction()?;
            if let Some(key) = new.idempotency_key {
                let existing: Option<String> = tx
                    .query_row("SELECT id FROM sessions WHERE idempotency_key = ?1", [key], |r| r.get(0))
                    .optional()?;
                if let Some(existing) = existing {
                    return Ok((existing, false));
                }
            }
            tx.execute(
                "INSERT INTO sessions (id, idempotency_key, created_ms, trials_total, setting, playback, state, \
                 adaptive_min, adaptive_k, legacy) VALUES (?1, ?2, ?3, ?4, ?5, ?6, 'created', ?7, ?8, ?9)",
                params![
                    id,
                    new.idempotency_key,
                    now_ms(),
                    new.trials_total,
                    new.setting,
                    new.playback,
                    new.adaptive_min,
                    new.adaptive_k,
                    new.legacy as i64
                ],
            )?;
            tx.commit()?;
            Ok((id.to_string(), true))
        })
    }

    pub fn session(&self, id: &str) -> Result<Option<SessionRow>, Error> {
        self.with(|c| {
            c.query_row(
                &format!("SELECT {SESSION_COLUMNS} FROM sessions WHERE id = ?1"),
                [id],
                session_from_row,
            )
            .optional()
        })
    }

    /// The newest `limit` sessions, newest first.
    pub fn recent_sessions(&self, limit: u32) -> Result<Vec<SessionRow>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare(&format!(
                "SELECT {SESSION_COLUMNS} FROM sessions ORDER BY rowid DESC LIMIT ?1"
            ))?;
            let rows = stmt.query_map([limit], session_from_row)?;
            rows.collect()
        })
    }

    /// Sessions past a retention that ends at `cutoff_ms` (ms since the epoch): done or
    /// failed before it, or created before it and left idle since (an upload that was
    /// abandoned, an `upload` session that never got its estimate).
    pub fn expired(&self, cutoff_ms: i64) -> Result<Vec<String>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare(
                "SELECT id FROM sessions WHERE \
                 (state IN ('done', 'failed') AND finished_ms < ?1) \
                 OR (created_ms < ?1 AND (state = 'created' \
                     OR (state = 'uploaded' AND playback = 'upload'))) \
                 ORDER BY created_ms",
            )?;
            let rows = stmt.query_map([cutoff_ms], |r| r.get(0))?;
            rows.collect()
        })
    }

    /// Sessions a previous server process left in flight.
    pub fn sessions_in_states(&self, states: &[&str]) -> Result<Vec<SessionRow>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare(&format!(
                "SELECT {SESSION_COLUMNS} FROM sessions WHERE state IN (SELECT value FROM json_each(?1)) ORDER BY created_ms"
            ))?;
            let list = serde_json::to_string(states).unwrap_or_default();
            let rows = stmt.query_map([list], session_from_row)?;
            rows.collect()
        })
    }

    pub fn set_state(&self, id: &str, state: &str, error: Option<&str>) -> Result<(), Error> {
        let finished = matches!(state, "done" | "failed").then(now_ms);
        self.with(|c| {
            c.execute(
                "UPDATE sessions SET state = ?2, error = ?3, finished_ms = ?4 WHERE id = ?1",
                params![id, state, error, finished],
            )
        })
        .map(|_| ())
    }

    pub fn set_recording(&self, id: &str, bytes: u64) -> Result<(), Error> {
        self.with(|c| {
            c.execute(
                "UPDATE sessions SET recording_bytes = ?2, state = 'uploaded' WHERE id = ?1",
                params![id, bytes as i64],
            )
        })
        .map(|_| ())
    }

    /// Records the first recording of a session that is still `created`;
    /// false when another request got there first (so playback starts once).
    pub fn claim_recording(&self, id: &str, bytes: u64) -> Result<bool, Error> {
        self.with(|c| {
            c.execute(
                "UPDATE sessions SET recording_bytes = ?2, state = 'uploaded' WHERE id = ?1 AND state = 'created'",
                params![id, bytes as i64],
            )
        })
        .map(|n| n == 1)
    }

    pub fn set_results(&self, id: &str, trials: u32) -> Result<(), Error> {
        self.with(|c| {
            c.execute(
                "UPDATE sessions SET results_trials = ?2 WHERE id = ?1",
                params![id, trials],
            )
        })
        .map(|_| ())
    }

    pub fn set_stop_reason(&self, id: &str, reason: &str) -> Result<(), Error> {
        self.with(|c| {
            c.execute(
                "UPDATE sessions SET stop_reason = ?2 WHERE id = ?1",
                params![id, reason],
            )
        })
        .map(|_| ())
    }

    /// Adds a trial under the next index. With a key already used in this
    /// session, nothing is added and the earlier index comes back with `false`.
    pub fn add_trial(
        &self,
        session: &str,
        key: Option<&str>,
        play_index: Option<u32>,
        poses: usize,
        source: &str,
        store: impl FnOnce(u32) -> Result<(), Error>,
    ) -> Result<(u32, bool), Error> {
        let mut conn = self
            .conn
            .lock()
            .map_err(|_| Error::Internal("database lock poisoned".into()))?;
        let tx = conn.transaction()?;
        if let Some(key) = key {
            let existing: Option<u32> = tx
                .query_row(
                    "SELECT idx FROM trials WHERE session_id = ?1 AND idempotency_key = ?2",
                    params![session, key],
                    |r| r.get(0),
                )
                .optional()?;
            if let Some(idx) = existing {
                return Ok((idx, false));
            }
        }
        let idx: u32 = tx.query_row(
            "SELECT COUNT(*) FROM trials WHERE session_id = ?1",
            [session],
            |r| r.get(0),
        )?;
        // The file goes into place before the row commits: a row never points at a missing file.
        store(idx)?;
        tx.execute(
            "INSERT INTO trials (session_id, idx, play_index, idempotency_key, poses, source, created_ms) \
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
            params![session, idx, play_index.unwrap_or(idx), key, poses as i64, source, now_ms()],
        )?;
        tx.commit()?;
        Ok((idx, true))
    }

    /// Removes a session with its trials and jobs (devices forget it) in one transaction.
    /// Returns whether it existed.
    pub fn delete_session(&self, id: &str) -> Result<bool, Error> {
        let mut conn = self
            .conn
            .lock()
            .map_err(|_| Error::Internal("database lock poisoned".into()))?;
        let tx = conn.transaction()?;
        tx.execute("DELETE FROM trials WHERE session_id = ?1", [id])?;
        tx.execute("DELETE FROM jobs WHERE session_id = ?1", [id])?;
        tx.execute(
            "UPDATE devices SET session_id = NULL WHERE session_id = ?1",
            [id],
        )?;
        let removed = tx.execute("DELETE FROM sessions WHERE id = ?1", [id])?;
        tx.commit()?;
        Ok(removed == 1)
    }

    pub fn trial_count(&self, session: &str) -> Result<u32, Error> {
        self.with(|c| {
            c.query_row(
                "SELECT COUNT(*) FROM trials WHERE session_id = ?1",
                [session],
                |r| r.get(0),
            )
        })
    }

    /// Storage indices of a session's trials in playback order, the order the
    /// estimate uses (trials of parallel devices arrive out of order).
    pub fn trials_in_order(&self, session: &str) -> Result<Vec<u32>, Error> {
        self.with(|c| {
            let mut stmt =
                c.prepare("SELECT idx FROM trials WHERE session_id = ?1 ORDER BY play_index, idx")?;
            let rows = stmt.query_map([session], |r| r.get(0))?;
            rows.collect()
        })
    }

    pub fn latest_session(
        &self,
        done_only: bool,
        legacy_only: bool,
    ) -> Result<Option<String>, Error> {
        let mut sql = String::from("SELECT id FROM sessions WHERE 1=1");
        if done_only {
            sql.push_str(" AND state = 'done'");
        }
        if legacy_only {
            sql.push_str(" AND legacy = 1");
        }
        sql.push_str(if done_only {
            " ORDER BY finished_ms DESC, rowid DESC LIMIT 1"
        } else {
            " ORDER BY rowid DESC LIMIT 1"
        });
        self.with(|c| c.query_row(&sql, [], |r| r.get(0)).optional())
    }

    pub fn start_job(&self, session: &str, kind: &str) -> Result<i64, Error> {
        self.with(|c| {
            c.execute(
                "INSERT INTO jobs (session_id, kind, state, started_ms) VALUES (?1, ?2, 'running', ?3)",
                params![session, kind, now_ms()],
            )?;
            Ok(c.last_insert_rowid())
        })
    }

    pub fn finish_job(&self, job: i64, state: &str, error: Option<&str>) -> Result<(), Error> {
        self.with(|c| {
            c.execute(
                "UPDATE jobs SET state = ?2, error = ?3, finished_ms = ?4 WHERE id = ?1",
                params![job, state, error, now_ms()],
            )
        })
        .map(|_| ())
    }

    /// Marks jobs a dead process left running; returns how many.
    pub fn interrupt_running_jobs(&self) -> Result<usize, Error> {
        self.with(|c| {
            c.execute(
                "UPDATE jobs SET state = 'interrupted', error = 'server stopped while the job ran', finished_ms = ?1 \
                 WHERE state = 'running'",
                [now_ms()],
            )
        })
    }

    pub fn jobs_of(&self, session: &str) -> Result<Vec<(String, String)>, Error> {
        self.with(|c| {
            let mut stmt =
                c.prepare("SELECT kind, state FROM jobs WHERE session_id = ?1 ORDER BY id")?;
            let rows = stmt.query_map([session], |r| Ok((r.get(0)?, r.get(1)?)))?;
            rows.collect()
        })
    }

    pub fn upsert_device(
        &self,
        serial: &str,
        state: &str,
        session: Option<&str>,
    ) -> Result<(), Error> {
        self.with(|c| {
            c.execute(
                "INSERT INTO devices (serial, state, session_id, last_seen_ms) VALUES (?1, ?2, ?3, ?4) \
                 ON CONFLICT(serial) DO UPDATE SET state = ?2, session_id = ?3, last_seen_ms = ?4",
                params![serial, state, session, now_ms()],
            )
        })
        .map(|_| ())
    }

    pub fn devices(&self) -> Result<Vec<DeviceRow>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare(
                "SELECT serial, state, session_id, last_seen_ms FROM devices ORDER BY serial",
            )?;
            let rows = stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?)))?;
            rows.collect()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn new_row(key: Option<&str>) -> NewSessionRow<'_> {
        NewSessionRow {
            idempotency_key: key,
            trials_total: 5,
            setting: "median",
            playback: "upload",
            adaptive_min: None,
            adaptive_k: 3,
            legacy: false,
        }
    }

    #[test]
    fn idempotent_insert_and_trials_survive_reopen() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sitar.db");
        {
            let db = Db::open(&path).unwrap();
            assert_eq!(
                db.insert_session("a", &new_row(Some("k1"))).unwrap(),
                ("a".into(), true)
            );
            assert_eq!(
                db.insert_session("b", &new_row(Some("k1"))).unwrap(),
                ("a".into(), false)
            );
            assert_eq!(
                db.add_trial("a", Some("t1"), None, 10, "upload", |_| Ok(()))
                    .unwrap(),
                (0, true)
            );
            assert_eq!(
                db.add_trial("a", Some("t2"), None, 10, "upload", |_| Ok(()))
                    .unwrap(),
                (1, true)
            );
            assert_eq!(
                db.add_trial("a", Some("t1"), None, 10, "upload", |_| Ok(()))
                    .unwrap(),
                (0, false)
            );
            // A failed store leaves no row behind.
            assert!(
                db.add_trial("a", None, Some(0), 10, "upload", |_| Err(Error::Internal(
                    "disk".into()
                )))
                .is_err()
            );
            db.set_state("a", "playing", None).unwrap();
        }
        let db = Db::open(&path).unwrap();
        assert_eq!(db.trial_count("a").unwrap(), 2);
        assert_eq!(
            db.add_trial("a", None, Some(0), 10, "sim", |_| Ok(()))
                .unwrap(),
            (2, true)
        );
        assert_eq!(db.trials_in_order("a").unwrap(), vec![0, 2, 1]);
        let row = db.session("a").unwrap().unwrap();
        assert_eq!((row.state.as_str(), row.trials_total), ("playing", 5));
        assert_eq!(db.sessions_in_states(&["playing"]).unwrap().len(), 1);
        assert!(db.session("b").unwrap().is_none());
    }
}
