//! The `tokens` and `share_links` tables: only hashes are stored; a token is shown once, when
//! it is made. `sitar token` uses the same functions on the same database, so it works while
//! the server runs (SQLite in WAL mode, each request looks its token up afresh: a revoked
//! token fails on the next request).

use std::path::Path;

use rusqlite::params;

use crate::Error;
use crate::auth::caller::Caller;
use crate::auth::role::Role;
use crate::auth::secret::{self, digest};
use crate::storage::db::{CachedSql, Db, now_ms};

/// A token as `sitar token list` shows it: never the token itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TokenInfo {
    /// The name given when it was made (unique).
    pub name: String,
    /// What it may do.
    pub role: Role,
    /// Made at, ms since the Unix epoch.
    pub created_ms: i64,
    /// Last request with it, ms since the Unix epoch (to the minute).
    pub last_used_ms: Option<i64>,
}

/// `last_used_ms` is written at most once a minute per token: phones poll twice a second.
const TOUCH_EVERY_MS: i64 = 60_000;

/// Token names: 1 to 64 letters, digits and `._-` (they appear in logs and listings).
pub(crate) fn check_name(name: &str) -> Result<(), Error> {
    let ok = !name.is_empty()
        && name.len() <= 64
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c));
    if ok {
        Ok(())
    } else {
        Err(Error::BadRequest(format!(
            "token name {name:?}: use 1 to 64 letters, digits, '.', '_' or '-'"
        )))
    }
}

impl Db {
    /// Stores `token`'s hash under `name`; a name in use is a conflict.
    pub(crate) fn insert_token(&self, name: &str, role: Role, token: &str) -> Result<(), Error> {
        check_name(name)?;
        let d = digest(token);
        self.with(|c| {
            c.execute_cached(
                "INSERT INTO tokens (name, role, lookup, hash, created_ms) VALUES (?1, ?2, ?3, ?4, ?5) \
                 ON CONFLICT(name) DO NOTHING",
                params![name, role.as_str(), &d.lookup[..], &d.hash[..], now_ms()],
            )
        })
        .and_then(|n| match n {
            1 => Ok(()),
            _ => Err(Error::Conflict(format!("a token named {name:?} exists"))),
        })
    }

    /// Stores `token` under `name`, replacing the hash a token of that name had (preset tokens).
    pub(crate) fn set_token(&self, name: &str, role: Role, token: &str) -> Result<(), Error> {
        check_name(name)?;
        let d = digest(token);
        self.with(|c| {
            c.execute_cached(
                "INSERT INTO tokens (name, role, lookup, hash, created_ms) VALUES (?1, ?2, ?3, ?4, ?5) \
                 ON CONFLICT(name) DO UPDATE SET role = ?2, lookup = ?3, hash = ?4",
                params![name, role.as_str(), &d.lookup[..], &d.hash[..], now_ms()],
            )
        })
        .map(|_| ())
    }

    pub(crate) fn has_token(&self, name: &str) -> Result<bool, Error> {
        self.with(|c| {
            c.prepare_cached("SELECT 1 FROM tokens WHERE name = ?1")?
                .exists([name])
        })
    }

