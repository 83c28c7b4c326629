//! The embedded default: the metadata store as SQLite in `DATA/sitar.db`, beside the files of
//! the same data directory. An existing data directory keeps working: the file, its tables and
//! the folder layout are the ones earlier versions wrote.

use std::path::Path;
use std::sync::Arc;

use crate::Error;
use crate::storage::metadata::MetadataStore;
use crate::storage::sqlite::SqliteStore;

/// The database file in a data directory.
pub(crate) const DATABASE_FILE: &str = "sitar.db";

/// Opens (creating when new) the metadata store of data directory `data_dir`.
pub(crate) fn open_metadata(data_dir: &Path) -> Result<Arc<dyn MetadataStore>, Error> {
    std::fs::create_dir_all(data_dir)
        .map_err(|e| Error::io("cannot create data directory", data_dir, e))?;
    Ok(Arc::new(SqliteStore::open(&data_dir.join(DATABASE_FILE))?))
}
