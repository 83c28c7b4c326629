//! The rows of one table on both sides: which of the embedded store's rows the database
//! holds already (equal), which it lacks, and which it holds differently (other data: the
//! copy is refused). Rows are known by their key columns ([`TableSpec::key`]).

use std::collections::HashMap;

use crate::error::Error;
use crate::storage::installation::Installation;
use crate::storage::postgres::PgStore;
use crate::storage::rows::{Column, TableSpec, Value};

/// One table compared.
pub(crate) struct Compared {
    pub spec: TableSpec,
    /// The database's columns the embedded table also has, in the embedded table's order.
    pub columns: Vec<Column>,
    /// The embedded rows, as those columns hold them.
    pub rows: Vec<Vec<Value>>,
    /// Per embedded row: whether the database holds it equal.
    pub present: Vec<bool>,
    /// Rows the database holds differently, described.
    pub conflicts: Vec<String>,
    /// Rows in the database's table.
    pub target_rows: usize,
}

impl Compared {
    /// Where column `name` is in [`Compared::columns`].
    pub(crate) fn index(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c.name == name)
    }

    /// The session row `row` belongs to, for tables copied with their session.
    pub(crate) fn session_of(&self, row: &[Value]) -> Option<String> {
        let at = self.index(self.spec.session?)?;
        match &row[at] {
            Value::Text(id) => Some(id.clone()),
            _ => None,
        }
    }

    /// How a message names row `row`: its key, secrets hidden.
    pub(crate) fn describe(&self, row: &[Value]) -> String {
        let key: Vec<String> = key_columns(&self.spec, &self.columns)
            .into_iter()
            .map(|i| {
                let name = &self.columns[i].name;
                let secret = self.spec.secret.contains(&name.as_str());
                format!("{name}={}", row[i].shown(secret))
            })
            .collect();
        let mut text = format!("{} row {}", self.spec.name, key.join(", "));
        if let Some(session) = self
            .session_of(row)
            .filter(|_| self.spec.name != "sessions")
        {
            text.push_str(&format!(" (session {session})"));
        }
        text
    }
}

/// The positions of `spec`'s key columns among `columns` (every column for a table
/// without a key).
fn key_columns(spec: &TableSpec, columns: &[Column]) -> Vec<usize> {
    if spec.key.is_empty() {
        return (0..columns.len()).collect();
    }
    spec.key
        .iter()
        .filter_map(|k| columns.iter().position(|c| c.name == *k))
        .collect()
}

/// A row's key as text (values are compared as the database holds them).
fn key_of(row: &[Value], key: &[usize]) -> String {
    key.iter()
        .map(|&i| format!("{:?}", row[i]))
        .collect::<Vec<_>>()
        .join("\u{1f}")
}

/// Compares table `spec` of the embedded store with the database's.
pub(crate) fn compare(
    spec: TableSpec,
    source: &Installation,
    db: &PgStore,
) -> Result<Compared, Error> {
    let table = if source.db.has_table(spec.name)? {
        source.db.table(spec.name)?
    } else {
        Default::default()
    };
    let target_columns = db.columns(spec.name)?;
    if target_columns.is_empty() {
        return Err(Error::Database(format!(
            "the database has no table {}: is it the database of `sitar serve --database`?",
            spec.name
        )));
    }
    let mut columns = Vec::new();
    for name in &table.columns {
        match target_columns.iter().find(|c| &c.name == name) {
            Some(c) => columns.push(c.clone()),
            None => {
                return Err(Error::Database(format!(
                    "the embedded table {}.{name} has no column in the database: its sitar is \
                     older than the one that wrote the data directory (start the newer \
                     `sitar serve --database` once to migrate it)",
                    spec.name
                )));
            }
        }
    }
    let rows: Vec<Vec<Value>> = table
        .rows
        .iter()
        .map(|row| {
            row.iter()
                .zip(&columns)
                .map(|(v, c)| v.canonical(c.kind))
                .collect()
        })
        .collect();
    let target = db.table(spec.name, &columns)?;
    let key = key_columns(&spec, &columns);
    // Several equal rows are possible in a table without a key: counted.
    let mut held: HashMap<String, Vec<usize>> = HashMap::new();
    for (n, row) in target.rows.iter().enumerate() {
        held.entry(key_of(row, &key)).or_default().push(n);
    }
    let compared_columns: Vec<usize> = (0..columns.len())
        .filter(|&i| !spec.volatile.contains(&columns[i].name.as_str()))
        .collect();
    let mut compared = Compared {
        spec,
        columns,
        present: Vec::with_capacity(rows.len()),
        conflicts: Vec::new(),
        target_rows: target.rows.len(),
        rows: Vec::new(),
    };
    for row in &rows {
        let Some(matches) = held.get_mut(&key_of(row, &key)) else {
            compared.present.push(false);
            continue;
        };
        let Some(n) = matches.pop() else {
            compared.present.push(false);
            continue;
        };
        let theirs = &target.rows[n];
        let differing: Vec<String> = compared_columns
            .iter()
            .filter(|&&i| row[i] != theirs[i])
            .map(|&i| {
                let name = &compared.columns[i].name;
                let secret = spec.secret.contains(&name.as_str());
                format!(
                    "{name} is {} here but {} in the database",
                    row[i].shown(secret),
                    theirs[i].shown(secret)
                )
            })
            .collect();
        if differing.is_empty() {
            compared.present.push(true);
        } else {
            compared.present.push(false);
            compared.conflicts.push(format!(
                "{}: {}",
                compared.describe(row),
                differing.join("; ")
            ));
        }
    }
    compared.rows = rows;
    Ok(compared)
}