    pub(crate) fn tokens(&self) -> Result<Vec<TokenInfo>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT name, role, created_ms, last_used_ms FROM tokens ORDER BY created_ms, id",
            )?;
            let rows = stmt.query_map([], |r| {
                Ok((
                    r.get::<_, String>(0)?,
                    r.get::<_, String>(1)?,
                    r.get(2)?,
                    r.get(3)?,
                ))
            })?;
            rows.collect::<rusqlite::Result<Vec<_>>>()
        })?
        .into_iter()
        .map(|(name, role, created_ms, last_used_ms)| {
            Ok(TokenInfo {
                role: role
                    .parse()
                    .map_err(|e| Error::Internal(format!("tokens.role of {name:?}: {e}")))?,
                name,
                created_ms,
                last_used_ms,
            })
        })
        .collect()
    }

    /// Deletes the token named `name`; whether it existed. Its sessions stay (an admin sees
    /// them); a new token of the same name does not inherit them.
    pub(crate) fn revoke_token(&self, name: &str) -> Result<bool, Error> {
        self.with(|c| c.execute_cached("DELETE FROM tokens WHERE name = ?1", [name]))
            .map(|n| n == 1)
    }

    /// The caller `token` belongs to, if any. Rows come by the hash's first 8 bytes; the full
    /// hashes are compared in constant time.
    pub(crate) fn caller(&self, token: &str) -> Result<Option<Caller>, Error> {
        if !secret::plausible(token) {
            return Ok(None);
        }
        let d = digest(token);
        let found = self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT id, name, role, hash, last_used_ms FROM tokens WHERE lookup = ?1",
            )?;
            let rows = stmt.query_map([&d.lookup[..]], |r| {
                Ok((
                    r.get::<_, i64>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, String>(2)?,
                    r.get::<_, Vec<u8>>(3)?,
                    r.get::<_, Option<i64>>(4)?,
                ))
            })?;
            rows.collect::<rusqlite::Result<Vec<_>>>()
        })?;
        let Some((id, name, role, _, last_used)) = found
            .into_iter()
            .find(|row| secret::same_hash(&row.3, &d.hash))
        else {
            return Ok(None);
        };
        let now = now_ms();
        if last_used.is_none_or(|t| now - t >= TOUCH_EVERY_MS) {
            self.with(|c| {
                c.execute_cached(
                    "UPDATE tokens SET last_used_ms = ?2 WHERE id = ?1",
                    params![id, now],
                )
            })?;
        }
        let role = role
            .parse()
            .map_err(|e| Error::Internal(format!("tokens.role of {name:?}: {e}")))?;
        Ok(Some(Caller::Token { id, name, role }))
    }

    /// Stores a share link's hash for `session`.
    pub(crate) fn insert_share(&self, session: &str, token: &str) -> Result<(), Error> {
        let d = digest(token);
        self.with(|c| {
            c.execute_cached(
                "INSERT INTO share_links (lookup, hash, session_id, created_ms) VALUES (?1, ?2, ?3, ?4)",
                params![&d.lookup[..], &d.hash[..], session, now_ms()],
            )
        })
        .map(|_| ())
    }

    /// The session a share link opens, if the link exists (constant-time hash comparison).
    pub(crate) fn shared_session(&self, token: &str) -> Result<Option<String>, Error> {
        if !secret::plausible(token) {
            return Ok(None);
        }
        let d = digest(token);
        let rows = self.with(|c| {
            let mut stmt =
                c.prepare_cached("SELECT hash, session_id FROM share_links WHERE lookup = ?1")?;
            let rows = stmt.query_map([&d.lookup[..]], |r| {
                Ok((r.get::<_, Vec<u8>>(0)?, r.get::<_, String>(1)?))
            })?;
            rows.collect::<rusqlite::Result<Vec<_>>>()
        })?;
        Ok(rows
            .into_iter()
            .find(|(hash, _)| secret::same_hash(hash, &d.hash))
            .map(|(_, session)| session))
    }

    /// Revokes every share link of `session`; how many there were.
    pub(crate) fn revoke_shares(&self, session: &str) -> Result<usize, Error> {
        self.with(|c| c.execute_cached("DELETE FROM share_links WHERE session_id = ?1", [session]))
    }

    /// Whether any token is stored at all (raw rows, for the tests of what is stored).
    #[cfg(test)]
    pub(crate) fn token_count(&self) -> Result<i64, Error> {
        self.with(|c| c.query_row("SELECT COUNT(*) FROM tokens", [], |r| r.get(0)))
    }
}

/// Opens `DATA/sitar.db` for `sitar token` (creating it when new).
fn open(data_dir: &Path) -> Result<Db, Error> {
    std::fs::create_dir_all(data_dir)
        .map_err(|e| Error::io("cannot create data directory", data_dir, e))?;
    Db::open(&data_dir.join("sitar.db"))
}

/// Makes a token named `name` with `role` in the data directory's database and returns it
/// (the only time it is shown: only its hash is stored).
pub fn create_token(data_dir: &Path, role: Role, name: &str) -> Result<String, Error> {
    let token = secret::new_token()?;
    open(data_dir)?.insert_token(name, role, &token)?;
    Ok(token)
}

/// The tokens of the data directory's database, oldest first.
pub fn list_tokens(data_dir: &Path) -> Result<Vec<TokenInfo>, Error> {
    open(data_dir)?.tokens()
}

/// Revokes the token named `name`: its next request is answered 401. Whether it existed.
pub fn revoke_token(data_dir: &Path, name: &str) -> Result<bool, Error> {
    open(data_dir)?.revoke_token(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_hashes_are_stored_and_revocation_is_immediate() {
        let dir = tempfile::tempdir().unwrap();
        let token = create_token(dir.path(), Role::App, "phone-1").unwrap();
        let db = Db::open(&dir.path().join("sitar.db")).unwrap();
        assert!(matches!(
            db.caller(&token).unwrap(),
            Some(Caller::Token {
                role: Role::App,
                ..
            })
        ));
        assert_eq!(db.caller("sitar_nope").unwrap(), None);
        assert_eq!(db.caller("").unwrap(), None);
        // The raw token appears nowhere in the database file (nor its WAL).
        for file in ["sitar.db", "sitar.db-wal"] {
            if let Ok(bytes) = std::fs::read(dir.path().join(file)) {
                let text = String::from_utf8_lossy(&bytes);
                assert!(
                    !text.contains(&token[secret::TOKEN_PREFIX.len()..]),
                    "{file}"
                );
            }
        }
        let listed = list_tokens(dir.path()).unwrap();
        assert_eq!(listed.len(), 1);
        assert_eq!(listed[0].name, "phone-1");
        assert!(listed[0].last_used_ms.is_some(), "the lookup touched it");
        // The same name twice is refused; a bad name is named.
        assert!(create_token(dir.path(), Role::App, "phone-1").is_err());
        let err = create_token(dir.path(), Role::App, "a b")
            .unwrap_err()
            .to_string();
        assert!(err.contains("token name"), "{err}");
        assert!(revoke_token(dir.path(), "phone-1").unwrap());
        assert!(!revoke_token(dir.path(), "phone-1").unwrap());
        assert_eq!(db.caller(&token).unwrap(), None);
        assert_eq!(db.token_count().unwrap(), 0);
    }
}
