//! The SQLite database: the connection, the schema and its migrations, and the tables of
//! trials, jobs and devices. The `sessions` table is [`crate::session`]'s: it reads and
//! writes those rows (`session/store.rs`, `session/lifecycle.rs`).

use std::path::Path;
use std::sync::Mutex;
use std::time::{SystemTime, UNIX_EPOCH};

use rusqlite::{Connection, OptionalExtension, Params, Row, params};

use crate::Error;

/// Room in the connection's statement cache: more than the server's distinct SQL texts
/// (about 50), so none is parsed twice.
const STATEMENT_CACHE: usize = 64;

/// `execute` and `query_row` through the connection's statement cache: a status poll or a
/// published estimate parses no SQL (parsing was about 2 % of a progressive session's CPU).
pub(crate) trait CachedSql {
    fn execute_cached(&self, sql: &str, params: impl Params) -> rusqlite::Result<usize>;
    fn query_row_cached<T>(
        &self,
        sql: &str,
        params: impl Params,
        row: impl FnOnce(&Row<'_>) -> rusqlite::Result<T>,
    ) -> rusqlite::Result<T>;
}

impl CachedSql for Connection {
    fn execute_cached(&self, sql: &str, params: impl Params) -> rusqlite::Result<usize> {
        self.prepare_cached(sql)?.execute(params)
    }

    fn query_row_cached<T>(
        &self,
        sql: &str,
        params: impl Params,
        row: impl FnOnce(&Row<'_>) -> rusqlite::Result<T>,
    ) -> rusqlite::Result<T> {
        self.prepare_cached(sql)?.query_row(params, row)
    }
}

/// How a job ended (the `jobs` table's states are `running`, these, and `interrupted`, which
/// a restart gives the jobs a dead process left running).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum JobEnd {
    Done,
    Failed,
}

impl JobEnd {
    fn as_str(self) -> &'static str {
        match self {
            JobEnd::Done => "done",
            JobEnd::Failed => "failed",
        }
    }
}

/// serial, state, session, last seen (ms since the epoch).
pub(crate) type DeviceRow = (String, String, Option<String>, i64);

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
    finished_ms INTEGER,
    window_frames INTEGER NOT NULL DEFAULT 10,
    pose_relation TEXT NOT NULL DEFAULT 'trans_part',
    owner INTEGER
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
CREATE TABLE IF NOT EXISTS tokens (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    name TEXT NOT NULL UNIQUE,
    role TEXT NOT NULL,
    lookup BLOB NOT NULL,
    hash BLOB NOT NULL UNIQUE,
    created_ms INTEGER NOT NULL,
    last_used_ms INTEGER
);
CREATE INDEX IF NOT EXISTS tokens_lookup ON tokens (lookup);
CREATE TABLE IF NOT EXISTS share_links (
    lookup BLOB NOT NULL,
    hash BLOB PRIMARY KEY,
    session_id TEXT NOT NULL,
    created_ms INTEGER NOT NULL
);
CREATE INDEX IF NOT EXISTS share_links_lookup ON share_links (lookup);
CREATE TABLE IF NOT EXISTS upload_usage (
    token_id INTEGER NOT NULL,
    hour INTEGER NOT NULL,
    bytes INTEGER NOT NULL,
    PRIMARY KEY (token_id, hour)
);
";

pub(crate) fn now_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}

/// Columns later versions added to a table, with their definitions: an older database gets
/// them on open (`ALTER TABLE … ADD COLUMN`, existing rows take the default).
const ADDED_COLUMNS: &[(&str, &str, &str)] = &[
    ("sessions", "window_frames", "INTEGER NOT NULL DEFAULT 10"),
    (
        "sessions",
        "pose_relation",
        "TEXT NOT NULL DEFAULT 'trans_part'",
    ),
    ("sessions", "owner", "INTEGER"),
];

/// Adds the [`ADDED_COLUMNS`] a database made by an older version lacks.
fn migrate(conn: &Connection) -> rusqlite::Result<()> {
    for (table, column, definition) in ADDED_COLUMNS {
        let present: bool = conn
            .prepare(&format!(
                "SELECT 1 FROM pragma_table_info('{table}') WHERE name = ?1"
            ))?
            .exists([column])?;
        if !present {
            conn.execute_batch(&format!(
                "ALTER TABLE {table} ADD COLUMN {column} {definition}"
            ))?;
            log::info!("database: added {table}.{column}");
        }
    }
    Ok(())
}

impl Db {
    pub fn open(path: &Path) -> Result<Db, Error> {
        let conn = Connection::open(path)?;
        conn.busy_timeout(std::time::Duration::from_secs(5))?;
        conn.set_prepared_statement_cache_capacity(STATEMENT_CACHE);
        conn.execute_batch(SCHEMA)?;
        migrate(&conn)?;
        Ok(Db {
            conn: Mutex::new(conn),
        })
    }

    /// Runs `f` on the connection (one at a time: the connection is behind a mutex).
    pub fn with<T>(
        &self,
        f: impl FnOnce(&mut Connection) -> rusqlite::Result<T>,
    ) -> Result<T, Error> {
        let mut conn = self
            .conn
            .lock()
            .map_err(|_| Error::Internal("database lock poisoned".into()))?;
        Ok(f(&mut conn)?)
    }

