//! One session's objects on both sides: each is hashed (SHA-256) here and in the bucket;
//! one the bucket lacks, or holds differently while the session's rows are not copied yet
//! (a run that was interrupted), is stored and hashed again. One the bucket holds
//! differently after the session's rows were copied is a difference, never overwritten.

use crate::error::Error;
use crate::storage::BlobStore;
use crate::storage::installation::{Installation, sha256_in};

/// What one session's objects came to.
#[derive(Debug, Default)]
pub(crate) struct Copied {
    pub objects: usize,
    pub bytes: u64,
    pub copied: usize,
    pub copied_bytes: u64,
    /// Objects that differ after the copy, described.
    pub differences: Vec<String>,
    /// Files in the folder that are no object (not copied).
    pub unknown: Vec<String>,
}

/// Copies session `id`'s objects into `blobs`; `rows_copied` says whether the database holds
/// the session's row already (its objects were complete then).
pub(crate) fn copy_session(
    source: &Installation,
    blobs: &dyn BlobStore,
    id: &str,
    rows_copied: bool,
) -> Result<Copied, Error> {
    let objects = source.objects(id)?;
    let mut copied = Copied {
        unknown: objects.unknown,
        ..Default::default()
    };
    for (object, len) in objects.found {
        let name = format!("sessions/{id}/{}", object.relative_path());
        copied.objects += 1;
        copied.bytes += len;
        let here = source.sha256(id, object)?;
        let there = sha256_in(blobs, id, object)?;
        match &there {
            Some((_, sha)) if *sha == here => continue,
            Some((_, sha)) if rows_copied => {
                copied.differences.push(format!(
                    "{name}: SHA-256 {here} here but {sha} in the store (the session was \
                     copied before: one side changed since)"
                ));
                continue;
            }
            _ => {}
        }
        source
            .copy_into(id, object, blobs)
            .map_err(|e| Error::Internal(format!("{name}: {e}")))?;
        copied.copied += 1;
        copied.copied_bytes += len;
        match sha256_in(blobs, id, object)? {
            Some((_, sha)) if sha == here => {}
            Some((_, sha)) => copied.differences.push(format!(
                "{name}: SHA-256 {here} here but {sha} in the store after the copy"
            )),
            None => copied
                .differences
                .push(format!("{name}: not in the store after the copy")),
        }
    }
    Ok(copied)
}
