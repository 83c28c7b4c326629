//! The `venues` and `venue_members` tables in Postgres, and the check a session joining a
//! venue passes inside `insert_session`'s transaction: the venue's row is locked, so two
//! instances cannot bring two conventions into one venue at once.

use postgres::{Row, Transaction};
use sitar_core::Convention;

use super::PgStore;
use crate::Error;
use crate::session::Session;
use crate::storage::metadata::VenueStore;
use crate::storage::now_ms;
use crate::venue::{NewVenue, Venue};

const COLUMNS: &str = "id, name, anchor, cell_m, owner, created_ms";

/// A stored convention name; a value no version writes is `None`.
pub(super) fn parse_convention(name: &str) -> Option<Convention> {
    match name {
        "unity" => Some(Convention::Unity),
        "arcore" => Some(Convention::Arcore),
        _ => None,
    }
}

/// Session joining `venue` with `convention`: the venue exists (a 422 naming `venue` when it
/// was deleted meanwhile) and its sessions have that convention (else a 409 naming both).
pub(super) fn check_joining(
    tx: &mut Transaction<'_>,
    venue: &str,
    convention: Convention,
) -> Result<(), Error> {
    let exists = tx.query_opt("SELECT 1 FROM venues WHERE id = $1 FOR UPDATE", &[&venue])?;
    if exists.is_none() {
        return Err(Error::InvalidContent(format!("venue: no venue {venue:?}")));
    }
    let theirs = tx.query_opt(
        "SELECT convention FROM sessions WHERE venue = $1 AND convention <> $2 LIMIT 1",
        &[&venue, &convention.name()],
    )?;
    match theirs {
        None => Ok(()),
        Some(row) => Err(Error::Conflict(format!(
            "convention: venue {venue}'s sessions use {}; this session's is {} \
             (a venue's sessions share one convention)",
            row.get::<_, String>(0),
            convention.name()
        ))),
    }
}

fn venue_from_row(r: &Row) -> Venue {
    Venue {
        id: r.get(0),
        name: r.get(1),
        anchor: r.get(2),
        cell_m: r.get(3),
        owner: r.get(4),
        created_ms: r.get(5),
    }
}

impl VenueStore for PgStore {
    fn insert_venue(&self, id: &str, new: &NewVenue<'_>) -> Result<(), Error> {
        let (id, name, anchor) = (id.to_string(), new.name.to_string(), new.anchor.to_string());
        let (cell_m, owner) = (new.cell_m, new.owner);
        self.pool.run(move |c| {
            c.execute(
                "INSERT INTO venues (id, name, anchor, cell_m, owner, created_ms) \
                 VALUES ($1, $2, $3, $4, $5, $6)",
                &[&id, &name, &anchor, &cell_m, &owner, &now_ms()],
            )?;
            Ok(())
        })
    }

    fn venue(&self, id: &str) -> Result<Option<Venue>, Error> {
        let id = id.to_string();
        self.pool.run(move |c| {
            Ok(c.query_opt(
                &format!("SELECT {COLUMNS} FROM venues WHERE id = $1"),
                &[&id],
            )?
            .map(|r| venue_from_row(&r)))
        })
    }

    fn venues_for(&self, viewer: Option<i64>, limit: u32) -> Result<Vec<Venue>, Error> {
        self.pool.run(move |c| {
            Ok(c.query(
                &format!(
                    "SELECT {COLUMNS} FROM venues WHERE $1::BIGINT IS NULL OR owner = $1 \
                     OR id IN (SELECT venue_id FROM venue_members WHERE token_id = $1) \
                     ORDER BY created_ms DESC, seq DESC LIMIT $2"
                ),
                &[&viewer, &i64::from(limit)],
            )?
            .iter()
            .map(venue_from_row)
            .collect())
        })
    }

    fn is_member(&self, venue: &str, token: i64) -> Result<bool, Error> {
        let venue = venue.to_string();
        self.pool.run(move |c| {
            Ok(c.query_opt(
                "SELECT 1 FROM venue_members WHERE venue_id = $1 AND token_id = $2",
                &[&venue, &token],
            )?
            .is_some())
        })
    }

    fn add_member(&self, venue: &str, token_name: &str) -> Result<bool, Error> {
        let (venue, name) = (venue.to_string(), token_name.to_string());
        self.pool.run(move |c| {
            c.execute(
                "INSERT INTO venue_members (venue_id, token_id) \
                 SELECT $1, id FROM tokens WHERE name = $2 \
                 ON CONFLICT (venue_id, token_id) DO NOTHING",
                &[&venue, &name],
            )?;
            Ok(
                c.query_opt("SELECT 1 FROM tokens WHERE name = $1", &[&name])?
                    .is_some(),
            )
        })
    }

    fn remove_member(&self, venue: &str, token_name: &str) -> Result<Option<bool>, Error> {
        let (venue, name) = (venue.to_string(), token_name.to_string());
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            let Some(token) = tx.query_opt("SELECT id FROM tokens WHERE name = $1", &[&name])?
            else {
                return Ok(None);
            };
            let token: i64 = token.get(0);
            let removed = tx.execute(
                "DELETE FROM venue_members WHERE venue_id = $1 AND token_id = $2",
                &[&venue, &token],
            )?;
            tx.commit()?;
            Ok(Some(removed == 1))
        })
    }

    fn members(&self, venue: &str) -> Result<Vec<String>, Error> {
        let venue = venue.to_string();
        self.pool.run(move |c| {
            Ok(c.query(
                "SELECT t.name FROM venue_members m JOIN tokens t ON t.id = m.token_id \
                 WHERE m.venue_id = $1 ORDER BY t.name",
                &[&venue],
            )?
            .iter()
            .map(|r| r.get(0))
            .collect())
        })
    }

    fn venue_sessions(&self, venue: &str) -> Result<Vec<Session>, Error> {
        let venue = venue.to_string();
        let rows = self.pool.run(move |c| {
            let rows = c.query(
                &format!(
                    "SELECT {} FROM sessions WHERE venue = $1 ORDER BY created_ms, seq",
                    super::sessions::COLUMNS
                ),
                &[&venue],
            )?;
            Ok(super::sessions::read_rows(rows))
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
        let id = id.to_string();
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            tx.execute("DELETE FROM venue_members WHERE venue_id = $1", &[&id])?;
            tx.execute("UPDATE sessions SET venue = NULL WHERE venue = $1", &[&id])?;
            let deleted = tx.execute("DELETE FROM venues WHERE id = $1", &[&id])? == 1;
            tx.commit()?;
            Ok(deleted)
        })
    }
}
