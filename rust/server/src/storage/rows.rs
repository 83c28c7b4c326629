//! Rows as plain values, for `sitar migrate`: the embedded store's tables read whole and
//! written into the cluster store's, compared column by column. No SQL here; the two stores
//! read and write them (`sqlite::export`, `postgres::copy`). The columns come from the tables
//! themselves, so a column a later version adds is copied without a change here.

use std::fmt;

/// One cell.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Value {
    Null,
    Int(i64),
    Real(f64),
    Text(String),
    Bytes(Vec<u8>),
}

/// A column's type in the cluster store (`information_schema.columns.data_type`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    Int,
    /// Kept as 0/1 in SQLite (`sessions.legacy`).
    Bool,
    Real,
    Text,
    Bytes,
}

/// A column of the cluster store's table.
#[derive(Debug, Clone)]
pub(crate) struct Column {
    pub name: String,
    pub kind: Kind,
    /// Filled from a sequence when not given (`BIGSERIAL`).
    pub serial: bool,
}

/// A table read whole: its column names and rows (each as long as `columns`).
#[derive(Debug, Clone, Default)]
pub(crate) struct Table {
    pub columns: Vec<String>,
    pub rows: Vec<Vec<Value>>,
}

/// What `sitar migrate` copies of one table, and how a row is known.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TableSpec {
    pub name: &'static str,
    /// The columns that name a row (every column when empty: a ledger without a key).
    pub key: &'static [&'static str],
    /// The column holding the session a row belongs to: copied with that session.
    pub session: Option<&'static str>,
    /// Columns the cluster may change by serving (never compared).
    pub volatile: &'static [&'static str],
    /// Columns whose values are secrets or hashes of them: never printed.
    pub secret: &'static [&'static str],
}

/// The tables copied, in the order they are written (a row's references first). Left out:
/// `devices` (the phones on this host's USB; the cluster's hosts report their own) and the
/// worker tables (hosts, leases, failed-trial notes: each instance's own) and
/// `venue_contributions` (kept venue-map contributions: computed again on first use).
pub(crate) const COPIED: &[TableSpec] = &[
    TableSpec {
        name: "tokens",
        key: &["id"],
        session: None,
        volatile: &["last_used_ms"],
        secret: &["lookup", "hash"],
    },
    TableSpec {
        name: "venues",
        key: &["id"],
        session: None,
        volatile: &[],
        secret: &[],
    },
    TableSpec {
        name: "venue_members",
        key: &["venue_id", "token_id"],
        session: None,
        volatile: &[],
        secret: &[],
    },
    TableSpec {
        name: "session_creations",
        key: &[],
        session: None,
        volatile: &[],
        secret: &[],
    },
    TableSpec {
        name: "upload_usage",
        key: &["token_id", "hour"],
        session: None,
        volatile: &[],
        secret: &[],
    },
    TableSpec {
        name: "sessions",
        key: &["id"],
        session: Some("id"),
        volatile: &[],
        secret: &[],
    },
    TableSpec {
        name: "trials",
        key: &["session_id", "idx"],
        session: Some("session_id"),
        volatile: &[],
        secret: &[],
    },
    TableSpec {
        name: "jobs",
        key: &["id"],
        session: Some("session_id"),
        volatile: &[],
        secret: &[],
    },
    TableSpec {
        name: "share_links",
        key: &["hash"],
        session: Some("session_id"),
        volatile: &[],
        secret: &["lookup", "hash"],
    },
];

impl Value {
    /// The value as a column of `kind` holds it, for comparing the two stores' rows
    /// (SQLite keeps booleans as integers and may keep a whole REAL as an integer).
    pub(crate) fn canonical(&self, kind: Kind) -> Value {
        match (kind, self) {
            (Kind::Real, Value::Int(i)) => Value::Real(*i as f64),
            (Kind::Bytes, Value::Text(s)) => Value::Bytes(s.as_bytes().to_vec()),
            _ => self.clone(),
        }
    }

    /// How a message shows it: text quoted and cut short, bytes by length only.
    pub(crate) fn shown(&self, secret: bool) -> String {
        match self {
            _ if secret => "(hidden)".into(),
            Value::Null => "NULL".into(),
            Value::Int(i) => i.to_string(),
            Value::Real(f) => f.to_string(),
            Value::Text(s) if s.chars().count() > 60 => {
                format!("{:?}…", s.chars().take(60).collect::<String>())
            }
            Value::Text(s) => format!("{s:?}"),
            Value::Bytes(b) => format!("({} bytes)", b.len()),
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.shown(false))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_compare_as_the_cluster_column_holds_them() {
        assert_eq!(Value::Int(2).canonical(Kind::Real), Value::Real(2.0));
        assert_eq!(Value::Int(1).canonical(Kind::Bool), Value::Int(1));
        assert_eq!(
            Value::Text("ab".into()).canonical(Kind::Bytes),
            Value::Bytes(b"ab".to_vec())
        );
        assert_ne!(Value::Int(2).canonical(Kind::Int), Value::Real(2.0));
    }

    #[test]
    fn secrets_and_long_texts_are_not_shown_whole() {
        assert_eq!(Value::Bytes(vec![1, 2, 3]).shown(false), "(3 bytes)");
        assert_eq!(Value::Text("sitar_secret".into()).shown(true), "(hidden)");
        let long = Value::Text("x".repeat(100)).shown(false);
        assert!(long.len() < 70 && long.ends_with('…'), "{long}");
    }

    #[test]
    fn every_copied_table_has_a_distinct_name_and_sessions_come_before_their_rows() {
        let names: Vec<_> = COPIED.iter().map(|t| t.name).collect();
        let unique: std::collections::BTreeSet<_> = names.iter().collect();
        assert_eq!(unique.len(), names.len());
        let at = |n: &str| names.iter().position(|x| *x == n).unwrap();
        assert!(at("tokens") < at("venue_members") && at("venues") < at("venue_members"));
        assert!(at("sessions") < at("trials") && at("sessions") < at("jobs"));
    }
}
