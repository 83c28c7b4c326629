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
//!   resumes them; a request that carries a whole recording of declared size goes straight
//!   into a multipart upload of `recording`, sent while it arrives ([`streamed`]) and
//!   completed only when the recording is published (aborted when it is not, and stored as a
//!   part from its staged copy when the body breaks off);
//! - quotas: counted as bytes arrive, against the bucket's usage (listed, reused 30 s);
//! - deletes: a deleted session's objects are removed after its row, idempotently, by the
//!   instance deleting it or, if it died, by any instance's sweep ([`trash`]).
//!
//! Tools that need a path get a local copy ([`cache`], bounded); an `append_line` log is read,
//! extended and put back whole (the session's history: one writer, a few KiB).

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use object_store::path::Path as Key;

use crate::error::Error;
use crate::storage::blobs::{BlobStore, BodyStream, ObjectReader, Upload};
use crate::storage::files::Files;
use crate::storage::keys::SessionObject;
use crate::storage::quota::{DiskQuota, Measure, Reservation};
use crate::storage::staged::{Appended, TempFile};

pub(crate) mod cache;
mod client;
mod local_parts;
mod parts;
mod streamed;
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
    /// Staged recordings and the session each is for: publishing one removes the session's
    /// parts.
    joined: Mutex<std::collections::HashMap<PathBuf, (String, Source)>>,
    /// Whole recordings received (one per session uploading now), waiting for
    /// [`BlobStore::staged_part`]: their staged copy and their unfinished upload.
    streamed: Mutex<std::collections::HashMap<String, Streamed>>,
    /// Local copies of the parts this instance stored.
    local_parts: local_parts::LocalParts,
}

/// Where a staged recording's bytes already are in the bucket.
enum Source {
    /// Nowhere whole: it is sent when published.
    Gathered,
    /// One kept part holds it whole: published by a server-side copy.
    Part(Key),
    /// Sent while it arrived, to `recording`: published by completing that upload.
    Sent(streamed::Sent),
}

/// A whole recording received by [`BlobStore::append_to`].
struct Streamed {
    /// The staged copy (in `DATA/tmp`), owned here until taken or discarded.
    file: PathBuf,
    len: u64,
    /// Its unfinished upload to `recording`; `None` when sending failed (it is then sent
    /// from the staged copy when published).
    sent: Option<streamed::Sent>,
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
            streamed: Mutex::new(Default::default()),
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

    /// Removes session `id`'s parts and their local copies, and gives up its recordings
    /// received whole but not published.
    fn remove_parts(&self, id: &str) -> Result<(), Error> {
        self.forget_uploads(id);
        parts::remove(&self.bucket, id)
    }

    /// Forgets what this instance holds of session `id`'s uploads: local copies of parts,
    /// recordings received whole but not published (their unfinished uploads aborted).
    fn forget_uploads(&self, id: &str) {
        self.local_parts
            .forget_under(&self.bucket.key(&parts::folder(id)));
        let unpublished = self.lock_streamed().remove(id);
        if let Some(whole) = unpublished {
            let _ = std::fs::remove_file(&whole.file);
            self.abort(id, whole.sent);
        }
        self.forget_joined(|_, session| session == id);
    }

    fn lock_streamed(
        &self,
    ) -> std::sync::MutexGuard<'_, std::collections::HashMap<String, Streamed>> {
        self.streamed.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Forgets the staged recordings that `forget` names (by staged path and session),
    /// aborting their unfinished uploads.
    fn forget_joined(&self, forget: impl Fn(&Path, &str) -> bool) {
        let forgotten: Vec<(String, Source)> = {
            let mut joined = self.joined.lock().unwrap_or_else(|p| p.into_inner());
            let paths: Vec<PathBuf> = joined
                .iter()
                .filter(|(path, (session, _))| forget(path, session))
                .map(|(path, _)| path.clone())
                .collect();
            paths.iter().filter_map(|p| joined.remove(p)).collect()
        };
        for (session, source) in forgotten {
            if let Source::Sent(sent) = source {
                self.abort(&session, Some(sent));
            }
        }
    }

