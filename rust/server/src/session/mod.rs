//! A session's life, in one place: its states and the table of the steps each allows
//! (`state`), its typed row (`record`), its estimate settings (`estimate_settings`), the
//! transitions (`lifecycle`, the only code that changes a session's state, through
//! [`crate::storage::SessionStore::transition`]), its status document (`status`) and its
//! deletion (`deletion`, finished by `delete_sweep` when a crash cut it off).

pub(crate) mod delete_sweep;
pub(crate) mod deletion;
pub(crate) mod estimate_settings;
mod lifecycle;
mod record;
mod state;
pub(crate) mod status;

pub(crate) use lifecycle::Lifecycle;
pub(crate) use record::{NewSession, Session};
pub(crate) use state::{SessionState, Step};
