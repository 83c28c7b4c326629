//! Removing a deleted session's objects: everything under `sessions/ID/`, and under
//! `trash/ID/` where an older version's delete put objects aside. Idempotent: an object
//! already gone (another instance removing the same session) is success. Trash older than
//! [`ORPHAN_AFTER`] (an older version's instance died mid-delete) is removed at start.

use object_store::path::Path as Key;

use super::client::{Bucket, delete, list};
use crate::error::Error;

/// Trash this old is an interrupted delete's: removed at start.
pub(crate) const ORPHAN_AFTER: std::time::Duration = std::time::Duration::from_secs(3600);

/// Objects deleted at once while a session is removed (a bound on requests in flight).
const DELETES_IN_FLIGHT: usize = 8;

/// Removes every object of session `id`; how many there were.
pub(crate) fn remove_session(bucket: &Bucket, id: &str) -> Result<usize, Error> {
    let s3 = bucket.s3.clone();
    let folders = [
        bucket.key(&format!("sessions/{id}")),
        bucket.key(&format!("trash/{id}")),
    ];
    bucket.block(async move {
        use futures_util::{StreamExt, TryStreamExt};
        let mut keys: Vec<Key> = Vec::new();
        for folder in &folders {
            keys.extend(list(&s3, folder).await?.into_iter().map(|m| m.location));
        }
        let removed = keys.len();
        futures_util::stream::iter(keys)
            .map(|key| {
                let s3 = s3.clone();
                async move { delete(&s3, &key).await }
            })
            .buffer_unordered(DELETES_IN_FLIGHT)
            .try_collect::<Vec<()>>()
            .await?;
        Ok(removed)
    })
}

/// Removes trash older than [`ORPHAN_AFTER`]; how many objects.
pub(crate) fn sweep(bucket: &Bucket) -> Result<usize, Error> {
    let (s3, key) = (bucket.s3.clone(), bucket.key("trash"));
    bucket.block(async move {
        let cutoff = ms_ago(ORPHAN_AFTER);
        let mut removed = 0;
        for meta in list(&s3, &key).await? {
            if meta.last_modified.timestamp_millis() < cutoff {
                delete(&s3, &meta.location).await?;
                removed += 1;
            }
        }
        Ok(removed)
    })
}

/// Now minus `ago`, in ms since the Unix epoch.
fn ms_ago(ago: std::time::Duration) -> i64 {
    crate::storage::now_ms() - ago.as_millis() as i64
}
