//! A session's life, in one place: its states and the table of the steps each allows
//! (`state`), its typed row (`record`), its estimate settings (`estimate_settings`), the
//! transitions (`lifecycle`, the only code that changes a session's state, through
//! [`crate::storage::SessionStore::transition`]), its status document (`status`) and its
//! deletion (`deletion`, finished by `delete_sweep` when a crash cut it off).

pub(crate) mod delete_sweep;
pub(crate) mod deletion;
mod lifecycle;
pub(crate) mod status;

pub(crate) use crate::model::estimate_settings;
pub(crate) use crate::model::{NewSession, Session, SessionState, Step};
pub(crate) use lifecycle::Lifecycle;
