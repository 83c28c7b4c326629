//! Access control: tokens with roles (`admin`, `app`, `worker`), stored only as hashes in the
//! metadata store and compared in constant time; the extractors for admin-only and worker
//! routes; share links; the admin token a new data directory gets; and the per-token limits,
//! counted in the metadata store so a restart keeps them. The middleware that finds every
//! request's caller (with the pages' `?token=` → cookie step) and the one that applies the
//! limits are HTTP's (`http::authenticate`, `http::upload_limits`).

mod bootstrap;
mod caller;
mod limits;
pub(crate) mod secret;
mod tokens;

pub(crate) use bootstrap::ensure_admin_token;
pub use bootstrap::{ADMIN_TOKEN_FILE, PresetToken};
pub(crate) use caller::{Admin, WorkerCaller};
pub use limits::Limits;
pub(crate) use limits::UploadLimiter;
pub use secret::new_token;
pub use tokens::{
    create_token, create_token_at, list_tokens, list_tokens_at, revoke_token, revoke_token_at,
};
