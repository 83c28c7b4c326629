//! A resumable recording upload in the bucket: every request's bytes are one object,
//! `sessions/ID/recording.part/OFFSET` (OFFSET in 20 digits), stored whole once its body
//! ended or broke off — so a part is never half-written, and a client resumes against any
//! instance from the sum of the parts. Publishing joins them into the recording and removes
//! them.

use object_store::path::Path as Key;

use super::client::Bucket;
use crate::error::Error;

/// The folder of session `id`'s parts, relative to the prefix.
pub(crate) fn folder(id: &str) -> String {
    format!("sessions/{id}/recording.part")
}

/// The key of the part starting at `offset`.
pub(crate) fn part_key(bucket: &Bucket, id: &str, offset: u64) -> Key {
    bucket.key(&format!("{}/{offset:020}", folder(id)))
}

/// One stored part.
pub(crate) struct Part {
    pub offset: u64,
    pub bytes: u64,
    pub key: Key,
    pub e_tag: Option<String>,
}

/// Session `id`'s parts in order, and the length they make: the
/// parts that follow on from each other from offset 0 (a part that does not, which no
/// sequence of appends leaves, is ignored).
pub(crate) fn parts(bucket: &Bucket, id: &str) -> Result<(Vec<Part>, u64), Error> {
    let mut found: Vec<Part> = bucket
        .list(&folder(id))?
        .into_iter()
        .filter_map(|meta| {
            let offset = meta.location.filename()?.parse::<u64>().ok()?;
            Some(Part {
                offset,
                bytes: meta.size,
                key: meta.location,
                e_tag: meta.e_tag,
            })
        })
        .collect();
    found.sort_by_key(|p| p.offset);
    let mut len = 0;
    let mut kept = Vec::new();
    for part in found {
        if part.offset == len {
            len += part.bytes;
            kept.push(part);
        } else {
            log::warn!(
                "session {id}: part at {} does not follow on from {len}, ignored",
                part.offset
            );
        }
    }
    Ok((kept, len))
}

/// Removes every part of session `id`.
pub(crate) fn remove(bucket: &Bucket, id: &str) -> Result<(), Error> {
    for meta in bucket.list(&folder(id))? {
        bucket.delete(meta.location)?;
    }
    Ok(())
}

/// Joins session `id`'s parts (the first `bytes` of them) into the local file `path`.
pub(crate) fn gather(
    bucket: &std::sync::Arc<Bucket>,
    id: &str,
    bytes: u64,
    path: &std::path::Path,
) -> Result<(), Error> {
    use std::io::Read as _;
    let (parts, len) = parts(bucket, id)?;
    if len < bytes {
        return Err(Error::Internal(format!(
            "session {id}: the kept parts hold {len} bytes, not the expected {bytes}"
        )));
    }
    let mut file = std::fs::File::create(path).map_err(|e| Error::io("cannot create", path, e))?;
    let mut written = 0;
    for Part { key, .. } in parts {
        if written >= bytes {
            break;
        }
        // Read a chunk at a time: a part may be most of a recording.
        let (_, part) = bucket
            .reader(key.clone())?
            .ok_or_else(|| Error::Internal(format!("part {key} went away")))?;
        let copied = std::io::copy(&mut part.take(bytes - written), &mut file)
            .map_err(|e| Error::io(format!("cannot join {key} into"), path, e))?;
        written += copied;
    }
    file.sync_all()
        .map_err(|e| Error::io("cannot write", path, e))
}
