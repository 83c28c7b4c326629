//! Rows written and read whole for `sitar migrate`: the columns of a table as the database
//! has them, its rows as plain values, and inserts of given rows (ids, states and times as
//! the embedded store had them) in one transaction. A session's rows are born here with the
//! state they had, not `created`: they are copies of sessions another store made, which is
//! why this file (and not `sessions`) writes them.

use postgres::types::ToSql;

use super::PgStore;
use crate::error::Error;
use crate::storage::rows::{Column, Kind, Table, Value};

/// One table's rows to insert: its name, the columns given, the rows.
pub(crate) struct Insert {
    pub table: &'static str,
    pub columns: Vec<Column>,
    pub rows: Vec<Vec<Value>>,
}

/// A value as a parameter of a `kind` column; what cannot be one is named by the caller.
fn param(value: &Value, kind: Kind) -> Result<Box<dyn ToSql + Sync + Send>, String> {
    Ok(match (kind, value) {
        (Kind::Int, Value::Null) => Box::new(None::<i64>),
        (Kind::Int, Value::Int(i)) => Box::new(*i),
        (Kind::Bool, Value::Null) => Box::new(None::<bool>),
        (Kind::Bool, Value::Int(i)) => Box::new(*i != 0),
        (Kind::Real, Value::Null) => Box::new(None::<f64>),
        (Kind::Real, Value::Real(f)) => Box::new(*f),
        (Kind::Real, Value::Int(i)) => Box::new(*i as f64),
        (Kind::Text, Value::Null) => Box::new(None::<String>),
        (Kind::Text, Value::Text(s)) => Box::new(s.clone()),
        (Kind::Bytes, Value::Null) => Box::new(None::<Vec<u8>>),
        (Kind::Bytes, Value::Bytes(b)) => Box::new(b.clone()),
        (Kind::Bytes, Value::Text(s)) => Box::new(s.as_bytes().to_vec()),
        (kind, value) => return Err(format!("{value} cannot be a {kind:?} column")),
    })
}

/// Column `i` of `row` as a plain value.
fn cell(row: &postgres::Row, i: usize, kind: Kind) -> Result<Value, postgres::Error> {
    Ok(match kind {
        Kind::Int => row
            .try_get::<_, Option<i64>>(i)?
            .map_or(Value::Null, Value::Int),
        Kind::Bool => row
            .try_get::<_, Option<bool>>(i)?
            .map_or(Value::Null, |b| Value::Int(b as i64)),
        Kind::Real => row
            .try_get::<_, Option<f64>>(i)?
            .map_or(Value::Null, Value::Real),
        Kind::Text => row
            .try_get::<_, Option<String>>(i)?
            .map_or(Value::Null, Value::Text),
        Kind::Bytes => row
            .try_get::<_, Option<Vec<u8>>>(i)?
            .map_or(Value::Null, Value::Bytes),
    })
}

impl PgStore {
    /// The columns of `table`, in their order; empty when there is no such table.
    pub(crate) fn columns(&self, table: &'static str) -> Result<Vec<Column>, Error> {
        self.pool.run(move |c| {
            c.query(
                "SELECT column_name, data_type, COALESCE(column_default, '') \
                 FROM information_schema.columns \
                 WHERE table_schema = current_schema() AND table_name = $1 \
                 ORDER BY ordinal_position",
                &[&table],
            )?
            .iter()
            .map(|r| {
                let (name, ty, default): (String, String, String) = (r.get(0), r.get(1), r.get(2));
                let kind = match ty.as_str() {
                    "bigint" | "integer" | "smallint" => Kind::Int,
                    "boolean" => Kind::Bool,
                    "double precision" | "real" => Kind::Real,
                    "text" | "character varying" => Kind::Text,
                    "bytea" => Kind::Bytes,
                    other => {
                        return Err(Error::Database(format!(
                            "{table}.{name} is of type {other}, which sitar migrate cannot copy"
                        )));
                    }
                };
                Ok(Column {
                    serial: default.starts_with("nextval("),
                    name,
                    kind,
                })
            })
            .collect()
        })
    }

    /// Every row of `table`, as `columns` (names of [`PgStore::columns`]) give them.
    pub(crate) fn table(&self, table: &'static str, columns: &[Column]) -> Result<Table, Error> {
        let names: Vec<String> = columns.iter().map(|c| c.name.clone()).collect();
        let kinds: Vec<Kind> = columns.iter().map(|c| c.kind).collect();
        let list = names.join(", ");
        let rows = self.pool.run(move |c| {
            let rows = c.query(&format!("SELECT {list} FROM {table}"), &[])?;
            rows.iter()
                .map(|row| {
                    (0..kinds.len())
                        .map(|i| cell(row, i, kinds[i]))
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(Error::from)
                })
                .collect::<Result<Vec<_>, Error>>()
        })?;
        Ok(Table {
            columns: names,
            rows,
        })
    }

    /// Inserts every row of `inserts`, in their order, in one transaction: all or nothing.
    /// A row the database refuses is named by table and row number.
    pub(crate) fn insert_all(&self, inserts: Vec<Insert>) -> Result<(), Error> {
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            for insert in &inserts {
                if insert.rows.is_empty() {
                    continue;
                }
                let names: Vec<&str> = insert.columns.iter().map(|c| c.name.as_str()).collect();
                let marks: Vec<String> = (1..=names.len()).map(|i| format!("${i}")).collect();
                let statement = tx.prepare(&format!(
                    "INSERT INTO {} ({}) VALUES ({})",
                    insert.table,
                    names.join(", "),
                    marks.join(", ")
                ))?;
                for (n, row) in insert.rows.iter().enumerate() {
                    let params = row
                        .iter()
                        .zip(&insert.columns)
                        .map(|(v, c)| param(v, c.kind).map_err(|e| format!("{}: {e}", c.name)))
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(|e| {
                            Error::Database(format!("{} row {}: {e}", insert.table, n + 1))
                        })?;
                    let refs: Vec<&(dyn ToSql + Sync)> =
                        params.iter().map(|p| &**p as &(dyn ToSql + Sync)).collect();
                    tx.execute(&statement, &refs)
                        .map_err(|e| match Error::from(e) {
                            Error::Database(why) => {
                                Error::Database(format!("{} row {}: {why}", insert.table, n + 1))
                            }
                            other => other,
                        })?;
                }
            }
            tx.commit()?;
            Ok(())
        })
    }

    /// Moves the sequence behind `table.column` past `at_least` (and past every id in the
    /// table), never back: an id handed out once is never handed out again.
    pub(crate) fn raise_sequence(
        &self,
        table: &'static str,
        column: String,
        at_least: i64,
    ) -> Result<(), Error> {
        self.pool.run(move |c| {
            let sequence: Option<String> = c
                .query_one("SELECT pg_get_serial_sequence($1, $2)", &[&table, &column])?
                .get(0);
            let Some(sequence) = sequence else {
                return Ok(());
            };
            c.execute(
                &format!(
                    "SELECT setval('{sequence}', GREATEST($1::BIGINT, \
                     (SELECT COALESCE(MAX({column}), 0) FROM {table}), \
                     (SELECT last_value FROM {sequence})))"
                ),
                &[&at_least],
            )?;
            Ok(())
        })
    }
}
