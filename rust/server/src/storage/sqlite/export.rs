//! The embedded database read whole for `sitar migrate`, under SQLite's own lock: the file is
//! opened in `locking_mode=EXCLUSIVE` and a write transaction taken at once, which SQLite
//! refuses while any other process has the database open in WAL mode (a running `sitar
//! serve` keeps its connection open for its whole life). Held until the copy ends, the lock
//! also keeps a server from starting on the folder meanwhile (its open waits, then fails
//! with "database is locked"). A process killed with SIGKILL leaves no lock behind: the
//! operating system drops its file locks.

use std::path::Path;

use rusqlite::types::ValueRef;
use rusqlite::{Connection, ErrorCode, OpenFlags};

use crate::error::Error;
use crate::storage::rows::{Table, Value};

/// The embedded database of a data directory, locked against every other process.
pub(crate) struct SqliteSource {
    conn: Connection,
}

impl SqliteSource {
    /// Opens `path` (which must exist) and takes the exclusive lock; a server running on it
    /// is an error saying so.
    pub(crate) fn open(path: &Path) -> Result<SqliteSource, Error> {
        if !path.is_file() {
            return Err(Error::Config(format!(
                "{}: no embedded database here (`sitar serve --data DIR` makes DIR/sitar.db)",
                path.display()
            )));
        }
        let conn = Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_WRITE)?;
        conn.busy_timeout(std::time::Duration::ZERO)?;
        let locked = conn
            .pragma_update(None, "locking_mode", "EXCLUSIVE")
            .and_then(|()| conn.execute_batch("BEGIN EXCLUSIVE; COMMIT;"));
        match locked {
            Ok(()) => Ok(SqliteSource { conn }),
            Err(rusqlite::Error::SqliteFailure(e, _))
                if matches!(e.code, ErrorCode::DatabaseBusy | ErrorCode::DatabaseLocked) =>
            {
                Err(Error::Conflict(format!(
                    "{} is in use: a server (or another sitar migrate) runs on this data \
                     directory; stop it first (the embedded store has no other lock than \
                     SQLite's own, which a running server holds)",
                    path.display()
                )))
            }
            Err(e) => Err(e.into()),
        }
    }

    /// Whether table `name` exists (an old database may lack a later version's tables).
    pub(crate) fn has_table(&self, name: &str) -> Result<bool, Error> {
        Ok(self
            .conn
            .prepare("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?1")?
            .exists([name])?)
    }

    /// Every row of table `name` (one of the names `rows::COPIED` lists), in insertion order.
    pub(crate) fn table(&self, name: &str) -> Result<Table, Error> {
        debug_assert!(name.bytes().all(|b| b.is_ascii_lowercase() || b == b'_'));
        let mut statement = self
            .conn
            .prepare(&format!("SELECT * FROM {name} ORDER BY rowid"))?;
        let columns: Vec<String> = statement
            .column_names()
            .iter()
            .map(|c| c.to_string())
            .collect();
        let width = columns.len();
        let rows = statement
            .query_map([], |row| {
                (0..width)
                    .map(|i| {
                        Ok(match row.get_ref(i)? {
                            ValueRef::Null => Value::Null,
                            ValueRef::Integer(v) => Value::Int(v),
                            ValueRef::Real(v) => Value::Real(v),
                            ValueRef::Text(t) => {
                                Value::Text(String::from_utf8_lossy(t).into_owned())
                            }
                            ValueRef::Blob(b) => Value::Bytes(b.to_vec()),
                        })
                    })
                    .collect::<rusqlite::Result<Vec<Value>>>()
            })?
            .collect::<rusqlite::Result<Vec<_>>>()?;
        Ok(Table { columns, rows })
    }

    /// The last id an `AUTOINCREMENT` table handed out (ids of deleted rows included), so
    /// the cluster never hands out one again: a revoked token's id stays unused.
    pub(crate) fn last_id(&self, table: &str) -> Result<i64, Error> {
        let found = self.conn.query_row(
            "SELECT seq FROM sqlite_sequence WHERE name = ?1",
            [table],
            |r| r.get::<_, i64>(0),
        );
        match found {
            Ok(seq) => Ok(seq),
            Err(rusqlite::Error::QueryReturnedNoRows) => Ok(0),
            // No AUTOINCREMENT table was ever written: no sqlite_sequence table.
            Err(rusqlite::Error::SqliteFailure(_, Some(m))) if m.contains("no such table") => Ok(0),
            Err(e) => Err(e.into()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_database_another_process_holds_open_is_refused_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sitar.db");
        let missing = SqliteSource::open(&path).err().unwrap().to_string();
        assert!(missing.contains("no embedded database"), "{missing}");
        // A server's connection (the store opens in WAL mode and stays open).
        let server = crate::storage::sqlite::SqliteStore::open(&path).unwrap();
        use crate::storage::TokenStore;
        server
            .insert_token(
                "a",
                crate::model::Role::App,
                "sitar_exportAAAAAAAAAAAAAAAAAAAAAAAA",
            )
            .unwrap();
        // A running server's refusal needs another process: the CLI test checks it.
        drop(server);
        let source = SqliteSource::open(&path).unwrap();
        let tokens = source.table("tokens").unwrap();
        assert_eq!(tokens.rows.len(), 1);
        assert_eq!(
            tokens.rows[0][tokens.columns.iter().position(|c| c == "name").unwrap()],
            Value::Text("a".into())
        );
        assert_eq!(source.last_id("tokens").unwrap(), 1);
        assert_eq!(source.last_id("jobs").unwrap(), 0);
        assert!(source.has_table("sessions").unwrap() && !source.has_table("nope").unwrap());
        // While the copy holds it, a server cannot open the database.
        let second = Connection::open(&path).unwrap();
        second.busy_timeout(std::time::Duration::ZERO).unwrap();
        let err = second
            .query_row("SELECT COUNT(*) FROM tokens", [], |r| r.get::<_, i64>(0))
            .unwrap_err();
        assert!(err.to_string().contains("locked"), "{err}");
    }
}
