//! What uploads leave in the blob store's hands: an upload staged whole ([`TempFile`]) and
//! what a resumable append made of a body ([`Appended`]).

use std::path::{Path, PathBuf};

use crate::error::Error;

/// What [`crate::storage::BlobStore::append_to`] made of a body.
#[derive(Debug)]
pub(crate) struct Appended {
    /// The file's length now.
    pub len: u64,
    /// Why the body broke off before its end (what arrived is kept), if it did.
    pub broken: Option<Error>,
}

/// An upload in `DATA/tmp`; removed on drop unless published.
#[derive(Debug)]
pub(crate) struct TempFile {
    pub path: PathBuf,
    pub bytes: u64,
}

impl TempFile {
    /// Moves the file to `dest` (same file system: an atomic rename).
    pub fn publish(self, dest: &Path) -> Result<(), Error> {
        if let Some(parent) = dest.parent() {
            std::fs::create_dir_all(parent).map_err(|e| Error::io("cannot create", parent, e))?;
        }
        std::fs::rename(&self.path, dest)
            .map_err(|e| Error::io("cannot move upload to", dest, e))?;
        std::mem::forget(self);
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}