    /// Runs `f` in one transaction, committed when it returns `Ok`.
    pub fn transaction<T>(
        &self,
        f: impl FnOnce(&rusqlite::Transaction<'_>) -> Result<T, Error>,
    ) -> Result<T, Error> {
        let mut conn = self
            .conn
            .lock()
            .map_err(|_| Error::Internal("database lock poisoned".into()))?;
        let tx = conn.transaction()?;
        let value = f(&tx)?;
        tx.commit()?;
        Ok(value)
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

    pub fn trial_count(&self, session: &str) -> Result<u32, Error> {
        self.with(|c| {
            c.query_row_cached(
                "SELECT COUNT(*) FROM trials WHERE session_id = ?1",
                [session],
                |r| r.get(0),
            )
        })
    }

    /// (storage index, playback index) of a session's trials in playback order, the order
    /// the estimate uses (trials of parallel devices arrive out of order).
    pub fn trials_in_order(&self, session: &str) -> Result<Vec<(u32, u32)>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT idx, play_index FROM trials WHERE session_id = ?1 ORDER BY play_index, idx",
            )?;
            let rows = stmt.query_map([session], |r| Ok((r.get(0)?, r.get(1)?)))?;
            rows.collect()
        })
    }

    pub fn start_job(&self, session: &str, kind: &str) -> Result<i64, Error> {
        self.with(|c| {
            c.execute_cached(
                "INSERT INTO jobs (session_id, kind, state, started_ms) VALUES (?1, ?2, 'running', ?3)",
                params![session, kind, now_ms()],
            )?;
            Ok(c.last_insert_rowid())
        })
    }

    pub fn finish_job(&self, job: i64, end: JobEnd, error: Option<&str>) -> Result<(), Error> {
        self.with(|c| {
            c.execute_cached(
                "UPDATE jobs SET state = ?2, error = ?3, finished_ms = ?4 WHERE id = ?1",
                params![job, end.as_str(), error, now_ms()],
            )
        })
        .map(|_| ())
    }

    /// Marks jobs a dead process left running; returns how many.
    pub fn interrupt_running_jobs(&self) -> Result<usize, Error> {
        self.with(|c| {
            c.execute_cached(
                "UPDATE jobs SET state = 'interrupted', error = 'server stopped while the job ran', finished_ms = ?1 \
                 WHERE state = 'running'",
                [now_ms()],
            )
        })
    }

    pub fn jobs_of(&self, session: &str) -> Result<Vec<(String, String)>, Error> {
        self.with(|c| {
            let mut stmt =
                c.prepare_cached("SELECT kind, state FROM jobs WHERE session_id = ?1 ORDER BY id")?;
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
            c.execute_cached(
                "INSERT INTO devices (serial, state, session_id, last_seen_ms) VALUES (?1, ?2, ?3, ?4) \
                 ON CONFLICT(serial) DO UPDATE SET state = ?2, session_id = ?3, last_seen_ms = ?4",
                params![serial, state, session, now_ms()],
            )
        })
        .map(|_| ())
    }

    /// Which phone (trial `source`: `adb:SERIAL`, `sim:N`, or the uploaded file) played which
    /// trials of `session`, in first-played order.
    pub fn trial_sources(&self, session: &str) -> Result<Vec<(String, Vec<u32>)>, Error> {
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

    /// When `session` was created (ms since the Unix epoch).
    pub fn session_created_ms(&self, session: &str) -> Result<Option<i64>, Error> {
        self.with(|c| {
            use rusqlite::OptionalExtension;
            c.query_row_cached(
                "SELECT created_ms FROM sessions WHERE id = ?1",
                [session],
                |r| r.get(0),
            )
            .optional()
        })
    }

    pub fn devices(&self) -> Result<Vec<DeviceRow>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
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

    #[test]
    fn trials_are_idempotent_and_survive_a_reopen() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sitar.db");
        {
            let db = Db::open(&path).unwrap();
            // Trials belong to a session (a foreign key).
            db.with(|c| {
                c.execute(
                    "INSERT INTO sessions (id, created_ms, trials_total, setting, playback, state, \
                     adaptive_k) VALUES ('a', 0, 5, 'median', 'upload', 'created', 3)",
                    [],
                )
            })
            .unwrap();
            let add = |key, play| db.add_trial("a", key, play, 10, "upload", |_| Ok(()));
            assert_eq!(add(Some("t1"), None).unwrap(), (0, true));
            assert_eq!(add(Some("t2"), None).unwrap(), (1, true));
            assert_eq!(add(Some("t1"), None).unwrap(), (0, false));
            // A failed store leaves no row behind.
            assert!(
                db.add_trial("a", None, Some(0), 10, "upload", |_| Err(Error::Internal(
                    "disk".into()
                )))
                .is_err()
            );
        }
        let db = Db::open(&path).unwrap();
        assert_eq!(db.trial_count("a").unwrap(), 2);
        assert_eq!(
            db.add_trial("a", None, Some(0), 10, "sim", |_| Ok(()))
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
