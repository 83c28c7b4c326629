//! `sitar migrate`: an embedded installation (the data directory's SQLite database and
//! session folders) copied into the cluster stores (Postgres and an S3-compatible bucket),
//! verified, and safe to run again.
//!
//! The order makes a rerun after an interruption correct: the tables that belong to no
//! session first (tokens, venues and their members, the per-token usage counters), in one
//! transaction; then session by session, its objects (each hashed on both sides, stored when
//! the bucket lacks it) and then its rows (the session, its trials, jobs and share links) in
//! one transaction. A session whose row the database holds was therefore copied whole; one
//! whose row it lacks is copied again, its objects compared first so what arrived before is
//! not sent twice. Before anything is written, every table is compared: a row the database
//! holds under the same key with other values is another installation's data, and the copy
//! is refused naming it. At the end every table and object is compared again ([`Summary`]).
//!
//! Ids, hashes, states and times are copied as they are, so tokens keep working (only their
//! hashes are stored) and the sequences behind ids are moved past every id the embedded
//! store ever handed out (a revoked token's id is never reused).

mod files;
mod rows;
mod summary;

use std::collections::{HashMap, HashSet};
use std::path::PathBuf;

use crate::error::Error;
use crate::storage::installation::Installation;
use crate::storage::postgres::PgStore;
use crate::storage::postgres::copy::Insert;
use crate::storage::rows::{COPIED, Value};

pub use summary::{Summary, TableCount};

/// Where `sitar migrate` copies from and to.
#[derive(Debug, Clone)]
pub struct MigrateOptions {
    /// The embedded installation's data directory (`sitar serve --data DIR`).
    pub data: PathBuf,
    /// The Postgres database (`postgres://…`; the `PG*` variables fill in the rest).
    pub database: String,
    /// The bucket (`s3://BUCKET/PREFIX`; endpoint and credentials from the `AWS_*` variables).
    pub store: String,
}

/// Copies the installation at `options.data` into the cluster stores and verifies the
/// copy; `progress` gets one line per step. Refused (an error naming why, nothing written)
/// while a server runs on the folder or when the database holds other data under the same
/// keys. Differences found at the end are in the summary ([`Summary::verified`]).
pub fn migrate(options: &MigrateOptions, progress: &mut dyn FnMut(&str)) -> Result<Summary, Error> {
    let source = Installation::open(&options.data)?;
    let outcome = run(&source, options, progress);
    source.close();
    outcome
}

/// The rows of `compared` that the database lacks, as an insert (those of `session` only,
/// for a table copied with its sessions).
fn missing(compared: &rows::Compared, session: Option<&str>) -> Insert {
    let rows = compared
        .rows
        .iter()
        .zip(&compared.present)
        .filter(|(row, present)| {
            !**present && session.is_none_or(|s| compared.session_of(row).as_deref() == Some(s))
        })
        .map(|(row, _)| row.clone())
        .collect();
    Insert {
        table: compared.spec.name,
        columns: compared.columns.clone(),
        rows,
    }
}

/// Moves the database's sequences past every id of `compared` (and past the embedded
/// store's own counter, which remembers deleted rows).
fn raise_sequences(
    source: &Installation,
    db: &PgStore,
    compared: &rows::Compared,
) -> Result<(), Error> {
    for (i, column) in compared.columns.iter().enumerate() {
        if !column.serial {
            continue;
        }
        let highest = compared
            .rows
            .iter()
            .filter_map(|r| match r[i] {
                Value::Int(v) => Some(v),
                _ => None,
            })
            .max()
            .unwrap_or(0)
            .max(source.db.last_id(compared.spec.name)?);
        db.raise_sequence(compared.spec.name, column.name.clone(), highest)?;
    }
    Ok(())
}

fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1u64 << 20) as f64)
}

