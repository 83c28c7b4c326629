//! Access control: tokens with roles (`admin`, `app`), stored only as hashes in SQLite and
//! compared in constant time; the middleware that finds every request's caller; the
//! `?token=` → cookie step of the HTML pages; share links; the admin token a new data
//! directory gets; and the per-token limits, counted in SQLite so a restart keeps them.

mod bootstrap;
mod caller;
mod limits;
mod middleware;
mod role;
pub(crate) mod secret;
mod store;
mod usage;

pub(crate) use bootstrap::ensure_admin_token;
pub use bootstrap::{ADMIN_TOKEN_FILE, PresetToken};
pub(crate) use caller::{Admin, Caller};
pub use limits::Limits;
pub(crate) use limits::{UploadLimiter, limit_uploads};
pub(crate) use middleware::{CallerName, authenticate};
pub use role::Role;
pub use secret::new_token;
pub use store::{TokenInfo, create_token, list_tokens, revoke_token};
