//! Access control: tokens with roles (`admin`, `app`, `worker`), stored only as hashes in the metadata store and
//! compared in constant time; the middleware that finds every request's caller; the
//! `?token=` → cookie step of the HTML pages; share links; the admin token a new data
//! directory gets; and the per-token limits, counted in the metadata store so a restart keeps them.

mod bootstrap;
mod caller;
mod limits;
mod middleware;
pub(crate) mod secret;
mod tokens;

pub(crate) use crate::model::Caller;
pub use crate::model::Role;
pub use crate::model::TokenInfo;
pub(crate) use bootstrap::ensure_admin_token;
pub use bootstrap::{ADMIN_TOKEN_FILE, PresetToken};
pub(crate) use caller::{Admin, WorkerCaller};
pub use limits::Limits;
pub(crate) use limits::{UploadLimiter, limit_uploads};
pub(crate) use middleware::{CallerName, authenticate};
pub use secret::new_token;
pub use tokens::{
    create_token, create_token_at, list_tokens, list_tokens_at, revoke_token, revoke_token_at,
};
