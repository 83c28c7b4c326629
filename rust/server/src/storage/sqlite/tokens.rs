//! The `tokens` and `share_links` tables: only hashes are stored; a token is shown once, when
//! it is made. Each request looks its token up afresh: a revoked token fails on the next
//! request.

use rusqlite::params;

use super::{CachedSql, SqliteStore};
use crate::error::Error;
use crate::model::{
    Caller, Role, TokenInfo, check_token_name,
    token_secret::{self as secret, digest},
};
use crate::storage::metadata::TokenStore;
use crate::storage::now_ms;

/// `last_used_ms` is written at most once a minute per token: phones poll twice a second.
const TOUCH_EVERY_MS: i64 = 60_000;

impl TokenStore for SqliteStore {
    /// Stores `token`'s hash under `name`; a name in use is a conflict.
    fn insert_token(&self, name: &str, role: Role, token: &str) -> Result<(), Error> {
        check_token_name(name)?;
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
    fn set_token(&self, name: &str, role: Role, token: &str) -> Result<(), Error> {
        check_token_name(name)?;
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

    fn has_token(&self, name: &str) -> Result<bool, Error> {
        self.with(|c| {
            c.prepare_cached("SELECT 1 FROM tokens WHERE name = ?1")?
                .exists([name])
        })
    }

    fn tokens(&self) -> Result<Vec<TokenInfo>, Error> {
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
    fn revoke_token(&self, name: &str) -> Result<bool, Error> {
        self.with(|c| c.execute_cached("DELETE FROM tokens WHERE name = ?1", [name]))
            .map(|n| n == 1)
    }

    /// The caller `token` belongs to, if any. Rows come by the hash's first 8 bytes; the full
    /// hashes are compared in constant time.
    fn caller(&self, token: &str) -> Result<Option<Caller>, Error> {
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
    fn insert_share(&self, session: &str, token: &str) -> Result<(), Error> {
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
    fn shared_session(&self, token: &str) -> Result<Option<String>, Error> {
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
    fn revoke_shares(&self, session: &str) -> Result<usize, Error> {
        self.with(|c| c.execute_cached("DELETE FROM share_links WHERE session_id = ?1", [session]))
    }

    /// Whether any token is stored at all (raw rows, for the tests of what is stored).
    #[cfg(test)]
    fn token_count(&self) -> Result<i64, Error> {
        self.with(|c| c.query_row("SELECT COUNT(*) FROM tokens", [], |r| r.get(0)))
    }
}
