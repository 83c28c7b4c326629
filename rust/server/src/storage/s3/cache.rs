//! The instance's local copies of bucket objects, for the tools that need a path (adb push,
//! the sim player, the MP4 check), and its local working folders. All under `DATA/cache/`:
//!
//! ```text
//! DATA/cache/objects/ID/…   objects fetched for a path; at most OBJECT_BYTES in all (least
//!                           recently used go first); emptied at every start
//! DATA/cache/playback/ID/   playback working files (trials pulled from the phones)
//! DATA/cache/scenes/ID/     scenes rebuilt for the report; at most SCENES (oldest go first)
//! ```
//!
//! A copy is checked against the object's entity tag on every use, so a replaced object is
//! fetched again.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use object_store::ObjectStoreExt;

use super::client::{Bucket, s3_error};
use crate::error::Error;
use crate::storage::keys::SessionObject;

/// Bytes of fetched objects kept at most (the largest object fetched is kept even when it is
/// larger alone).
pub(crate) const OBJECT_BYTES: u64 = 8 << 30;

/// Scenes kept at most.
pub(crate) const SCENES: usize = 64;

/// One fetched object.
struct Copy {
    e_tag: String,
    bytes: u64,
    used: Instant,
}

/// The local copies and folders of one instance.
pub(crate) struct LocalCache {
    root: PathBuf,
    copies: Mutex<HashMap<PathBuf, Copy>>,
}

impl LocalCache {
    /// The cache of data directory `data_dir`; fetched objects of an earlier run are removed
    /// (nothing says which object versions they were).
    pub fn open(data_dir: &Path) -> Result<LocalCache, Error> {
        let root = data_dir.join("cache");
        let objects = root.join("objects");
        if objects.exists() {
            std::fs::remove_dir_all(&objects)
                .map_err(|e| Error::io("cannot empty", &objects, e))?;
        }
        for dir in [&objects, &root.join("playback"), &root.join("scenes")] {
            std::fs::create_dir_all(dir).map_err(|e| Error::io("cannot create", dir, e))?;
        }
        Ok(LocalCache {
            root,
            copies: Mutex::new(HashMap::new()),
        })
    }

    pub fn object_path(&self, id: &str, object: SessionObject) -> PathBuf {
        self.root
            .join("objects")
            .join(id)
            .join(object.relative_path())
    }

    pub fn playback_folder(&self, id: &str) -> PathBuf {
        self.root.join("playback").join(id)
    }

    pub fn scene_folder(&self, id: &str) -> PathBuf {
        self.root.join("scenes").join(id)
    }

    /// Makes `path` a copy of the object at `key` (fetched unless the copy is current).
    pub fn fetch(
        &self,
        bucket: &Bucket,
        key: object_store::path::Path,
        path: &Path,
    ) -> Result<(), Error> {
        let Some((bytes, e_tag)) = bucket.head(key.clone())? else {
            let _ = std::fs::remove_file(path);
            self.lock().remove(path);
            return Err(Error::NotFound(format!("no object {key}")));
        };
        {
            let mut copies = self.lock();
            if let Some(copy) = copies.get_mut(path)
                && copy.e_tag == e_tag
                && path.is_file()
            {
                copy.used = Instant::now();
                return Ok(());
            }
        }
        let temp = path.with_extension(format!("fetch-{}", crate::storage::files::new_id()));
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| Error::io("cannot create", dir, e))?;
        }
        let (s3, target) = (bucket.s3.clone(), temp.clone());
        let fetched = bucket.block(async move { download(&s3, &key, &target).await });
        if let Err(e) = fetched.and_then(|()| {
            std::fs::rename(&temp, path).map_err(|e| Error::io("cannot move into place", path, e))
        }) {
            let _ = std::fs::remove_file(&temp);
            return Err(e);
        }
        self.lock().insert(
            path.to_path_buf(),
            Copy {
                e_tag,
                bytes,
                used: Instant::now(),
            },
        );
        self.evict(path);
        Ok(())
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<PathBuf, Copy>> {
        self.copies.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Removes the least recently used copies (never `keep`) while they pass the bound.
    fn evict(&self, keep: &Path) {
        let mut copies = self.lock();
        let mut total: u64 = copies.values().map(|c| c.bytes).sum();
        while total > OBJECT_BYTES {
            let Some(oldest) = copies
                .iter()
                .filter(|(p, _)| p.as_path() != keep)
                .min_by_key(|(_, c)| c.used)
                .map(|(p, _)| p.clone())
            else {
                break;
            };
            if let Some(copy) = copies.remove(&oldest) {
                total -= copy.bytes;
            }
            let _ = std::fs::remove_file(&oldest);
        }
    }

    /// Forgets the copy of one object.
    pub fn forget(&self, path: &Path) {
        self.lock().remove(path);
        let _ = std::fs::remove_file(path);
    }

    /// Removes everything kept locally for session `id`.
    pub fn forget_session(&self, id: &str) {
        let objects = self.root.join("objects").join(id);
        self.lock().retain(|p, _| !p.starts_with(&objects));
        for dir in [objects, self.playback_folder(id), self.scene_folder(id)] {
            if dir.exists()
                && let Err(e) = std::fs::remove_dir_all(&dir)
            {
                log::warn!("cannot remove {}: {e}", dir.display());
            }
        }
    }

    /// Removes the oldest scenes (by when they were kept) beyond [`SCENES`].
    pub fn bound_scenes(&self) {
        let Ok(entries) = std::fs::read_dir(self.root.join("scenes")) else {
            return;
        };
        let mut scenes: Vec<(std::time::SystemTime, PathBuf)> = entries
            .flatten()
            .filter_map(|e| Some((e.metadata().ok()?.modified().ok()?, e.path())))
            .collect();
        if scenes.len() <= SCENES {
            return;
        }
        scenes.sort();
        for (_, dir) in &scenes[..scenes.len() - SCENES] {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// Streams the object at `key` into the file `path`.
async fn download(
    s3: &object_store::aws::AmazonS3,
    key: &object_store::path::Path,
    path: &Path,
) -> Result<(), Error> {
    use futures_util::StreamExt;
    use tokio::io::AsyncWriteExt;
    let got = s3.get(key).await.map_err(|e| s3_error(key, e))?;
    let file = tokio::fs::File::create(path)
        .await
        .map_err(|e| Error::io("cannot create", path, e))?;
    let mut out = tokio::io::BufWriter::with_capacity(1 << 20, file);
    let mut stream = got.into_stream();
    while let Some(chunk) = stream.next().await {
        let chunk = chunk.map_err(|e| s3_error(key, e))?;
        out.write_all(&chunk)
            .await
            .map_err(|e| Error::io("cannot write", path, e))?;
    }
    out.flush()
        .await
        .map_err(|e| Error::io("cannot write", path, e))
}
