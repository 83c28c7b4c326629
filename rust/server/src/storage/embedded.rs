//! The embedded default: the metadata store as SQLite in `DATA/sitar.db`, beside the files of
//! the same data directory. An existing data directory keeps working: the file, its tables and
//! the folder layout are the ones earlier versions wrote.

use std::path::Path;
use std::sync::Arc;

use crate::error::Error;
use crate::storage::metadata::MetadataStore;
use crate::storage::sqlite::SqliteStore;
use crate::storage::workers::WorkerStore;

/// The database file in a data directory.
pub(crate) const DATABASE_FILE: &str = "sitar.db";

/// Opens (creating when new) the metadata store of data directory `data_dir`.
pub(crate) fn open_metadata(data_dir: &Path) -> Result<Arc<dyn MetadataStore>, Error> {
    Ok(open_embedded(data_dir)?.0)
}

/// The metadata store and the worker store of one data directory.
pub(crate) type Stores = (Arc<dyn MetadataStore>, Arc<dyn WorkerStore>);

/// Opens the embedded store of `data_dir` as both the metadata store and the worker store
/// (one SQLite connection behind both).
pub(crate) fn open_embedded(data_dir: &Path) -> Result<Stores, Error> {
    std::fs::create_dir_all(data_dir)
        .map_err(|e| Error::io("cannot create data directory", data_dir, e))?;
    let store = Arc::new(SqliteStore::open(&data_dir.join(DATABASE_FILE))?);
    Ok((store.clone(), store))
}
