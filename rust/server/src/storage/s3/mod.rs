//! The cluster blob store: an S3-compatible bucket (`sitar serve --store s3://BUCKET/PREFIX`;
//! endpoint, region and credentials from the usual `AWS_*` variables: `AWS_ENDPOINT_URL`,
//! `AWS_REGION`, `AWS_ACCESS_KEY_ID`, `AWS_SECRET_ACCESS_KEY`, `AWS_ALLOW_HTTP` for a
//! plain-HTTP endpoint). Every object of a session is `PREFIX/sessions/ID/` + the embedded
//! layout's relative path ([`SessionObject::relative_path`]).
//!
//! The guarantees of [`BlobStore`], kept the bucket's way:
//! - whole objects: a PUT replaces an object atomically; a large upload is a multipart upload
//!   that is visible only once complete;
//! - uploads are staged in the instance's `DATA/tmp` (emptied at start: nothing partial
//!   survives a crash) and published whole;
//! - resumable recordings: one object per request's bytes ([`parts`]), so any instance
//!   resumes them;
//! - quotas: counted as bytes arrive, against the bucket's usage (listed, reused 30 s);
//! - deletes: objects put aside in `trash/` first ([`trash`]).
//!
//! Tools that need a path get a local copy ([`cache`], bounded); an `append_line` log is read,
//! extended and put back whole (the session's history: one writer, a few KiB).

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use object_store::path::Path as Key;

use crate::Error;
use crate::storage::blobs::{BlobStore, BodyStream, Upload};
use crate::storage::files::Files;
use crate::storage::keys::SessionObject;
use crate::storage::quota::{DiskQuota, Measure, Reservation};
use crate::storage::staged::{Appended, TakenAway, TempFile};

pub(crate) mod cache;
mod client;
mod local_parts;
mod parts;
mod trash;

use cache::LocalCache;
use client::Bucket;

/// The file in a kept scene folder that names what the scene was built from.
const SCENE_TAG: &str = "source.txt";

/// The bucket's usage, listed.
struct BucketUsage(Arc<Bucket>);

impl std::fmt::Debug for BucketUsage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "BucketUsage({})", self.0.url)
    }
}

impl BucketUsage {
    fn bytes(&self, folder: &str) -> u64 {
        match self.0.list(folder) {
            Ok(objects) => objects.iter().map(|o| o.size).sum(),
            Err(e) => {
                log::warn!("quota: cannot list {folder} of {}: {e}", self.0.url);
                0
            }
        }
    }
}

impl Measure for BucketUsage {
    fn total(&self) -> u64 {
        self.bytes("sessions")
    }

    fn session(&self, id: &str) -> u64 {
        self.bytes(&format!("sessions/{id}"))
    }

    fn reuse_for(&self) -> std::time::Duration {
        std::time::Duration::from_secs(30)
    }
}

/// The cluster blob store.
pub(crate) struct S3Blobs {
    bucket: Arc<Bucket>,
    /// Uploads are staged in `DATA/tmp` through the embedded store's streaming code, counted
    /// against the bucket's quotas.
    staging: Files,
    cache: Arc<LocalCache>,
    /// Staged recordings made of kept parts: publishing one removes the parts; a recording
    /// that is one part whole is published by a server-side copy of that part.
    joined: Mutex<std::collections::HashMap<PathBuf, (String, Option<Key>)>>,
    /// Local copies of the parts this instance stored.
    local_parts: local_parts::LocalParts,
}

