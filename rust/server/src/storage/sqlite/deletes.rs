//! Unfinished deletes in SQLite (`storage/deletes.rs`), as a versioned component of their
//! own in `schema_versions` (`deletes`). One connection behind a mutex: a claim is atomic
//! with any other statement.

use rusqlite::{Transaction, params};

use super::{CachedSql, SqliteStore};
use crate::error::Error;
use crate::storage::deletes::{Claim, DeleteStore};
use crate::storage::now_ms;

/// The component whose version `schema_versions` keeps for these tables.
const COMPONENT: &str = "deletes";

/// Version n is `MIGRATIONS[n - 1]`. Append only: a released version never changes.
const MIGRATIONS: &[&str] = &[
    // 1: a deleted session whose bytes are still to be removed, and who does it until when.
    // Postgres: migration 0008_unfinished_deletes.sql.
    "
CREATE TABLE unfinished_deletes (
    session_id TEXT PRIMARY KEY,
    deleted_ms INTEGER NOT NULL,
    claimed_by TEXT NOT NULL,
    claimed_until_ms INTEGER NOT NULL
);
",
];

/// Brings these tables to the latest version; returns the version found.
pub(super) fn migrate(conn: &mut rusqlite::Connection) -> rusqlite::Result<i64> {
    super::component_schema::migrate_component(conn, COMPONENT, MIGRATIONS)
}

/// Records session `id`'s bytes as still to remove, inside the transaction deleting its row.
pub(super) fn record(tx: &Transaction<'_>, id: &str, claim: Claim<'_>) -> Result<(), Error> {
    tx.execute_cached(
        "INSERT INTO unfinished_deletes (session_id, deleted_ms, claimed_by, claimed_until_ms) \
         VALUES (?1, ?2, ?3, ?4) ON CONFLICT (session_id) DO NOTHING",
        params![id, now_ms(), claim.instance, claim.until_ms],
    )?;
    Ok(())
}

impl DeleteStore for SqliteStore {
    fn claim_unfinished_deletes(
        &self,
        claim: Claim<'_>,
        now_ms: i64,
        limit: u32,
    ) -> Result<Vec<String>, Error> {
        self.transaction(|tx| {
            let mut ids: Vec<String> = tx
                .prepare_cached(
                    "SELECT session_id FROM unfinished_deletes WHERE claimed_until_ms < ?1 \
                     ORDER BY deleted_ms, session_id LIMIT ?2",
                )?
                .query_map(params![now_ms, limit], |r| r.get(0))?
                .collect::<rusqlite::Result<_>>()?;
            for id in &ids {
                tx.execute_cached(
                    "UPDATE unfinished_deletes SET claimed_by = ?2, claimed_until_ms = ?3 \
                     WHERE session_id = ?1",
                    params![id, claim.instance, claim.until_ms],
                )?;
            }
            ids.sort();
            Ok(ids)
        })
    }

    fn finish_delete(&self, id: &str) -> Result<(), Error> {
        self.with(|c| {
            c.execute_cached("DELETE FROM unfinished_deletes WHERE session_id = ?1", [id])
        })
        .map(drop)
    }

    #[cfg(test)]
    fn unfinished_deletes(&self) -> Result<Vec<String>, Error> {
        self.with(|c| {
            c.prepare_cached("SELECT session_id FROM unfinished_deletes ORDER BY session_id")?
                .query_map([], |r| r.get(0))?
                .collect()
        })
    }
}
