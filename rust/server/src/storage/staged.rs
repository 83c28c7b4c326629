//! What uploads and deletions leave in the blob store's hands: an upload staged whole
//! ([`TempFile`]), what a resumable append made of a body ([`Appended`]), and a session's
//! objects taken out of sight ([`TakenAway`]).

use std::path::{Path, PathBuf};

use crate::Error;

/// A session's objects taken out of sight by [`crate::storage::BlobStore::take_away`].
pub(crate) struct TakenAway(Box<dyn PutAside>);

/// Objects put aside by one blob store, to be put back or removed.
pub(crate) trait PutAside: Send {
    /// Puts the objects back where they were (the delete did not happen).
    fn restore(self: Box<Self>) -> Result<(), Error>;
    /// Removes them for good.
    fn remove(self: Box<Self>);
}

impl std::fmt::Debug for TakenAway {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("TakenAway")
    }
}

/// A session folder renamed into the trash folder.
struct Folder {
    dir: PathBuf,
    trash: PathBuf,
}

impl PutAside for Folder {
    fn restore(self: Box<Self>) -> Result<(), Error> {
        std::fs::rename(&self.trash, &self.dir)
            .map_err(|e| Error::io("cannot move back", &self.dir, e))
    }

    /// What a failure leaves, the next start removes.
    fn remove(self: Box<Self>) {
        if let Err(e) = std::fs::remove_dir_all(&self.trash) {
            log::warn!("cannot remove {}: {e}", self.trash.display());
        }
    }
}

impl TakenAway {
    /// Files that were at `dir` and are at `trash` now.
    pub(crate) fn new(dir: PathBuf, trash: PathBuf) -> TakenAway {
        TakenAway(Box::new(Folder { dir, trash }))
    }

    /// Objects a blob store put aside its own way.
    #[cfg_attr(not(feature = "cluster"), allow(dead_code))] // the cluster stores use it
    pub(crate) fn put_aside(objects: Box<dyn PutAside>) -> TakenAway {
        TakenAway(objects)
    }

    /// Puts the objects back where they were (the delete did not happen).
    pub fn restore(self) -> Result<(), Error> {
        self.0.restore()
    }

    /// Removes the objects for good.
    pub fn remove(self) {
        self.0.remove()
    }
}

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