impl S3Blobs {
    /// The bucket of `url`, with instance-local files in `data_dir`; `session` and `global`
    /// are the quotas in bytes, `idle` the stall after which a body counts as broken off.
    pub fn open(
        url: &str,
        data_dir: &Path,
        idle: std::time::Duration,
        session: u64,
        global: u64,
    ) -> Result<S3Blobs, Error> {
        let bucket = Arc::new(Bucket::open(url)?);
        // A store that does not answer is an error at start, naming it.
        bucket
            .list("sessions/s0000000000000000")
            .map_err(|e| Error::Config(format!("--store {url}: {e}")))?;
        match trash::sweep(&bucket) {
            Ok(0) => {}
            Ok(n) => log::info!("{url}: removed {n} objects of interrupted deletes"),
            Err(e) => log::warn!("{url}: cannot sweep the trash: {e}"),
        }
        let quota = Arc::new(DiskQuota::measured(
            Box::new(BucketUsage(bucket.clone())),
            session,
            global,
        ));
        let staging = Files::open(data_dir)?
            .with_idle_timeout(idle)
            .with_quota(quota);
        Ok(S3Blobs {
            cache: Arc::new(LocalCache::open(data_dir)?),
            bucket,
            staging,
            joined: Mutex::new(Default::default()),
            local_parts: Default::default(),
        })
    }

    fn key(&self, id: &str, object: SessionObject) -> Key {
        debug_assert!(crate::storage::files::is_server_id(id));
        self.bucket
            .key(&format!("sessions/{id}/{}", object.relative_path()))
    }

    fn upload(&self, path: PathBuf, key: Key) -> Result<(), Error> {
        let s3 = self.bucket.s3.clone();
        self.bucket
            .block(client::upload_file(s3, path, key))
            .map(|_| ())
    }

    /// Removes session `id`'s parts and their local copies.
    fn remove_parts(&self, id: &str) -> Result<(), Error> {
        self.local_parts
            .forget_under(&self.bucket.key(&parts::folder(id)));
        parts::remove(&self.bucket, id)
    }
}

