//! Deleting a session's objects in two steps, as the data directory does with a rename: its
//! objects are copied under `trash/ID/` and removed from `sessions/ID/` (out of sight), then
//! either removed for good or copied back. Trash older than [`ORPHAN_AFTER`] (left by an
//! instance that died in between) is removed at start.

use std::sync::Arc;

use object_store::ObjectStoreExt;
use object_store::path::Path as Key;

use super::cache::LocalCache;
use super::client::{Bucket, delete, list, s3_error};
use crate::Error;
use crate::storage::staged::PutAside;

/// Trash this old is an interrupted delete's: removed at start.
pub(crate) const ORPHAN_AFTER: std::time::Duration = std::time::Duration::from_secs(3600);

/// A session's objects in the trash: (where it was, where it is).
pub(crate) struct Trashed {
    bucket: Arc<Bucket>,
    cache: Arc<LocalCache>,
    id: String,
    moved: Vec<(Key, Key)>,
}

/// Moves session `id`'s objects into the trash; `None` when it has none.
pub(crate) fn take_away(
    bucket: &Arc<Bucket>,
    cache: &Arc<LocalCache>,
    id: &str,
) -> Result<Option<Trashed>, Error> {
    let objects = bucket.list(&format!("sessions/{id}"))?;
    if objects.is_empty() {
        return Ok(None);
    }
    let from_prefix = bucket.key(&format!("sessions/{id}"));
    let to_prefix = bucket.key(&format!("trash/{id}"));
    let moved: Vec<(Key, Key)> = objects
        .into_iter()
        .filter_map(|meta| {
            let rest: Vec<_> = meta.location.prefix_match(&from_prefix)?.collect();
            let to = Key::from_iter(to_prefix.parts().chain(rest));
            Some((meta.location, to))
        })
        .collect();
    let s3 = bucket.s3.clone();
    let pairs = moved.clone();
    bucket.block(async move {
        for (from, to) in &pairs {
            s3.copy(from, to).await.map_err(|e| s3_error(from, e))?;
        }
        for (from, _) in &pairs {
            delete(&s3, from).await?;
        }
        Ok(())
    })?;
    Ok(Some(Trashed {
        bucket: bucket.clone(),
        cache: cache.clone(),
        id: id.to_string(),
        moved,
    }))
}

impl PutAside for Trashed {
    fn restore(self: Box<Self>) -> Result<(), Error> {
        let (s3, pairs) = (self.bucket.s3.clone(), self.moved.clone());
        self.bucket.block(async move {
            for (from, to) in &pairs {
                s3.copy(to, from).await.map_err(|e| s3_error(to, e))?;
            }
            for (_, to) in &pairs {
                delete(&s3, to).await?;
            }
            Ok(())
        })
    }

    fn remove(self: Box<Self>) {
        self.cache.forget_session(&self.id);
        let (s3, pairs) = (self.bucket.s3.clone(), self.moved.clone());
        let removed = self.bucket.block(async move {
            for (_, to) in &pairs {
                delete(&s3, to).await?;
            }
            Ok(())
        });
        if let Err(e) = removed {
            log::warn!(
                "session {}: trash left for the next start's sweep: {e}",
                self.id
            );
        }
    }
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