fn run(
    source: &Installation,
    options: &MigrateOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<Summary, Error> {
    let (db, blobs) = source.open_target(&options.database, &options.store)?;
    let compare_all = || -> Result<Vec<rows::Compared>, Error> {
        COPIED
            .iter()
            .map(|spec| rows::compare(*spec, source, &db))
            .collect()
    };
    let compared = compare_all()?;
    let conflicts: Vec<&String> = compared.iter().flat_map(|c| &c.conflicts).collect();
    if !conflicts.is_empty() {
        let shown: Vec<&str> = conflicts.iter().take(20).map(|s| s.as_str()).collect();
        return Err(Error::Conflict(format!(
            "the database holds other data than {} under the same keys ({} rows; nothing was \
             copied; migrate into an empty database, or into the one an earlier run of this \
             copy wrote):\n  {}",
            options.data.display(),
            conflicts.len(),
            shown.join("\n  ")
        )));
    }
    let mut copied_rows: HashMap<&'static str, usize> = HashMap::new();

    // The tables that belong to no session, in one transaction.
    let global: Vec<Insert> = compared
        .iter()
        .filter(|c| c.spec.session.is_none())
        .map(|c| missing(c, None))
        .collect();
    for insert in &global {
        *copied_rows.entry(insert.table).or_default() += insert.rows.len();
    }
    let global_rows: usize = global.iter().map(|i| i.rows.len()).sum();
    db.insert_all(global)?;
    for c in compared.iter().filter(|c| c.spec.session.is_none()) {
        raise_sequences(source, &db, c)?;
    }
    progress(&format!("tokens, venues, usage: {global_rows} rows copied"));

    // Session by session: objects, then rows.
    let sessions = compared
        .iter()
        .find(|c| c.spec.name == "sessions")
        .ok_or_else(|| Error::Internal("no sessions table in the copy list".into()))?;
    let id_at = sessions
        .index("id")
        .ok_or_else(|| Error::Internal("sessions has no id column".into()))?;
    let ids: Vec<(String, bool)> = sessions
        .rows
        .iter()
        .zip(&sessions.present)
        .filter_map(|(row, present)| match &row[id_at] {
            Value::Text(id) if crate::storage::installation::is_server_id(id) => {
                Some((id.clone(), *present))
            }
            _ => None,
        })
        .collect();
    let known: HashSet<&str> = ids.iter().map(|(id, _)| id.as_str()).collect();
    let mut summary = Summary {
        sessions: ids.len(),
        ..Default::default()
    };
    for (n, (id, present)) in ids.iter().enumerate() {
        let objects = source.objects(id)?;
        let bytes: u64 = objects.found.iter().map(|(_, len)| len).sum();
        progress(&format!(
            "session {id} ({}/{}): {} files, {}",
            n + 1,
            ids.len(),
            objects.found.len(),
            mib(bytes)
        ));
        let copied = files::copy_session(source, &blobs, id, *present)?;
        summary.files += copied.objects;
        summary.bytes += copied.bytes;
        summary.files_copied += copied.copied;
        summary.bytes_copied += copied.copied_bytes;
        summary.differences.extend(copied.differences);
        summary.left_behind.extend(
            copied
                .unknown
                .into_iter()
                .map(|f| format!("{f}: no object sitar keeps")),
        );
        let inserts: Vec<Insert> = compared
            .iter()
            .filter(|c| c.spec.session.is_some())
            .map(|c| missing(c, Some(id)))
            .collect();
        for insert in &inserts {
            *copied_rows.entry(insert.table).or_default() += insert.rows.len();
        }
        db.insert_all(inserts)?;
    }
    for c in compared.iter().filter(|c| c.spec.session.is_some()) {
        raise_sequences(source, &db, c)?;
        let orphans = c
            .rows
            .iter()
            .filter(|r| c.session_of(r).is_none_or(|s| !known.contains(s.as_str())))
            .count();
        if orphans > 0 {
            summary.left_behind.push(format!(
                "{orphans} rows of {} belong to no session of the embedded store",
                c.spec.name
            ));
        }
    }
    for folder in source.folders()? {
        if !known.contains(folder.as_str()) {
            summary
                .left_behind
                .push(format!("sessions/{folder}/: a folder of no session"));
        }
    }

    // Verification: every table read again from both sides.
    progress("verifying: every table read again from both sides");
    for c in compare_all()? {
        summary.differences.extend(c.conflicts.iter().cloned());
        let orphan = |r: &Vec<Value>| {
            c.spec.session.is_some() && c.session_of(r).is_none_or(|s| !known.contains(s.as_str()))
        };
        let copyable: Vec<bool> = c.rows.iter().map(|r| !orphan(r)).collect();
        summary.tables.push(TableCount {
            table: c.spec.name,
            rows: copyable.iter().filter(|x| **x).count(),
            copied: copied_rows.get(c.spec.name).copied().unwrap_or(0),
            equal: c
                .present
                .iter()
                .zip(&copyable)
                .filter(|(p, k)| **p && **k)
                .count(),
            in_database: c.target_rows,
        });
    }
    Ok(summary)
}
