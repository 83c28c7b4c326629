//! Where bytes are kept, behind two seams named by meaning, with no SQL, connection or path
//! types crossing them: the metadata store ([`metadata`]: sessions, trials, jobs, devices,
//! tokens, usage, share links, idempotency keys) and the blob store ([`blobs`]: every byte of
//! a session, named by [`keys::SessionObject`]); beside them the worker store ([`workers`]:
//! playback hosts, their phones, trials leased to them). The embedded default is SQLite in
//! `DATA/sitar.db` ([`sqlite`], opened by [`embedded`]) and the data directory's session
//! folders ([`files`], with the disk quotas of [`quota`]); each instance's own files (admin
//! token, TLS certificate, instance id) are [`instance`]'s; deletes cut off by a crash are
//! finished from [`deletes`]' records; which instance plays which session
//! is [`instances`]'. One conformance suite per seam
//! (`conformance`) runs against any implementation. The cluster implementations, for several
//! instances on one database and bucket, are `postgres` and `s3` ([`open`] picks), built with the
//! `cluster` feature only (as is all of `sitar migrate`). For `sitar migrate`: an embedded installation read under SQLite's exclusive lock
//! (`installation`) and rows as plain values (`rows`), written into Postgres as they are.
//! Only this folder speaks SQL or touches the data directory (the workspace's `tests/tests/server_layout.rs` checks both).

pub(crate) mod blobs;
pub(crate) mod blocking;
pub(crate) mod deletes;
pub(crate) mod embedded;
pub(crate) mod files;
#[cfg(feature = "cluster")]
pub(crate) mod installation;
pub(crate) mod instance;
pub(crate) mod instances;
pub(crate) mod keys;
pub(crate) mod metadata;
pub(crate) mod open;
#[cfg(feature = "cluster")]
pub(crate) mod postgres;
pub(crate) mod quota;
#[cfg(feature = "cluster")]
pub(crate) mod rows;
#[cfg(feature = "cluster")]
pub(crate) mod s3;
pub(crate) mod sqlite;
pub(crate) mod staged;
pub(crate) mod streamed;
pub(crate) mod workers;

#[cfg(test)]
pub(crate) mod conformance;
#[cfg(test)]
pub(crate) mod delete_conformance;
#[cfg(test)]
pub(crate) mod worker_conformance;

pub(crate) use blobs::{BlobStore, body_stream};
pub(crate) use deletes::Claim;
pub(crate) use instances::StopRequest;
pub(crate) use metadata::{
    JobEnd, MetadataStore, SessionStore, StepRecord, TokenStore, UsageStore, VenueStore,
};
pub(crate) use workers::WorkerStore;

/// A server's two stores, borrowed: what code that reads a session's rows and bytes, and
/// nothing else of the server, takes.
#[derive(Clone, Copy)]
pub(crate) struct StoreRefs<'a> {
    pub db: &'a dyn MetadataStore,
    pub blobs: &'a dyn BlobStore,
}

/// Now, in ms since the Unix epoch (0 if the clock is before it): the unit of every stored
/// time.
pub(crate) fn now_ms() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}
