//! Who is asking: the caller the authentication middleware found, as axum extractors
//! (`Caller` for any authenticated request, `Admin` for admin-only routes, `WorkerCaller` for
//! the playback hosts' routes; atuin's `UserAuth` pattern).

use axum::extract::FromRequestParts;
use axum::http::request::Parts;

use crate::Error;
use crate::auth::role::Role;
use crate::session::Session;

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

impl<S: Send + Sync> FromRequestParts<S> for Caller {
    type Rejection = Error;

    async fn from_request_parts(parts: &mut Parts, _: &S) -> Result<Caller, Error> {
        parts
            .extensions
            .get::<Caller>()
            .cloned()
            .ok_or_else(|| Error::Unauthorized("this route needs a token".into()))
    }
}

/// A caller with the admin role; an app token gets 403.
pub(crate) struct Admin(#[allow(dead_code)] pub Caller);

impl<S: Send + Sync> FromRequestParts<S> for Admin {
    type Rejection = Error;

    async fn from_request_parts(parts: &mut Parts, state: &S) -> Result<Admin, Error> {
        let caller = Caller::from_request_parts(parts, state).await?;
        if caller.is_admin() {
            Ok(Admin(caller))
        } else {
            Err(Error::Forbidden(format!(
                "token {:?} has the app role; this route needs an admin token",
                caller.name()
            )))
        }
    }
}

/// A caller with the worker role (a playback host); any other token gets 403. The token id
/// is the one its hosts are registered under.
pub(crate) struct WorkerCaller {
    /// The token's id.
    pub token: i64,
    /// The token's name (logs, the devices listing).
    pub name: String,
}

impl<S: Send + Sync> FromRequestParts<S> for WorkerCaller {
    type Rejection = Error;

    async fn from_request_parts(parts: &mut Parts, state: &S) -> Result<WorkerCaller, Error> {
        match Caller::from_request_parts(parts, state).await? {
            Caller::Token {
                id,
                name,
                role: Role::Worker,
            } => Ok(WorkerCaller { token: id, name }),
            other => Err(Error::Forbidden(format!(
                "token {:?} is not a worker token; the /v1/worker/ routes are for playback hosts \
                 (sitar token create --role worker)",
                other.name()
            ))),
        }
    }
}
