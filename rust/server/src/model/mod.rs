//! The server's vocabulary, the bottom layer: what the stores keep and the logic above them
//! speaks of — sessions (their record, states and steps, estimate settings), venues,
//! callers, roles, tokens and their secrets, usage. It imports nothing of the server but
//! its error and configuration; `storage/` depends on it alone, and the lifecycle
//! (`session/`), access control (`auth/`) and venue logic (`venue/`) use it from above.

mod caller;
pub(crate) mod estimate_settings;
mod playback_kind;
mod role;
mod session;
mod session_state;
mod token;
pub(crate) mod token_secret;
mod usage;
mod venue;

pub(crate) use caller::Caller;
pub use playback_kind::PlaybackKind;
pub use role::Role;
pub(crate) use session::{NewSession, Session};
pub(crate) use session_state::{SessionState, Step};
pub use token::TokenInfo;
pub(crate) use token::check_token_name;
pub(crate) use usage::{DAY_HOURS, HOUR_MS, UsageFull};
pub(crate) use venue::{
    CELL_M_RANGE, DEFAULT_CELL_M, MAX_NAME_CHARS, NewVenue, Venue, is_venue_id, new_venue_id,
};
