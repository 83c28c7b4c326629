//! What a session's row and a venue share: the stored convention's name, the check a
//! session joining a venue passes inside `insert_session`'s transaction (the venue's row is
//! locked, so two instances cannot bring two conventions into one venue at once), and
//! forgetting a session's kept contribution to its venue's map. Below
//! `sessions` and `venues`, which both use it, so neither imports the other for it.

use postgres::Transaction;
use sitar_core::Convention;

use crate::error::Error;

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

/// Forgets the kept venue-map contribution of session `$1` (when it is in a venue), raising
/// its generation: `venues`' `forget_contribution`, and `sessions`' transition to `done`.
pub(super) const FORGET_CONTRIBUTION: &str = "INSERT INTO venue_contributions (session_id, generation, body) \
     SELECT $1::text, 1, NULL WHERE EXISTS (SELECT 1 FROM sessions WHERE id = $1::text AND venue IS NOT NULL) \
     ON CONFLICT (session_id) DO UPDATE SET generation = venue_contributions.generation + 1, \
     body = NULL";
