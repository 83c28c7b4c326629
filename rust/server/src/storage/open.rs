//! Which stores an instance opens: the embedded default (SQLite in `DATA/sitar.db`, the data
//! directory's session folders) or, with `--database postgres://…` and `--store s3://…`, the
//! cluster stores (`postgres`, `s3`; built with the `cluster` feature) that several instances
//! share. Either
//! flag alone is allowed (e.g. Postgres with the files on one host). The worker store (hosts
//! and leases of `sitar worker`) lives with the metadata: the data directory's SQLite, or with
//! `--database` the same Postgres, shared by every instance (a host may register, lease and
//! upload on any of them).

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use crate::error::Error;
use crate::storage::blobs::BlobStore;
use crate::storage::files::Files;
use crate::storage::metadata::MetadataStore;
#[cfg(feature = "cluster")]
use crate::storage::postgres::{PgStore, is_postgres_url};
#[cfg(feature = "cluster")]
use crate::storage::s3::S3Blobs;
use crate::storage::workers::WorkerStore;

/// Whether this build has the cluster backends (Postgres metadata, S3-compatible blobs:
/// `--database`, `--store`, `sitar migrate`): the `cluster` feature.
pub const CLUSTER: bool = cfg!(feature = "cluster");

/// What a cluster flag or `sitar migrate` says in a build without the cluster backends.
pub const NO_CLUSTER: &str = "this build has no cluster backends (Postgres, S3-compatible store); \
     build one with `cargo build --release -p sitar-cli --features cluster`";

/// The metadata store: Postgres at `database` when given, else the data directory's SQLite.
pub(crate) fn open_metadata(
    data_dir: &Path,
    database: Option<&str>,
) -> Result<Arc<dyn MetadataStore>, Error> {
    match database {
        None => crate::storage::embedded::open_metadata(data_dir),
        #[cfg(feature = "cluster")]
        Some(url) if is_postgres_url(url) => Ok(Arc::new(PgStore::open(url)?)),
        #[cfg(feature = "cluster")]
        Some(url) => Err(not_postgres(url)),
        #[cfg(not(feature = "cluster"))]
        Some(_) => Err(no_cluster("--database")),
    }
}

/// The error of a cluster flag in a build without the cluster backends.
#[cfg(not(feature = "cluster"))]
fn no_cluster(flag: &str) -> Error {
    Error::Config(format!("{flag}: {}", NO_CLUSTER))
}

/// The error of a `--database` that is not a Postgres URL.
#[cfg(feature = "cluster")]
fn not_postgres(url: &str) -> Error {
    Error::Config(format!(
        "--database {}: expected postgres://USER@HOST:PORT/DATABASE",
        crate::storage::postgres::redact(url)
    ))
}

/// The stores an instance holds: metadata, blobs, and the worker store.
pub(crate) type Stores = (
    Arc<dyn MetadataStore>,
    Arc<dyn BlobStore>,
    Arc<dyn WorkerStore>,
);

/// What the stores are opened with: the part of the server's configuration that is theirs
/// (the configuration itself sits above storage).
pub(crate) struct StoreSettings<'a> {
    pub data_dir: &'a Path,
    /// `--database`: a Postgres URL, or the embedded SQLite store.
    pub database: Option<&'a str>,
    /// `--store`: an S3-compatible bucket URL, or the data directory's files.
    pub store: Option<&'a str>,
    pub upload_idle_timeout: Duration,
    pub session_disk_quota: u64,
    pub disk_quota: u64,
}

/// The stores `config` names.
pub(crate) fn open(config: &StoreSettings<'_>) -> Result<Stores, Error> {
    std::fs::create_dir_all(config.data_dir)
        .map_err(|e| Error::io("cannot create data directory", config.data_dir, e))?;
    let blobs: Arc<dyn BlobStore> = match config.store {
        None => Arc::new(
            Files::open(config.data_dir)?
                .with_idle_timeout(config.upload_idle_timeout)
                .with_quotas(config.session_disk_quota, config.disk_quota),
        ),
        #[cfg(not(feature = "cluster"))]
        Some(_) => return Err(no_cluster("--store")),
        #[cfg(feature = "cluster")]
        Some(url) => Arc::new(S3Blobs::open(
            url,
            config.data_dir,
            config.upload_idle_timeout,
            config.session_disk_quota,
            config.disk_quota,
        )?),
    };
    let (db, workers): (Arc<dyn MetadataStore>, Arc<dyn WorkerStore>) = match config.database {
        None => crate::storage::embedded::open_embedded(config.data_dir)?,
        #[cfg(feature = "cluster")]
        Some(url) if is_postgres_url(url) => {
            let store = Arc::new(PgStore::open(url)?);
            (store.clone(), store)
        }
        #[cfg(feature = "cluster")]
        Some(url) => return Err(not_postgres(url)),
        #[cfg(not(feature = "cluster"))]
        Some(_) => return Err(no_cluster("--database")),
    };
    Ok((db, blobs, workers))
}
