//! The `venues`, `venue_members` and `venue_contributions` tables in Postgres (the check a session joining a venue
//! passes is `joining`'s, below both this file and `sessions`).

use postgres::Row;

use super::PgStore;
use crate::error::Error;
use crate::model::{NewVenue, Session, Venue};
use crate::storage::metadata::{KeptContribution, VenueStore};
use crate::storage::now_ms;

const COLUMNS: &str = "id, name, anchor, cell_m, owner, created_ms";

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
            tx.execute(
                "DELETE FROM venue_contributions WHERE session_id IN \
                 (SELECT id FROM sessions WHERE venue = $1)",
                &[&id],
            )?;
            tx.execute("UPDATE sessions SET venue = NULL WHERE venue = $1", &[&id])?;
            let deleted = tx.execute("DELETE FROM venues WHERE id = $1", &[&id])? == 1;
            tx.commit()?;
            Ok(deleted)
        })
    }

    fn kept_contributions(&self, venue: &str) -> Result<Vec<KeptContribution>, Error> {
        let venue = venue.to_string();
        self.pool.run(move |c| {
            Ok(c.query(
                "SELECT s.id, COALESCE(k.generation, 0), k.body FROM sessions s \
                 LEFT JOIN venue_contributions k ON k.session_id = s.id WHERE s.venue = $1",
                &[&venue],
            )?
            .iter()
            .map(|r| KeptContribution {
                session: r.get(0),
                generation: r.get(1),
                body: r.get(2),
            })
            .collect())
        })
    }

    fn keep_contribution(
        &self,
        session: &str,
        generation: i64,
        body: &[u8],
    ) -> Result<bool, Error> {
        let (session, body) = (session.to_string(), body.to_vec());
        self.pool.run(move |c| {
            Ok(c.execute(
                "INSERT INTO venue_contributions (session_id, generation, body) \
                 SELECT $1::text, $2::bigint, $3::bytea WHERE EXISTS \
                 (SELECT 1 FROM sessions WHERE id = $1::text AND venue IS NOT NULL) \
                 ON CONFLICT (session_id) DO UPDATE SET body = EXCLUDED.body \
                 WHERE venue_contributions.generation = EXCLUDED.generation",
                &[&session, &generation, &body],
            )? == 1)
        })
    }

    fn forget_contribution(&self, session: &str) -> Result<(), Error> {
        let session = session.to_string();
        self.pool.run(move |c| {
            c.execute(super::joining::FORGET_CONTRIBUTION, &[&session])?;
            Ok(())
        })
    }
}