    /// Aborts session `id`'s unfinished upload of its recording, in the background.
    fn abort(&self, id: &str, sent: Option<streamed::Sent>) {
        if let Some(sent) = sent {
            let key = self.key(id, SessionObject::Recording);
            if let Err(e) = self.bucket.start(sent.abort(key)) {
                log::warn!("session {id}: {e}");
            }
        }
    }

    /// Aborts an unfinished upload of `key`, in the background.
    fn abort_sent(&self, sent: Option<streamed::Sent>, key: Key) {
        if let Some(sent) = sent
            && let Err(e) = self.bucket.start(sent.abort(key))
        {
            log::warn!("{e}");
        }
    }

    /// The recording size the session's upload declared (`recording.part.total`).
    fn declared_total(&self, id: &str) -> Result<Option<u64>, Error> {
        Ok(self
            .bucket
            .get(self.key(id, SessionObject::RecordingPartTotal))?
            .and_then(|b| String::from_utf8_lossy(&b).trim().parse().ok()))
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
            return self.peek(id, object, usize::MAX);
        }
        self.bucket.get(self.key(id, object))
    }

    fn peek(&self, id: &str, object: SessionObject, max: usize) -> Result<Option<Vec<u8>>, Error> {
        if object == SessionObject::RecordingPart {
            let Some(found) = self.open(id, object)? else {
                return Ok(None);
            };
            let mut head = Vec::new();
            std::io::Read::read_to_end(
                &mut std::io::Read::take(found.bytes, max as u64),
                &mut head,
            )
            .map_err(|e| Error::Internal(format!("session {id}: recording.part: {e}")))?;
            return Ok(Some(head));
        }
        self.bucket.get_start(self.key(id, object), max)
    }

    fn open(&self, id: &str, object: SessionObject) -> Result<Option<ObjectReader>, Error> {
        if object == SessionObject::RecordingPart {
            // The parts joined into a staged file, which is read and then gone.
            let (found, len) = parts::parts(&self.bucket, id)?;
            if found.is_empty() {
                return Ok(None);
            }
            let temp = self.staging.temp_path();
            let opened = parts::gather(&self.bucket, id, len, &temp).and_then(|()| {
                std::fs::File::open(&temp).map_err(|e| Error::io("cannot read", &temp, e))
            });
            let _ = std::fs::remove_file(&temp);
            return opened.map(|file| {
                Some(ObjectReader {
                    len,
                    bytes: Box::new(file),
                })
            });
        }
        Ok(self
            .bucket
            .reader(self.key(id, object))?
            .map(|(len, reader)| ObjectReader {
                len,
                bytes: Box::new(reader),
            }))
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
            // A body from byte 0 that may carry the whole recording of declared size goes
            // straight into an upload of `recording`; any other body into its part's object.
            let total = match offset {
                0 => self.declared_total(id)?.filter(|&t| t > 0 && t <= end),
                _ => None,
            };
            let part = parts::part_key(&self.bucket, id, offset);
            let target = match total {
                Some(_) => self.key(id, SessionObject::Recording),
                None => part.clone(),
            };
            // This request's bytes, staged whole (the checks read them) and sent on meanwhile.
            let temp = TempFile {
                path: self.staging.temp_path(),
                bytes: 0,
            };
            std::fs::File::create(&temp.path)
                .map_err(|e| Error::io("cannot create", &temp.path, e))?;
            let (to, chunks) = tokio::sync::mpsc::channel(streamed::QUEUED_CHUNKS);
            let sending = self.bucket.start(streamed::upload(
                self.bucket.s3.clone(),
                target.clone(),
                chunks,
            ))?;
            let appended = self
                .staging
                .append(
                    streamed::tee(body, to),
                    &temp.path,
                    0,
                    end - offset,
                    what,
                    room,
                )
                .await;
            let sent = match sending.await {
                Ok(Ok(sent)) => Some(sent),
                Ok(Err(e)) => {
                    log::info!("session {id}: {e}; the bytes are sent from the staged copy");
                    None
                }
                Err(e) => {
                    log::warn!("session {id}: the upload to the bucket stopped: {e}");
                    None
                }
            };
            let appended = match appended {
                Ok(appended) => appended,
                Err(e) => {
                    self.abort_sent(sent.map(|(s, _)| s), target);
                    return Err(e);
                }
            };
            // What was sent is what was staged, or it is not used.
            let sent = match sent {
                Some((sent, n)) if n == appended.len => Some(sent),
                Some((sent, n)) => {
                    log::warn!(
                        "session {id}: {n} bytes sent, {} staged; sent from the staged copy",
                        appended.len
                    );
                    self.abort_sent(Some(sent), target.clone());
                    None
                }
                None => None,
            };
            if appended.broken.is_none() && total == Some(appended.len) {
                // The whole recording: kept until it is published or discarded.
                let file = temp.path.clone();
                std::mem::forget(temp);
                let replaced = self.lock_streamed().insert(
                    id.to_string(),
                    Streamed {
                        file,
                        len: appended.len,
                        sent,
                    },
                );
                if let Some(old) = replaced {
                    let _ = std::fs::remove_file(&old.file);
                    self.abort(id, old.sent);
                }
                return Ok(Appended {
                    len: appended.len,
                    broken: None,
                });
            }
            if appended.len > 0 {
                let s3 = self.bucket.s3.clone();
                let e_tag = match sent {
                    Some(sent) if target == part => {
                        self.bucket.spawn(sent.store(s3, part.clone())).await?
                    }
                    other => {
                        // Sent to `recording`, but the body broke off or was short: the
                        // prefix is kept as the part, from the staged copy.
                        self.abort_sent(other, target);
                        self.bucket
                            .spawn(client::upload_file(s3, temp.path.clone(), part.clone()))
                            .await?
                    }
                };
                if let Some(e_tag) = e_tag {
                    let file = temp.path.clone();
                    std::mem::forget(temp);
                    self.local_parts.keep(part, file, e_tag);
                }
            } else {
                self.abort_sent(sent, target);
            }
            Ok(Appended {
                len: offset + appended.len,
                broken: appended.broken,
            })
        })
    }

    fn publish(&self, temp: TempFile, id: &str, object: SessionObject) -> Result<(), Error> {
        if object == SessionObject::RecordingPart {
            // A kept prefix as a whole (`sitar migrate`): one part from byte 0, sent from
            // the staged file a part at a time.
            self.remove_parts(id)?;
            return self.upload(temp.path.clone(), parts::part_key(&self.bucket, id, 0));
        }
        let joined = self
            .joined
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(&temp.path);
        let dest = self.key(id, object);
        let (session, source) = match joined {
            Some((session, source)) => (Some(session), source),
            None => (None, Source::Gathered),
        };
        let copied = match source {
            Source::Sent(sent)
                if session.as_deref() == Some(id) && object == SessionObject::Recording =>
            {
                // Completing the upload sent while the recording arrived makes it visible
                // whole; when that fails it is sent again from the staged copy.
                let done = self
                    .bucket
                    .block(sent.store(self.bucket.s3.clone(), dest.clone()));
                done.map_err(|e| log::info!("session {id}: {e}; the recording is sent again"))
                    .is_ok()
            }
            Source::Sent(sent) => {
                self.abort(session.as_deref().unwrap_or(id), Some(sent));
                false
            }
            Source::Part(part) => {
                let (s3, from, to) = (self.bucket.s3.clone(), part, dest.clone());
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
            Source::Gathered => false,
        };
        if !copied {
            self.upload(temp.path.clone(), dest)?;
        }
        self.cache.forget(&self.cache.object_path(id, object));
        if let Some(session) = session {
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
        // A staged recording dropped unpublished (refused by its check) is gone.
        self.forget_joined(|staged, _| !staged.exists());
        let received = self.lock_streamed().remove(id);
        let joined = match received {
            Some(whole) if whole.len == bytes && std::fs::rename(&whole.file, &path).is_ok() => {
                Ok(whole.sent.map_or(Source::Gathered, Source::Sent))
            }
            other => {
                if let Some(stale) = other {
                    let _ = std::fs::remove_file(&stale.file);
                    self.abort(id, stale.sent);
                }
                parts::parts(&self.bucket, id).and_then(|(found, _)| match &found[..] {
                    [one]
                        if one.bytes == bytes
                            && self.local_parts.link(&one.key, one.e_tag.as_deref(), &path) =>
                    {
                        Ok(Source::Part(one.key.clone()))
                    }
                    _ => parts::gather(&self.bucket, id, bytes, &path).map(|()| Source::Gathered),
                })
            }
        };
        match joined {
            Ok(source) => {
                self.joined
                    .lock()
                    .unwrap_or_else(|p| p.into_inner())
                    .insert(path.clone(), (id.to_string(), source));
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

    fn remove_session(&self, id: &str) -> Result<(), Error> {
        self.forget_uploads(id);
        self.cache.forget_session(id);
        let removed = trash::remove_session(&self.bucket, id)?;
        log::debug!("session {id}: {removed} objects removed");
        Ok(())
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

    /// A recording of declared size larger than a part goes up in parts while it arrives,
    /// invisible until published; broken off, what arrived is the part to resume from.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_large_whole_recording_is_sent_while_it_arrives() {
        let Some(url) = fresh("s3_streamed") else {
            return;
        };
        let dir = tempfile::tempdir().unwrap();
        let idle = std::time::Duration::from_secs(60);
        let store = S3Blobs::open(&url, dir.path(), idle, u64::MAX, u64::MAX).unwrap();
        let id = "s3000000000000002";
        let size = client::PART_BYTES * 2 + 777;
        let big: Vec<u8> = (0..size).map(|i| (i % 253) as u8).collect();
        let body = |upto: usize, broken: bool| {
            let mut items: Vec<Result<axum::body::Bytes, String>> = big[..upto]
                .chunks(300_000)
                .map(|c| Ok(axum::body::Bytes::copy_from_slice(c)))
                .collect();
            if broken {
                items.push(Err("connection reset".into()));
            }
            crate::storage::body_stream(futures_util::stream::iter(items))
        };
        let part = SessionObject::RecordingPart;
        let total = size.to_string();
        store
            .put(id, SessionObject::RecordingPartTotal, total.as_bytes())
            .unwrap();
        let room = store.reserve(Some(id), None).unwrap();
        let cut = store
            .append_to(
                body(size - 5000, true),
                id,
                part,
                0,
                1 << 30,
                "recording",
                room,
            )
            .await
            .unwrap();
        assert_eq!(cut.len, (size - 5000) as u64);
        assert_eq!(store.len(id, part).unwrap(), Some(cut.len));
        assert!(!store.exists(id, SessionObject::Recording));
        store.remove(id, part).unwrap();
        let room = store.reserve(Some(id), None).unwrap();
        let whole = store
            .append_to(body(size, false), id, part, 0, 1 << 30, "recording", room)
            .await
            .unwrap();
        assert_eq!((whole.len, whole.broken.is_none()), (size as u64, true));
        assert!(
            !store.exists(id, SessionObject::Recording),
            "visible too early"
        );
        let staged = store.staged_part(id, size as u64);
        store.publish(staged, id, SessionObject::Recording).unwrap();
        store.remove(id, part).unwrap();
        let local = store.local_file(id, SessionObject::Recording);
        assert!(
            std::fs::read(&local).unwrap() == big,
            "the recording is not what was sent"
        );
        assert!(!store.exists(id, part));
    }

    #[test]
    fn a_store_url_that_is_not_s3_is_refused_naming_it() {
        let err = Bucket::open("file:///tmp/x").err().unwrap().to_string();
        assert!(err.contains("s3://BUCKET/PREFIX"), "{err}");
        let err = Bucket::open("s3:///prefix").err().unwrap().to_string();
        assert!(err.contains("bucket is missing"), "{err}");
    }
}
