//! The worker store's tables (`storage/workers.rs`), as versioned migrations: each version's
//! SQL runs once, in order, in one transaction with the version it reaches, recorded in
//! `schema_versions` under the component `workers` (other components keep their own
//! versions there, so this one never collides with them).

use rusqlite::Connection;

/// The component whose version `schema_versions` keeps for these tables.
const COMPONENT: &str = "workers";

/// Version n is `MIGRATIONS[n - 1]`. Append only: a released version never changes.
const MIGRATIONS: &[&str] = &[
    // 1: hosts, phones, offered trials and their leases, owners' turns, failed trials.
    "
CREATE TABLE worker_hosts (
    id TEXT PRIMARY KEY,
    token_id INTEGER NOT NULL,
    name TEXT NOT NULL,
    playback TEXT NOT NULL,
    registered_ms INTEGER NOT NULL,
    last_seen_ms INTEGER NOT NULL,
    UNIQUE (token_id, name)
);
CREATE TABLE worker_phones (
    host_id TEXT NOT NULL REFERENCES worker_hosts(id),
    serial TEXT NOT NULL,
    state TEXT NOT NULL,
    failures INTEGER NOT NULL DEFAULT 0,
    last_error TEXT,
    PRIMARY KEY (host_id, serial)
);
CREATE TABLE trial_leases (
    session_id TEXT NOT NULL,
    play_index INTEGER NOT NULL,
    owner_key TEXT NOT NULL,
    playback TEXT NOT NULL,
    recording_sha256 TEXT NOT NULL,
    offered_seq INTEGER NOT NULL,
    state TEXT NOT NULL,
    attempts INTEGER NOT NULL DEFAULT 0,
    lease_id TEXT UNIQUE,
    host_id TEXT,
    phone TEXT,
    expires_ms INTEGER,
    PRIMARY KEY (session_id, play_index)
);
CREATE INDEX trial_leases_pending ON trial_leases (state, playback, owner_key, offered_seq);
CREATE TABLE lease_turns (
    owner_key TEXT PRIMARY KEY,
    served_seq INTEGER NOT NULL
);
CREATE TABLE trial_failures (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    session_id TEXT NOT NULL,
    play_index INTEGER NOT NULL,
    source TEXT NOT NULL,
    error TEXT NOT NULL,
    at_ms INTEGER NOT NULL
);
CREATE INDEX trial_failures_session ON trial_failures (session_id, id);
",
    // 2: a committed trial's text travels with its lease until its session's job takes it.
    "
ALTER TABLE trial_leases ADD COLUMN trial_text TEXT;
ALTER TABLE trial_leases ADD COLUMN trial_source TEXT;
ALTER TABLE trial_leases ADD COLUMN taken INTEGER NOT NULL DEFAULT 0;
UPDATE trial_leases SET taken = 1 WHERE state = 'done';
",
];

/// The version these tables are at now.
#[cfg(test)]
pub(super) const LATEST: i64 = MIGRATIONS.len() as i64;

/// Brings the worker tables to the latest version (`MIGRATIONS.len()`); returns the version found.
pub(super) fn migrate(conn: &mut Connection) -> rusqlite::Result<i64> {
    super::component_schema::migrate_component(conn, COMPONENT, MIGRATIONS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn migrations_run_once_and_record_their_version() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sitar.db");
        let mut conn = Connection::open(&path).unwrap();
        assert_eq!(migrate(&mut conn).unwrap(), 0);
        // A second open finds the latest version and runs nothing (the CREATEs would fail).
        assert_eq!(migrate(&mut conn).unwrap(), LATEST);
        let mut again = Connection::open(&path).unwrap();
        assert_eq!(migrate(&mut again).unwrap(), LATEST);
        let tables: i64 = again
            .query_row(
                "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table' AND name IN \
                 ('worker_hosts', 'worker_phones', 'trial_leases', 'lease_turns', 'trial_failures')",
                [],
                |r| r.get(0),
            )
            .unwrap();
        assert_eq!(tables, 5);
    }
}
