//! Versioned migrations of a component's tables (the worker store's, the instances'), recorded
//! in `schema_versions` under the component's name, so components never collide: each
//! version's SQL runs once, in order, in one transaction with the version it reaches.

use rusqlite::Connection;

/// Brings `component`'s tables to version `migrations.len()` (version n is
/// `migrations[n - 1]`); returns the version found.
pub(super) fn migrate_component(
    conn: &mut Connection,
    component: &str,
    migrations: &[&str],
) -> rusqlite::Result<i64> {
    conn.execute_batch(
        "CREATE TABLE IF NOT EXISTS schema_versions (
            component TEXT PRIMARY KEY,
            version INTEGER NOT NULL
        )",
    )?;
    let found: i64 = conn.query_row(
        "SELECT COALESCE(MAX(version), 0) FROM schema_versions WHERE component = ?1",
        [component],
        |r| r.get(0),
    )?;
    for (at, sql) in migrations.iter().enumerate().skip(found.max(0) as usize) {
        let version = at as i64 + 1;
        let tx = conn.transaction()?;
        tx.execute_batch(sql)?;
        tx.execute(
            "INSERT INTO schema_versions (component, version) VALUES (?1, ?2) \
             ON CONFLICT (component) DO UPDATE SET version = excluded.version",
            rusqlite::params![component, version],
        )?;
        tx.commit()?;
        log::info!("database: {component} tables at version {version}");
    }
    Ok(found)
}
