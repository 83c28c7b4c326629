//! Who is asking, as axum extractors of the caller the authentication middleware found
//! (`Caller` for any authenticated request, `Admin` for admin-only routes, `WorkerCaller` for
//! the playback hosts' routes; atuin's `UserAuth` pattern).

use axum::extract::FromRequestParts;
use axum::http::request::Parts;

use crate::error::Error;
use crate::model::{Caller, Role};

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
