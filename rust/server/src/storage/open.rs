//! Which stores an instance opens: the embedded default (SQLite in `DATA/sitar.db`, the data
//! directory's session folders) or, with `--database postgres://…` and `--store s3://…`, the
//! cluster stores ([`super::postgres`], [`super::s3`]) that several instances share. Either
//! flag alone is allowed (e.g. Postgres with the files on one host).

use std::path::Path;
use std::sync::Arc;

use crate::Error;
use crate::config::ServerConfig;
use crate::storage::blobs::BlobStore;
use crate::storage::files::Files;
use crate::storage::metadata::MetadataStore;
use crate::storage::postgres::{PgStore, is_postgres_url};
use crate::storage::s3::S3Blobs;

/// The metadata store: Postgres at `database` when given, else the data directory's SQLite.
pub(crate) fn open_metadata(
    data_dir: &Path,
    database: Option<&str>,
) -> Result<Arc<dyn MetadataStore>, Error> {
    match database {
        None => crate::storage::embedded::open_metadata(data_dir),
        Some(url) if is_postgres_url(url) => Ok(Arc::new(PgStore::open(url)?)),
        Some(url) => Err(Error::Config(format!(
            "--database {}: expected postgres://USER@HOST:PORT/DATABASE",
            crate::storage::postgres::redact(url)
        ))),
    }
}

/// The two stores an instance holds.
pub(crate) type Stores = (Arc<dyn MetadataStore>, Arc<dyn BlobStore>);

/// Both stores of `config`.
pub(crate) fn open(config: &ServerConfig) -> Result<Stores, Error> {
    std::fs::create_dir_all(&config.data_dir)
        .map_err(|e| Error::io("cannot create data directory", &config.data_dir, e))?;
    let blobs: Arc<dyn BlobStore> = match &config.store {
        None => Arc::new(
            Files::open(&config.data_dir)?
                .with_idle_timeout(config.upload_idle_timeout)
                .with_quotas(config.session_disk_quota, config.disk_quota),
        ),
        Some(url) => Arc::new(S3Blobs::open(
            url,
            &config.data_dir,
            config.upload_idle_timeout,
            config.session_disk_quota,
            config.disk_quota,
        )?),
    };
    let db = open_metadata(&config.data_dir, config.database.as_deref())?;
    Ok((db, blobs))
}
