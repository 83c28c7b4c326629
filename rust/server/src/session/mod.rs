//! A session's life, in one place: its states and the table of the steps each allows
//! (`state.rs`), its typed row (`record.rs`), reading and creating rows (`store.rs`) and the
//! transitions (`lifecycle.rs`), the only code that writes a session's state.

pub(crate) mod deletion;
pub(crate) mod estimate_settings;
mod lifecycle;
mod record;
mod state;
pub(crate) mod status;
mod store;

pub(crate) use lifecycle::Lifecycle;
pub(crate) use record::{NewSession, Session};
pub(crate) use state::{SessionState, Step};
