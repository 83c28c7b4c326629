//! The Postgres schema, versioned: each migration is applied once, in order, at start, and
//! recorded in `schema_migrations`. Instances starting together take turns (a transaction-
//! scoped advisory lock), so each migration runs exactly once. A database a newer sitar
//! migrated further is refused, naming both versions.

use postgres::Client;

use crate::error::Error;
use crate::storage::now_ms;

/// Every migration, in order: (version, name, SQL). Never edit one that shipped; add the next.
const MIGRATIONS: &[(i64, &str, &str)] = &[
    (1, "tables", include_str!("migrations/0001_tables.sql")),
    (2, "venues", include_str!("migrations/0002_venues.sql")),
    (3, "workers", include_str!("migrations/0003_workers.sql")),
    (
        4,
        "instances",
        include_str!("migrations/0004_instances.sql"),
    ),
    (
        5,
        "progress_view",
        include_str!("migrations/0005_progress_view.sql"),
    ),
    (
        6,
        "calibration",
        include_str!("migrations/0006_calibration.sql"),
    ),
    (
        7,
        "venue_contributions",
        include_str!("migrations/0007_venue_contributions.sql"),
    ),
    (
        8,
        "unfinished_deletes",
        include_str!("migrations/0008_unfinished_deletes.sql"),
    ),
];

/// The advisory lock key the migrating instance holds (`sitar` in ASCII).
const MIGRATION_LOCK: i64 = 0x0073_6974_6172;

/// Applies the migrations `client`'s database lacks; returns how many it applied.
pub(super) fn migrate(client: &mut Client) -> Result<usize, Error> {
    let mut tx = client.transaction()?;
    tx.execute("SELECT pg_advisory_xact_lock($1)", &[&MIGRATION_LOCK])?;
    tx.batch_execute(
        "CREATE TABLE IF NOT EXISTS schema_migrations (
             version BIGINT PRIMARY KEY,
             name TEXT NOT NULL,
             applied_ms BIGINT NOT NULL
         )",
    )?;
    let current: i64 = tx
        .query_one(
            "SELECT COALESCE(MAX(version), 0) FROM schema_migrations",
            &[],
        )?
        .get(0);
    let known = MIGRATIONS.last().map_or(0, |m| m.0);
    if current > known {
        return Err(Error::Config(format!(
            "the database's schema is at version {current}, newer than this sitar knows \
             ({known}): run the newer sitar"
        )));
    }
    let mut applied = 0;
    for (version, name, sql) in MIGRATIONS.iter().filter(|m| m.0 > current) {
        tx.batch_execute(sql).map_err(|e| {
            Error::Database(format!("migration {version} ({name}): {}", Error::from(e)))
        })?;
        tx.execute(
            "INSERT INTO schema_migrations (version, name, applied_ms) VALUES ($1, $2, $3)",
            &[version, name, &now_ms()],
        )?;
        log::info!("database: applied migration {version} ({name})");
        applied += 1;
    }
    tx.commit()?;
    Ok(applied)
}

/// Every schema version this sitar knows, in order (numbers are never reused, so a version
/// may be missing from a branch that has not merged it yet).
#[cfg(test)]
pub(super) fn versions() -> Vec<i64> {
    MIGRATIONS.iter().map(|m| m.0).collect()
}