impl BlobStore for S3Blobs {
    fn reserve(&self, id: Option<&str>, declared: Option<u64>) -> Result<Reservation<'_>, Error> {
        self.staging.reserve(id, declared)
    }

    /// Nothing to make: a bucket has no folders.
    fn create_session(&self, _id: &str) -> Result<(), Error> {
        Ok(())
    }

    fn exists(&self, id: &str, object: SessionObject) -> bool {
        match self.len(id, object) {
            Ok(len) => len.is_some(),
            Err(e) => {
                log::warn!("session {id}: {e}");
                false
            }
        }
    }

    fn get(&self, id: &str, object: SessionObject) -> Result<Option<Vec<u8>>, Error> {
        if object == SessionObject::RecordingPart {
            let (found, len) = parts::parts(&self.bucket, id)?;
            if found.is_empty() {
                return Ok(None);
            }
            let temp = self.staging.temp_path();
            let joined = parts::gather(&self.bucket, id, len, &temp).and_then(|()| {
                std::fs::read(&temp).map_err(|e| Error::io("cannot read", &temp, e))
            });
            let _ = std::fs::remove_file(&temp);
            return joined.map(Some);
        }
        self.bucket.get(self.key(id, object))
    }

    fn len(&self, id: &str, object: SessionObject) -> Result<Option<u64>, Error> {
        if object == SessionObject::RecordingPart {
            let (found, len) = parts::parts(&self.bucket, id)?;
            return Ok((!found.is_empty()).then_some(len));
        }
        Ok(self.bucket.head(self.key(id, object))?.map(|(len, _)| len))
    }

    fn put(&self, id: &str, object: SessionObject, bytes: &[u8]) -> Result<(), Error> {
        if object == SessionObject::RecordingPart {
            self.remove_parts(id)?;
            return self
                .bucket
                .put(parts::part_key(&self.bucket, id, 0), bytes.to_vec());
        }
        self.bucket.put(self.key(id, object), bytes.to_vec())
    }

    fn append_line(&self, id: &str, object: SessionObject, line: &str) -> Result<(), Error> {
        let key = self.key(id, object);
        let mut log = self.bucket.get(key.clone())?.unwrap_or_default();
        log.extend_from_slice(line.as_bytes());
        log.push(b'\n');
        self.bucket.put(key, log)
    }

    fn remove(&self, id: &str, object: SessionObject) -> Result<(), Error> {
        if object == SessionObject::RecordingPart {
            return self.remove_parts(id);
        }
        self.cache.forget(&self.cache.object_path(id, object));
        self.bucket.delete(self.key(id, object))
    }

    /// A local copy (fetched when missing or out of date); when it cannot be fetched, the
    /// path where it would be, which the tool then fails to open, naming it.
    fn local_file(&self, id: &str, object: SessionObject) -> PathBuf {
        let path = self.cache.object_path(id, object);
        if let Err(e) = self.cache.fetch(&self.bucket, self.key(id, object), &path) {
            log::warn!("session {id}: cannot fetch {}: {e}", object.relative_path());
        }
        path
    }

    fn receive<'a>(
        &'a self,
        body: BodyStream<'a>,
        limit: u64,
        what: &'static str,
    ) -> Upload<'a, TempFile> {
        self.staging.receive(body, limit, what)
    }

    fn receive_bytes_into<'a>(
        &'a self,
        body: BodyStream<'a>,
        limit: u64,
        what: &'static str,
        room: Reservation<'a>,
    ) -> Upload<'a, Vec<u8>> {
        self.staging.receive_bytes_into(body, limit, what, room)
    }

    fn append_to<'a>(
        &'a self,
        body: BodyStream<'a>,
        id: &'a str,
        object: SessionObject,
        offset: u64,
        end: u64,
        what: &'static str,
        room: Reservation<'a>,
    ) -> Upload<'a, Appended> {
        Box::pin(async move {
            if object != SessionObject::RecordingPart {
                return Err(Error::Internal(format!(
                    "{}: only a recording is uploaded in parts",
                    object.relative_path()
                )));
            }
            let (_, len) = parts::parts(&self.bucket, id)?;
            if len != offset {
                return Err(Error::Internal(format!(
                    "session {id}: the kept upload is {len} bytes, not the expected {offset}"
                )));
            }
            // This request's bytes, staged whole, then stored as one part.
            let temp = TempFile {
                path: self.staging.temp_path(),
                bytes: 0,
            };
            std::fs::File::create(&temp.path)
                .map_err(|e| Error::io("cannot create", &temp.path, e))?;
            let appended = self
                .staging
                .append(body, &temp.path, 0, end - offset, what, room)
                .await?;
            if appended.len > 0 {
                let key = parts::part_key(&self.bucket, id, offset);
                let s3 = self.bucket.s3.clone();
                let e_tag = self
                    .bucket
                    .spawn(client::upload_file(s3, temp.path.clone(), key.clone()))
                    .await?;
                if let Some(e_tag) = e_tag {
                    let file = temp.path.clone();
                    std::mem::forget(temp);
                    self.local_parts.keep(key, file, e_tag);
                }
            }
            Ok(Appended {
                len: offset + appended.len,
                broken: appended.broken,
            })
        })
    }

    fn publish(&self, temp: TempFile, id: &str, object: SessionObject) -> Result<(), Error> {
        let joined = self
            .joined
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(&temp.path);
        let dest = self.key(id, object);
        let copied = match &joined {
            Some((_, Some(part))) => {
                let (s3, from, to) = (self.bucket.s3.clone(), part.clone(), dest.clone());
                let copy = self.bucket.block(async move {
                    use object_store::ObjectStoreExt;
                    s3.copy(&from, &to)
                        .await
                        .map_err(|e| client::s3_error(&from, e))
                });
                // A copy the store refuses (e.g. past its size for one copy): sent instead.
                copy.map_err(|e| log::info!("session {id}: {e}; the recording is sent again"))
                    .is_ok()
            }
            _ => false,
        };
        if !copied {
            self.upload(temp.path.clone(), dest)?;
        }
        self.cache.forget(&self.cache.object_path(id, object));
        if let Some((session, _)) = joined {
            self.remove_parts(&session)?;
        }
        drop(temp);
        Ok(())
    }

    /// The kept parts joined into a staged file (empty, so that publishing fails naming it,
    /// when they cannot be read). A recording this instance received whole is its own local
    /// copy of the one part: nothing is read back from the bucket.
    fn staged_part(&self, id: &str, bytes: u64) -> TempFile {
        let path = self.staging.temp_path();
        let joined = parts::parts(&self.bucket, id).and_then(|(found, _)| match &found[..] {
            [one]
                if one.bytes == bytes
                    && self.local_parts.link(&one.key, one.e_tag.as_deref(), &path) =>
            {
                Ok(Some(one.key.clone()))
            }
            _ => parts::gather(&self.bucket, id, bytes, &path).map(|()| None),
        });
        match joined {
            Ok(part) => {
                let mut joined = self.joined.lock().unwrap_or_else(|p| p.into_inner());
                // A staged recording dropped unpublished (refused by its check) is gone.
                joined.retain(|staged, _| staged.exists());
                joined.insert(path.clone(), (id.to_string(), part));
            }
            Err(e) => {
                log::warn!("session {id}: cannot join the kept upload: {e}");
                let _ = std::fs::remove_file(&path);
            }
        }
        TempFile { path, bytes }
    }

    fn same_content(
        &self,
        temp: &TempFile,
        id: &str,
        object: SessionObject,
    ) -> Result<bool, Error> {
        let Some((len, _)) = self.bucket.head(self.key(id, object))? else {
            return Ok(false);
        };
        let local = std::fs::metadata(&temp.path)
            .map_err(|e| Error::io("cannot stat", &temp.path, e))?
            .len();
        if len != local {
            return Ok(false);
        }
        let copy = self.cache.object_path(id, object);
        self.cache
            .fetch(&self.bucket, self.key(id, object), &copy)?;
        same_file(&temp.path, &copy)
    }

    fn take_away(&self, id: &str) -> Result<Option<TakenAway>, Error> {
        self.local_parts
            .forget_under(&self.bucket.key(&parts::folder(id)));
        let taken = trash::take_away(&self.bucket, &self.cache, id)?;
        match taken {
            Some(t) => Ok(Some(TakenAway::put_aside(Box::new(t)))),
            None => {
                self.cache.forget_session(id);
                Ok(None)
            }
        }
    }

    fn playback_folder(&self, id: &str) -> PathBuf {
        self.cache.playback_folder(id)
    }

    fn scene_folder(&self, id: &str) -> PathBuf {
        self.cache.scene_folder(id)
    }

    fn kept_scene(&self, id: &str) -> Option<(PathBuf, String)> {
        let dir = self.scene_folder(id);
        let tag = std::fs::read_to_string(dir.join(SCENE_TAG)).ok()?;
        Some((dir, tag.trim().to_string()))
    }

    fn discard_scene(&self, id: &str) {
        let dir = self.scene_folder(id);
        if dir.exists()
            && let Err(e) = std::fs::remove_dir_all(&dir)
        {
            log::warn!("cannot remove {}: {e}", dir.display());
        }
    }

    fn keep_scene(&self, id: &str, tag: &str, save: &mut dyn FnMut(&Path) -> bool) -> bool {
        let scratch = self.staging.temp_path().with_extension("scene");
        let kept = save(&scratch)
            && std::fs::write(scratch.join(SCENE_TAG), tag).is_ok()
            && std::fs::rename(&scratch, self.scene_folder(id)).is_ok();
        if !kept {
            let _ = std::fs::remove_dir_all(&scratch);
        }
        self.cache.bound_scenes();
        kept
    }
}

