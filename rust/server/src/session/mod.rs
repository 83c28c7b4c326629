//! A session's life, in one place: the transitions (`lifecycle`, the only code that changes
//! a session's state, through [`crate::storage::SessionStore::transition`]). Its states,
//! steps, row and estimate settings are vocabulary (`crate::model`); its status document
//! is `http::session_status`, its deletion `jobs::deletion` (finished by
//! `jobs::delete_sweep` when a crash cut it off).

mod lifecycle;

pub(crate) use lifecycle::Lifecycle;
