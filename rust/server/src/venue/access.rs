//! Who sees a venue: the token that made it (its owner), the tokens it granted membership,
//! and admins. Everyone else is told it does not exist (404, never 403).

use crate::error::Error;
use crate::model::{Caller, Venue};
use crate::storage::VenueStore;

/// How a caller stands to a venue it may see.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Standing {
    /// An admin token (or a server without authentication): everything.
    Admin,
    /// The token that made it: everything.
    Owner,
    /// A token the owner granted membership: adds its own sessions, reads map and report.
    Member,
}

impl Standing {
    /// How `caller` stands to `venue`; `None` when it may not see it.
    pub(crate) fn of(
        store: &dyn VenueStore,
        caller: &Caller,
        venue: &Venue,
    ) -> Result<Option<Standing>, Error> {
        if caller.is_admin() {
            return Ok(Some(Standing::Admin));
        }
        let Some(token) = caller.owner() else {
            return Ok(None);
        };
        if venue.owner == Some(token) {
            Ok(Some(Standing::Owner))
        } else if store.is_member(&venue.id, token)? {
            Ok(Some(Standing::Member))
        } else {
            Ok(None)
        }
    }

    /// Whether this caller may delete the venue and grant or end memberships.
    pub(crate) fn manages(self) -> bool {
        matches!(self, Standing::Admin | Standing::Owner)
    }
}
