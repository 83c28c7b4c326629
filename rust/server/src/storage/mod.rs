//! Where bytes are kept, behind two seams: the metadata store ([`metadata`]: sessions,
//! trials, jobs, devices, tokens, usage, share links, idempotency keys) and the data
//! directory's files (`files`, with the disk quotas of `quota`). The embedded default is
//! SQLite in `DATA/sitar.db` ([`sqlite`]) beside the files; only this folder speaks SQL or
//! touches the data directory (`tests/layout.rs` checks the SQL). Every stored object of a
//! session has a typed name ([`keys::SessionObject`]).

pub(crate) mod embedded;
pub(crate) mod files;
pub(crate) mod keys;
pub(crate) mod metadata;
pub(crate) mod quota;
pub(crate) mod sqlite;

#[cfg(test)]
pub(crate) mod conformance;

pub(crate) use metadata::{
    JobEnd, MetadataStore, SessionStore, StepRecord, TokenStore, UsageStore,
};

/// Now, in ms since the Unix epoch (0 if the clock is before it): the unit of every stored
/// time.
pub(crate) fn now_ms() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}
