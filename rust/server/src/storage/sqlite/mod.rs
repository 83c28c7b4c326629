//! The embedded metadata store: SQLite in `DATA/sitar.db` (WAL mode, so `sitar token` works
//! beside a running server). This folder is the only place that speaks SQL: the connection,
//! the schema and its migrations here, and one file per concern of
//! [`crate::storage::metadata`] (`sessions`, `trials`, `jobs`, `tokens`, `usage`, `venues`,
//! `instances` with its versioned `instance_schema`) and
//! of [`crate::storage::workers`] (`hosts`, `leases`, with their versioned `worker_schema`).

use std::path::Path;
use std::sync::Mutex;

use rusqlite::{Connection, Params, Row};

use crate::error::Error;

mod component_schema;
mod deletes;
#[cfg(feature = "cluster")]
pub(crate) mod export;
mod hosts;
mod instance_schema;
mod instances;
mod jobs;
mod joining;
mod leases;
mod sessions;
mod tokens;
mod trials;
mod usage;
mod venues;
mod worker_schema;

/// Room in the connection's statement cache: more than the server's distinct SQL texts
/// (about 50), so none is parsed twice.
const STATEMENT_CACHE: usize = 64;

/// `execute` and `query_row` through the connection's statement cache: a status poll or a
/// published estimate parses no SQL (parsing was about 2 % of a progressive session's CPU).
pub(super) trait CachedSql {
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

/// The embedded metadata store: one SQLite connection behind a mutex.
pub(crate) struct SqliteStore {
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
    owner INTEGER,
    venue TEXT,
    convention TEXT NOT NULL DEFAULT 'unity',
    calibration TEXT
);
CREATE TABLE IF NOT EXISTS venues (
    id TEXT PRIMARY KEY,
    name TEXT NOT NULL,
    anchor TEXT NOT NULL,
    cell_m REAL NOT NULL,
    owner INTEGER,
    created_ms INTEGER NOT NULL
);
CREATE TABLE IF NOT EXISTS venue_members (
    venue_id TEXT NOT NULL REFERENCES venues(id),
    token_id INTEGER NOT NULL,
    PRIMARY KEY (venue_id, token_id)
);
CREATE TABLE IF NOT EXISTS venue_contributions (
    session_id TEXT PRIMARY KEY,
    generation INTEGER NOT NULL,
    body BLOB
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
CREATE TABLE IF NOT EXISTS session_creations (
    token_id INTEGER NOT NULL,
    created_ms INTEGER NOT NULL
);
CREATE INDEX IF NOT EXISTS session_creations_token ON session_creations (token_id, created_ms);
CREATE TABLE IF NOT EXISTS upload_usage (
    token_id INTEGER NOT NULL,
    hour INTEGER NOT NULL,
    bytes INTEGER NOT NULL,
    PRIMARY KEY (token_id, hour)
);
";

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
    ("sessions", "venue", "TEXT"),
    ("sessions", "convention", "TEXT NOT NULL DEFAULT 'unity'"),
    // The calibration a session's estimates get, by name (older rows: none).
    ("sessions", "calibration", "TEXT"),
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

impl SqliteStore {
    pub fn open(path: &Path) -> Result<SqliteStore, Error> {
        let conn = Connection::open(path)?;
        conn.busy_timeout(std::time::Duration::from_secs(5))?;
        conn.set_prepared_statement_cache_capacity(STATEMENT_CACHE);
        let mut conn = conn;
        conn.execute_batch(SCHEMA)?;
        migrate(&conn)?;
        // After the columns exist: a database of an older version lacks `sessions.venue`.
        conn.execute_batch(
            "CREATE INDEX IF NOT EXISTS sessions_venue ON sessions (venue) WHERE venue IS NOT NULL",
        )?;
        worker_schema::migrate(&mut conn)?;
        instance_schema::migrate(&mut conn)?;
        deletes::migrate(&mut conn)?;
        Ok(SqliteStore {
            conn: Mutex::new(conn),
        })
    }

    /// Runs `f` on the connection (one at a time: the connection is behind a mutex).
    pub(super) fn with<T>(
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
    pub(super) fn transaction<T>(
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
}

/// A SQLite failure is the store's own: a 500 `database` that names no backend type.
impl From<rusqlite::Error> for Error {
    fn from(e: rusqlite::Error) -> Error {
        Error::Database(e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_store_passes_the_conformance_suite() {
        let dir = tempfile::tempdir().unwrap();
        let store = SqliteStore::open(&dir.path().join("sitar.db")).unwrap();
        crate::storage::conformance::metadata_store(&store);
        crate::storage::worker_conformance::worker_store(&store);
        crate::storage::worker_conformance::only_the_player_takes(&store);
        let racing = SqliteStore::open(&dir.path().join("racing.db")).unwrap();
        crate::storage::worker_conformance::racing_instances(&racing, &racing);
        crate::storage::delete_conformance::unfinished_deletes(&store);
        crate::storage::delete_conformance::racing_sweepers(&racing, &racing);
        // What it stored survives a reopen of the file.
        drop(store);
        let again = SqliteStore::open(&dir.path().join("sitar.db")).unwrap();
        use crate::storage::SessionStore;
        assert!(again.session("s1000000000000005").unwrap().is_some());
    }
}
