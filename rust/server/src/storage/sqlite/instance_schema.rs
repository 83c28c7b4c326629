//! The tables of several instances on one database (`storage/instances.rs`) as versioned
//! migrations, recorded in `schema_versions` under the component `instances` (as
//! `worker_schema` records `workers`): each version's SQL runs once, in order, in one
//! transaction with the version it reaches. It runs after the base schema, so the `sessions`
//! and `jobs` tables exist.

use rusqlite::Connection;

/// The component whose version `schema_versions` keeps for these tables.
const COMPONENT: &str = "instances";

/// Version n is `MIGRATIONS[n - 1]`. Append only: a released version never changes.
const MIGRATIONS: &[&str] = &[
    // 1: instances and their heartbeats; who plays a session and the stop asked of it; which
    // instance runs a job. Postgres has the same in migration 0004_instances.sql.
    "
CREATE TABLE instances (
    id TEXT PRIMARY KEY,
    started_ms INTEGER NOT NULL,
    heartbeat_ms INTEGER NOT NULL
);
ALTER TABLE sessions ADD COLUMN played_by TEXT;
ALTER TABLE sessions ADD COLUMN stop_request TEXT;
CREATE INDEX sessions_played_by ON sessions (played_by) WHERE played_by IS NOT NULL;
ALTER TABLE jobs ADD COLUMN instance TEXT;
",
    // 2: the progress the player publishes for the other instances' status answers
    // (`jobs::progress_view`). Postgres: migration 0005_progress_view.sql.
    "
ALTER TABLE sessions ADD COLUMN progress_view TEXT;
",
];

/// The version these tables are at now.
#[cfg(test)]
pub(super) const LATEST: i64 = MIGRATIONS.len() as i64;

/// Brings the instance tables to the latest version (`MIGRATIONS.len()`); returns the version found.
pub(super) fn migrate(conn: &mut Connection) -> rusqlite::Result<i64> {
    super::component_schema::migrate_component(conn, COMPONENT, MIGRATIONS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_instance_columns_are_added_once_to_an_older_database() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sitar.db");
        let mut conn = Connection::open(&path).unwrap();
        // The tables as an older version left them.
        conn.execute_batch(
            "CREATE TABLE sessions (id TEXT PRIMARY KEY);
             CREATE TABLE jobs (id INTEGER PRIMARY KEY, session_id TEXT NOT NULL);
             INSERT INTO sessions (id) VALUES ('s1');",
        )
        .unwrap();
        assert_eq!(migrate(&mut conn).unwrap(), 0);
        // Again: nothing runs (the ALTERs would fail on a column that exists).
        assert_eq!(migrate(&mut conn).unwrap(), LATEST);
        let played_by: Option<String> = conn
            .query_row("SELECT played_by FROM sessions WHERE id = 's1'", [], |r| {
                r.get(0)
            })
            .unwrap();
        assert_eq!(played_by, None);
        let columns: i64 = conn
            .query_row(
                "SELECT COUNT(*) FROM pragma_table_info('jobs') WHERE name = 'instance'",
                [],
                |r| r.get(0),
            )
            .unwrap();
        assert_eq!(columns, 1);
    }
}
