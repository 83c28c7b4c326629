//! The `venues`, `venue_members` and `venue_contributions` tables (the check a session joining a venue passes is
//! `joining`'s, below both this file and `sessions`).

use rusqlite::{OptionalExtension, params};

use super::{CachedSql, SqliteStore};
use crate::error::Error;
use crate::model::{NewVenue, Session, Venue};
use crate::storage::metadata::{KeptContribution, VenueStore};
use crate::storage::now_ms;

const COLUMNS: &str = "id, name, anchor, cell_m, owner, created_ms";

fn venue_from_row(r: &rusqlite::Row<'_>) -> rusqlite::Result<Venue> {
    Ok(Venue {
        id: r.get(0)?,
        name: r.get(1)?,
        anchor: r.get(2)?,
        cell_m: r.get(3)?,
        owner: r.get(4)?,
        created_ms: r.get(5)?,
    })
}

impl VenueStore for SqliteStore {
    fn insert_venue(&self, id: &str, new: &NewVenue<'_>) -> Result<(), Error> {
        self.with(|c| {
            c.execute_cached(
                "INSERT INTO venues (id, name, anchor, cell_m, owner, created_ms) \
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
                params![id, new.name, new.anchor, new.cell_m, new.owner, now_ms()],
            )
        })
        .map(|_| ())
    }

    fn venue(&self, id: &str) -> Result<Option<Venue>, Error> {
        self.with(|c| {
            c.query_row_cached(
                &format!("SELECT {COLUMNS} FROM venues WHERE id = ?1"),
                [id],
                venue_from_row,
            )
            .optional()
        })
    }

    fn venues_for(&self, viewer: Option<i64>, limit: u32) -> Result<Vec<Venue>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(&format!(
                "SELECT {COLUMNS} FROM venues WHERE ?1 IS NULL OR owner = ?1 \
                 OR id IN (SELECT venue_id FROM venue_members WHERE token_id = ?1) \
                 ORDER BY created_ms DESC, rowid DESC LIMIT ?2"
            ))?;
            let rows = stmt.query_map(params![viewer, limit], venue_from_row)?;
            rows.collect()
        })
    }

    fn is_member(&self, venue: &str, token: i64) -> Result<bool, Error> {
        self.with(|c| {
            c.prepare_cached("SELECT 1 FROM venue_members WHERE venue_id = ?1 AND token_id = ?2")?
                .exists(params![venue, token])
        })
    }

    fn add_member(&self, venue: &str, token_name: &str) -> Result<bool, Error> {
        self.with(|c| {
            c.execute_cached(
                "INSERT INTO venue_members (venue_id, token_id) \
                 SELECT ?1, id FROM tokens WHERE name = ?2 \
                 ON CONFLICT (venue_id, token_id) DO NOTHING",
                params![venue, token_name],
            )?;
            c.prepare_cached("SELECT 1 FROM tokens WHERE name = ?1")?
                .exists([token_name])
        })
    }

    fn remove_member(&self, venue: &str, token_name: &str) -> Result<Option<bool>, Error> {
        self.transaction(|tx| {
            let token: Option<i64> = tx
                .query_row_cached("SELECT id FROM tokens WHERE name = ?1", [token_name], |r| {
                    r.get(0)
                })
                .optional()?;
            let Some(token) = token else {
                return Ok(None);
            };
            let removed = tx.execute_cached(
                "DELETE FROM venue_members WHERE venue_id = ?1 AND token_id = ?2",
                params![venue, token],
            )?;
            Ok(Some(removed == 1))
        })
    }

    fn members(&self, venue: &str) -> Result<Vec<String>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT t.name FROM venue_members m JOIN tokens t ON t.id = m.token_id \
                 WHERE m.venue_id = ?1 ORDER BY t.name",
            )?;
            let rows = stmt.query_map([venue], |r| r.get(0))?;
            rows.collect()
        })
    }

    fn venue_sessions(&self, venue: &str) -> Result<Vec<Session>, Error> {
        let rows = self.with(|c| {
            let mut stmt = c.prepare_cached(&format!(
                "SELECT {} FROM sessions WHERE venue = ?1 ORDER BY created_ms, rowid",
                super::sessions::COLUMNS
            ))?;
            super::sessions::read_rows(&mut stmt, [venue])
        })?;
        for bad in &rows.unreadable {
            log::warn!(
                "session {}: unreadable row, left out of its venue: {}",
                bad.id,
                bad.why
            );
        }
        Ok(rows.sessions)
    }

    fn delete_venue(&self, id: &str) -> Result<bool, Error> {
        self.transaction(|tx| {
            tx.execute_cached("DELETE FROM venue_members WHERE venue_id = ?1", [id])?;
            tx.execute_cached(
                "DELETE FROM venue_contributions WHERE session_id IN \
                 (SELECT id FROM sessions WHERE venue = ?1)",
                [id],
            )?;
            tx.execute_cached("UPDATE sessions SET venue = NULL WHERE venue = ?1", [id])?;
            Ok(tx.execute_cached("DELETE FROM venues WHERE id = ?1", [id])? == 1)
        })
    }

    fn kept_contributions(&self, venue: &str) -> Result<Vec<KeptContribution>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT s.id, COALESCE(k.generation, 0), k.body FROM sessions s \
                 LEFT JOIN venue_contributions k ON k.session_id = s.id WHERE s.venue = ?1",
            )?;
            let rows = stmt.query_map([venue], |r| {
                Ok(KeptContribution {
                    session: r.get(0)?,
                    generation: r.get(1)?,
                    body: r.get(2)?,
                })
            })?;
            rows.collect()
        })
    }

    fn keep_contribution(
        &self,
        session: &str,
        generation: i64,
        body: &[u8],
    ) -> Result<bool, Error> {
        self.with(|c| {
            c.execute_cached(KEEP, params![session, generation, body])
                .map(|n| n == 1)
        })
    }

    fn forget_contribution(&self, session: &str) -> Result<(), Error> {
        self.with(|c| c.execute_cached(super::joining::FORGET_CONTRIBUTION, [session]))
            .map(drop)
    }
}

/// Keeps a contribution (`?1` session, `?2` generation, `?3` body) when the generation is
/// still the kept one (0: none kept yet) and the session is in a venue.
const KEEP: &str = "INSERT INTO venue_contributions (session_id, generation, body) \
     SELECT ?1, ?2, ?3 WHERE EXISTS (SELECT 1 FROM sessions WHERE id = ?1 AND venue IS NOT NULL) \
     ON CONFLICT (session_id) DO UPDATE SET body = excluded.body \
     WHERE venue_contributions.generation = excluded.generation";
