//! The `tokens` and `share_links` tables in Postgres: only hashes are stored, each request
//! looks its token up afresh (a token revoked through one instance fails on the next request
//! to any instance).

use super::PgStore;
use crate::error::Error;
use crate::model::{
    Caller, Role, TokenInfo, check_token_name,
    token_secret::{self as secret, digest},
};
use crate::storage::metadata::TokenStore;
use crate::storage::now_ms;

/// `last_used_ms` is written at most once a minute per token: phones poll twice a second.
const TOUCH_EVERY_MS: i64 = 60_000;

fn parse_role(name: &str, role: &str) -> Result<Role, Error> {
    role.parse()
        .map_err(|e| Error::Internal(format!("tokens.role of {name:?}: {e}")))
}

impl PgStore {
    /// Inserts or (with `replace`) replaces the token named `name`; rows written.
    fn write_token(
        &self,
        name: &str,
        role: Role,
        token: &str,
        replace: bool,
    ) -> Result<u64, Error> {
        check_token_name(name)?;
        let d = digest(token);
        let (name, role) = (name.to_string(), role.as_str());
        let (lookup, hash) = (d.lookup.to_vec(), d.hash.to_vec());
        let conflict = if replace {
            "DO UPDATE SET role = $2, lookup = $3, hash = $4"
        } else {
            "DO NOTHING"
        };
        self.pool.run(move |c| {
            Ok(c.execute(
                &format!(
                    "INSERT INTO tokens (name, role, lookup, hash, created_ms) \
                     VALUES ($1, $2, $3, $4, $5) ON CONFLICT (name) {conflict}"
                ),
                &[&name, &role, &lookup, &hash, &now_ms()],
            )?)
        })
    }
}

impl TokenStore for PgStore {
    fn insert_token(&self, name: &str, role: Role, token: &str) -> Result<(), Error> {
        match self.write_token(name, role, token, false)? {
            1 => Ok(()),
            _ => Err(Error::Conflict(format!("a token named {name:?} exists"))),
        }
    }

    fn set_token(&self, name: &str, role: Role, token: &str) -> Result<(), Error> {
        self.write_token(name, role, token, true).map(|_| ())
    }

    fn has_token(&self, name: &str) -> Result<bool, Error> {
        let name = name.to_string();
        self.pool.run(move |c| {
            Ok(
                c.query_opt("SELECT 1 FROM tokens WHERE name = $1", &[&name])?
                    .is_some(),
            )
        })
    }

    fn tokens(&self) -> Result<Vec<TokenInfo>, Error> {
        let rows = self.pool.run(|c| {
            Ok(c.query(
                "SELECT name, role, created_ms, last_used_ms FROM tokens ORDER BY created_ms, id",
                &[],
            )?)
        })?;
        rows.iter()
            .map(|r| {
                let name: String = r.get(0);
                Ok(TokenInfo {
                    role: parse_role(&name, r.get(1))?,
                    name,
                    created_ms: r.get(2),
                    last_used_ms: r.get(3),
                })
            })
            .collect()
    }

    fn revoke_token(&self, name: &str) -> Result<bool, Error> {
        let name = name.to_string();
        self.pool
            .run(move |c| Ok(c.execute("DELETE FROM tokens WHERE name = $1", &[&name])? == 1))
    }

    /// Rows come by the hash's first 8 bytes; the full hashes are compared in constant time.
    fn caller(&self, token: &str) -> Result<Option<Caller>, Error> {
        if !secret::plausible(token) {
            return Ok(None);
        }
        let d = digest(token);
        let lookup = d.lookup.to_vec();
        let rows = self.pool.run(move |c| {
            Ok(c.query(
                "SELECT id, name, role, hash, last_used_ms FROM tokens WHERE lookup = $1",
                &[&lookup],
            )?)
        })?;
        let Some(row) = rows
            .iter()
            .find(|r| secret::same_hash(r.get::<_, &[u8]>(3), &d.hash))
        else {
            return Ok(None);
        };
        let (id, name, last_used): (i64, String, Option<i64>) =
            (row.get(0), row.get(1), row.get(4));
        let role = parse_role(&name, row.get(2))?;
        let now = now_ms();
        if last_used.is_none_or(|t| now - t >= TOUCH_EVERY_MS) {
            self.pool.run(move |c| {
                c.execute(
                    "UPDATE tokens SET last_used_ms = $2 WHERE id = $1",
                    &[&id, &now],
                )?;
                Ok(())
            })?;
        }
        Ok(Some(Caller::Token { id, name, role }))
    }

    fn insert_share(&self, session: &str, token: &str) -> Result<(), Error> {
        let d = digest(token);
        let (lookup, hash, session) = (d.lookup.to_vec(), d.hash.to_vec(), session.to_string());
        self.pool.run(move |c| {
            c.execute(
                "INSERT INTO share_links (lookup, hash, session_id, created_ms) VALUES ($1, $2, $3, $4)",
                &[&lookup, &hash, &session, &now_ms()],
            )?;
            Ok(())
        })
    }

    fn shared_session(&self, token: &str) -> Result<Option<String>, Error> {
        if !secret::plausible(token) {
            return Ok(None);
        }
        let d = digest(token);
        let lookup = d.lookup.to_vec();
        let rows = self.pool.run(move |c| {
            Ok(c.query(
                "SELECT hash, session_id FROM share_links WHERE lookup = $1",
                &[&lookup],
            )?)
        })?;
        Ok(rows
            .iter()
            .find(|r| secret::same_hash(r.get::<_, &[u8]>(0), &d.hash))
            .map(|r| r.get(1)))
    }

    fn revoke_shares(&self, session: &str) -> Result<usize, Error> {
        let session = session.to_string();
        self.pool.run(move |c| {
            Ok(c.execute("DELETE FROM share_links WHERE session_id = $1", &[&session])? as usize)
        })
    }

    #[cfg(test)]
    fn token_count(&self) -> Result<i64, Error> {
        self.pool
            .run(|c| Ok(c.query_one("SELECT COUNT(*) FROM tokens", &[])?.get(0)))
    }
}