/// Whether two local files hold the same bytes.
fn same_file(a: &Path, b: &Path) -> Result<bool, Error> {
    use std::io::Read;
    let open = |p: &Path| std::fs::File::open(p).map_err(|e| Error::io("cannot open", p, e));
    let (mut fa, mut fb) = (open(a)?, open(b)?);
    let (mut ba, mut bb) = (vec![0u8; 1 << 20], vec![0u8; 1 << 20]);
    loop {
        let n = fa
            .read(&mut ba)
            .map_err(|e| Error::io("cannot read", a, e))?;
        if n == 0 {
            let more = fb
                .read(&mut bb[..1])
                .map_err(|e| Error::io("cannot read", b, e))?;
            return Ok(more == 0);
        }
        if fb.read_exact(&mut bb[..n]).is_err() || ba[..n] != bb[..n] {
            return Ok(false);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh prefix of the test bucket (`SITAR_TEST_S3_URL`), or `None` after printing
    /// SKIPPED.
    pub(crate) fn fresh(test: &str) -> Option<String> {
        let Some(url) = std::env::var("SITAR_TEST_S3_URL")
            .ok()
            .filter(|u| !u.is_empty())
        else {
            println!(
                "SKIPPED {test}: SITAR_TEST_S3_URL is not set (scripts/cluster-services start)"
            );
            return None;
        };
        Some(format!(
            "{}/{test}-{}",
            url.trim_end_matches('/'),
            crate::storage::files::new_id()
        ))
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn the_bucket_passes_the_conformance_suite() {
        let Some(url) = fresh("s3_conformance") else {
            return;
        };
        let dir = tempfile::tempdir().unwrap();
        let store = S3Blobs::open(
            &url,
            dir.path(),
            std::time::Duration::from_secs(60),
            u64::MAX,
            u64::MAX,
        )
        .unwrap();
        crate::storage::conformance::blob_store(&store).await;
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn quotas_count_what_the_bucket_holds() {
        let Some(url) = fresh("s3_quota") else {
            return;
        };
        let dir = tempfile::tempdir().unwrap();
        let store = S3Blobs::open(
            &url,
            dir.path(),
            std::time::Duration::from_secs(60),
            1000,
            u64::MAX,
        )
        .unwrap();
        let id = "s3000000000000001";
        store
            .put(id, SessionObject::Recording, &[7u8; 600])
            .unwrap();
        // 400 bytes are left in the session: 401 declared is refused before reading.
        let err = store.reserve(Some(id), Some(401)).unwrap_err();
        assert_eq!(err.status_and_code().0.as_u16(), 413, "{err}");
        assert!(store.reserve(Some(id), Some(400)).is_ok());
        // A large object goes up in parts and comes back whole, also as a local file.
        let big: Vec<u8> = (0..(client::PART_BYTES * 2 + 12345))
            .map(|i| (i % 251) as u8)
            .collect();
        let staged = dir.path().join("tmp").join("big");
        std::fs::write(&staged, &big).unwrap();
        let temp = TempFile {
            path: staged,
            bytes: big.len() as u64,
        };
        store.publish(temp, id, SessionObject::Trial(0)).unwrap();
        assert_eq!(
            store.len(id, SessionObject::Trial(0)).unwrap(),
            Some(big.len() as u64)
        );
        let local = store.local_file(id, SessionObject::Trial(0));
        assert_eq!(std::fs::read(&local).unwrap(), big);
        // Replaced in the bucket, the local copy follows.
        store.put(id, SessionObject::Trial(0), b"short").unwrap();
        assert_eq!(
            std::fs::read(store.local_file(id, SessionObject::Trial(0))).unwrap(),
            b"short"
        );
    }

    #[test]
    fn a_store_url_that_is_not_s3_is_refused_naming_it() {
        let err = Bucket::open("file:///tmp/x").err().unwrap().to_string();
        assert!(err.contains("s3://BUCKET/PREFIX"), "{err}");
        let err = Bucket::open("s3:///prefix").err().unwrap().to_string();
        assert!(err.contains("bucket is missing"), "{err}");
    }
}
