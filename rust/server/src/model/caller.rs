//! Who is asking: a token's caller (or the open server's), and what it may see.

use crate::model::{role::Role, session::Session};

/// The authenticated caller of a request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Caller {
    /// A token from the `tokens` table.
    Token { id: i64, name: String, role: Role },
    /// `--insecure-no-auth` on loopback: everything is allowed.
    Open,
}

impl Caller {
    pub fn is_admin(&self) -> bool {
        matches!(
            self,
            Caller::Open
                | Caller::Token {
                    role: Role::Admin,
                    ..
                }
        )
    }

    /// The token id new sessions are recorded under (`None` without authentication).
    pub fn owner(&self) -> Option<i64> {
        match self {
            Caller::Token { id, .. } => Some(*id),
            Caller::Open => None,
        }
    }

    /// The sessions this caller sees: `None` every one, `Some(id)` those of token `id`.
    pub fn scope(&self) -> Option<i64> {
        if self.is_admin() { None } else { self.owner() }
    }

    /// Whether the caller may see `session` (an app token: only its own).
    pub fn may_see(&self, session: &Session) -> bool {
        match self.scope() {
            None => true,
            Some(id) => session.owner == Some(id),
        }
    }

    /// The name request logs show (never the token).
    pub fn name(&self) -> &str {
        match self {
            Caller::Token { name, .. } => name,
            Caller::Open => "-",
        }
    }
}
