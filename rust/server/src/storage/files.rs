//! The embedded blob store ([`BlobStore`]): the data directory's session folders, written
//! with temp files renamed into place (atomic replace), bodies streamed with 1 MiB buffered
//! writes, one idle timer per body and the disk quotas counted as bytes arrive; `tmp/` is
//! emptied at every start, so nothing partial survives a crash.

use std::hash::{BuildHasher, Hasher};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use axum::body::Bytes;
use futures_util::{Stream, StreamExt};
use tokio::io::AsyncWriteExt;

use crate::error::Error;
use crate::storage::blobs::{BlobStore, BodyStream, ObjectReader, Upload};
use crate::storage::keys::SessionObject;
use crate::storage::quota::{DiskQuota, Reservation};
use crate::storage::staged::{Appended, TempFile};

/// The data directory's file layout. Every path is made here, from server-made ids and
/// indices only (a session's objects are typed, [`SessionObject`]): no client-supplied name
/// becomes a path.
///
/// ```text
/// DATA/sitar.db                       the embedded metadata store (storage::sqlite)
/// DATA/admin.token                    the first start's admin token (auth::bootstrap)
/// DATA/tls/cert.pem, key.pem          the self-signed TLS certificate of `--tls` (http::tls)
/// DATA/tmp/upload-*.part              uploads and atomic writes in progress (cleared at start)
/// DATA/tmp/deleted-ID                 a deleted session's folder, until removed (cleared at start)
/// DATA/tmp/phone-*                    a phone session being rebuilt for the scene (cleared at start)
/// DATA/sessions/ID/recording          the uploaded recording (mp4 or sim recording)
/// DATA/sessions/ID/recording.part     a recording upload as it arrives; kept when it breaks off
/// DATA/sessions/ID/recording.part.key the Idempotency-Key of the upload they belong to
/// DATA/sessions/ID/recording.part.total the total length the upload declared
/// DATA/sessions/ID/trials/trial_NNN.txt   one TUM file per finished trial
/// DATA/sessions/ID/timestamps.txt     legacy POST /timestamps upload
/// DATA/sessions/ID/results.csv|json   latest published estimate
/// DATA/sessions/ID/history.jsonl      one line per published estimate (the report's history)
/// DATA/sessions/ID/evidence.json      the phone's evidence.csv, validated and parsed once
/// DATA/sessions/ID/spans.json         start and end of each sub-trajectory
/// DATA/sessions/ID/thumbnails/K.jpg   sub-trajectory K's camera thumbnail
/// DATA/sessions/ID/phone/             the phone session rebuilt for the scene (sitar-core folder)
/// DATA/sessions/ID/adb-pull/          trials pulled from the phones before they are parsed
/// ```
#[derive(Debug, Clone)]
pub(crate) struct Files {
    root: PathBuf,
    /// A body that sends nothing for this long is treated as broken off.
    idle: std::time::Duration,
    /// Every upload streamed here counts against it.
    quota: std::sync::Arc<DiskQuota>,
}

/// The file in a kept scene folder that names what the scene was built from.
const SCENE_TAG: &str = "source.txt";

/// Default of [`Files::with_idle_timeout`].
const DEFAULT_IDLE: std::time::Duration = std::time::Duration::from_secs(60);

/// Removes folder `dir` and what it holds; one that is not there is success.
fn remove_folder(dir: &Path) -> Result<(), Error> {
    match std::fs::remove_dir_all(dir) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(Error::io("cannot remove", dir, e)),
    }
}

/// A fresh server-made id: `s` and 16 hex digits.
pub(crate) fn new_id() -> String {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u64(COUNTER.fetch_add(1, Ordering::Relaxed));
    h.write_u128(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0),
    );
    format!("s{:016x}", h.finish())
}

/// Whether `id` has the shape of a server-made id (and so is safe in a path).
pub(crate) fn is_server_id(id: &str) -> bool {
    id.len() == 17
        && id.starts_with('s')
        && id[1..]
            .bytes()
            .all(|b| b.is_ascii_hexdigit() && !b.is_ascii_uppercase())
}

impl Files {
    pub fn open(root: &Path) -> Result<Files, Error> {
        for dir in [root.to_path_buf(), root.join("sessions"), root.join("tmp")] {
            std::fs::create_dir_all(&dir).map_err(|e| Error::io("cannot create", &dir, e))?;
        }
        // Half-written uploads and deleted sessions' folders of a dead process are garbage.
        if let Ok(entries) = std::fs::read_dir(root.join("tmp")) {
            for entry in entries.flatten() {
                let path = entry.path();
                let _ = if path.is_dir() {
                    std::fs::remove_dir_all(&path)
                } else {
                    std::fs::remove_file(&path)
                };
            }
        }
        Ok(Files {
            root: root.to_path_buf(),
            idle: DEFAULT_IDLE,
            quota: std::sync::Arc::new(DiskQuota::new(root, u64::MAX, u64::MAX)),
        })
    }

    /// The same files, with bodies that stall longer than `idle` treated as broken off:
    /// what arrived is kept (a recording can be resumed), and the request ends instead of
    /// holding its session for as long as a silent client keeps the connection open.
    pub fn with_idle_timeout(mut self, idle: std::time::Duration) -> Files {
        self.idle = idle;
        self
    }

    /// The same files with disk quotas: `session` bytes per session folder, `global` bytes
    /// for the whole data directory.
    pub fn with_quotas(mut self, session: u64, global: u64) -> Files {
        self.quota = std::sync::Arc::new(DiskQuota::new(&self.root, session, global));
        self
    }

    /// The same files counting every upload against `quota` (the cluster store stages its
    /// uploads here, counted against the bucket's quotas).
    #[cfg_attr(not(feature = "cluster"), allow(dead_code))] // the cluster stores use it
    pub fn with_quota(mut self, quota: std::sync::Arc<DiskQuota>) -> Files {
        self.quota = quota;
        self
    }

    /// A fresh path in `DATA/tmp` (emptied at every start).
    pub fn temp_path(&self) -> PathBuf {
        self.root
            .join("tmp")
            .join(format!("upload-{}.part", new_id()))
    }

    fn session_dir(&self, id: &str) -> PathBuf {
        debug_assert!(is_server_id(id));
        self.root.join("sessions").join(id)
    }

    /// Where `object` of session `id` lives.
    fn path(&self, id: &str, object: SessionObject) -> PathBuf {
        self.session_dir(id).join(object.relative_path())
    }

    /// Writes small server-made content atomically (temp file + rename).
    fn write_atomic(&self, dest: &Path, content: &[u8]) -> Result<(), Error> {
        let temp = TempFile {
            path: self.temp_path(),
            bytes: content.len() as u64,
        };
        std::fs::write(&temp.path, content)
            .map_err(|e| Error::io("cannot write", &temp.path, e))?;
        temp.publish(dest)
    }

    /// [`BlobStore::append_to`] at `path`.
    pub(crate) async fn append<S, E>(
        &self,
        mut body: S,
        path: &Path,
        offset: u64,
        end: u64,
        what: &'static str,
        room: Reservation<'_>,
    ) -> Result<Appended, Error>
    where
        S: Stream<Item = Result<Bytes, E>> + Unpin,
        E: std::fmt::Display,
    {
        let mut file = tokio::fs::OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .await
            .map_err(|e| Error::io("cannot open", path, e))?;
        let len = file
            .metadata()
            .await
            .map_err(|e| Error::io("cannot stat", path, e))?
            .len();
        if len != offset {
            return Err(Error::Internal(format!(
                "{} is {len} bytes, not the expected {offset}",
                path.display()
            )));
        }
        use tokio::io::AsyncSeekExt;
        file.seek(std::io::SeekFrom::Start(offset))
            .await
            .map_err(|e| Error::io("cannot seek in", path, e))?;
        let mut sink = Sink::new(file, path, offset, self.idle, room);
        match sink.copy(&mut body, end, what).await {
            Ok(()) => Ok(Appended {
                len: sink.written,
                broken: None,
            }),
            Err(Copy::BrokeOff(error)) => Ok(Appended {
                len: sink.written,
                broken: Some(error),
            }),
            Err(Copy::Failed(error)) => {
                let error = match error {
                    Error::TooLarge { .. } => Error::BadRequest(format!(
                        "{what}: the body is longer than its Content-Range ({} bytes)",
                        end - offset
                    )),
                    other => other,
                };
                sink.room.discard();
                let file = sink.out.into_inner();
                file.set_len(offset)
                    .await
                    .map_err(|e| Error::io("cannot truncate", path, e))?;
                Err(error)
            }
        }
    }

    /// Streams `body` into a temporary file, refusing more than `limit` bytes (and what
    /// would pass the global disk quota). The caller moves the result into place with
    /// [`BlobStore::publish`]; a body that breaks off leaves nothing.
    async fn receive_stream<S, E>(
        &self,
        mut body: S,
        limit: u64,
        what: &'static str,
    ) -> Result<TempFile, Error>
    where
        S: Stream<Item = Result<Bytes, E>> + Unpin,
        E: std::fmt::Display,
    {
        let mut temp = TempFile {
            path: self.temp_path(),
            bytes: 0,
        };
        let file = tokio::fs::File::create(&temp.path)
            .await
            .map_err(|e| Error::io("cannot create", &temp.path, e))?;
        let room = self.reserve(None, None)?;
        let mut sink = Sink::new(file, &temp.path, 0, self.idle, room);
        let outcome = sink.copy(&mut body, limit, what).await;
        temp.bytes = sink.written;
        if outcome.is_err() {
            // The temporary file goes: its bytes stop counting.
            sink.room.discard();
        }
        drop(sink);
        match outcome {
            Ok(()) => Ok(temp),
            Err(Copy::BrokeOff(error) | Copy::Failed(error)) => Err(error),
        }
    }

    /// Reads `body` into memory under `room`'s quotas, refusing more than `limit` bytes.
    async fn read_stream<S, E>(
        &self,
        mut body: S,
        limit: u64,
        what: &'static str,
        room: Reservation<'_>,
    ) -> Result<Vec<u8>, Error>
    where
        S: Stream<Item = Result<Bytes, E>> + Unpin,
        E: std::fmt::Display,
    {
        let mut sink = Sink {
            out: Vec::new(),
            path: Path::new("(memory)"),
            written: 0,
            idle: self.idle,
            room,
        };
        match sink.copy(&mut body, limit, what).await {
            Ok(()) => Ok(sink.out),
            Err(Copy::BrokeOff(error) | Copy::Failed(error)) => {
                sink.room.discard();
                Err(error)
            }
        }
    }
}

/// The embedded blob store: the data directory's session folders.
impl BlobStore for Files {
    fn reserve(&self, id: Option<&str>, declared: Option<u64>) -> Result<Reservation<'_>, Error> {
        self.quota.reserve(id, declared)
    }

    fn exists(&self, id: &str, object: SessionObject) -> bool {
        self.path(id, object).is_file()
    }

    fn get(&self, id: &str, object: SessionObject) -> Result<Option<Vec<u8>>, Error> {
        let path = self.path(id, object);
        match std::fs::read(&path) {
            Ok(bytes) => Ok(Some(bytes)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(Error::io("cannot read", &path, e)),
        }
    }

    fn peek(&self, id: &str, object: SessionObject, max: usize) -> Result<Option<Vec<u8>>, Error> {
        use std::io::Read as _;
        let path = self.path(id, object);
        let Some(found) = self.open(id, object)? else {
            return Ok(None);
        };
        let mut head = Vec::with_capacity(max.min(found.len as usize));
        found
            .bytes
            .take(max as u64)
            .read_to_end(&mut head)
            .map_err(|e| Error::io("cannot read", &path, e))?;
        Ok(Some(head))
    }

    fn open(&self, id: &str, object: SessionObject) -> Result<Option<ObjectReader>, Error> {
        let path = self.path(id, object);
        let file = match std::fs::File::open(&path) {
            Ok(file) => file,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(Error::io("cannot read", &path, e)),
        };
        let len = file
            .metadata()
            .map_err(|e| Error::io("cannot stat", &path, e))?
            .len();
        Ok(Some(ObjectReader {
            len,
            bytes: Box::new(file),
        }))
    }

    fn put(&self, id: &str, object: SessionObject, bytes: &[u8]) -> Result<(), Error> {
        self.write_atomic(&self.path(id, object), bytes)
    }

    fn append_line(&self, id: &str, object: SessionObject, line: &str) -> Result<(), Error> {
        use std::io::Write as _;
        let path = self.path(id, object);
        std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .and_then(|mut f| writeln!(f, "{line}"))
            .map_err(|e| Error::io("cannot append to", &path, e))
    }

    fn len(&self, id: &str, object: SessionObject) -> Result<Option<u64>, Error> {
        let path = self.path(id, object);
        match std::fs::metadata(&path) {
            Ok(m) => Ok(Some(m.len())),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(Error::io("cannot stat", &path, e)),
        }
    }

    fn remove(&self, id: &str, object: SessionObject) -> Result<(), Error> {
        let path = self.path(id, object);
        match std::fs::remove_file(&path) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
            Err(e) => Err(Error::io("cannot remove", &path, e)),
        }
    }

    fn local_file(&self, id: &str, object: SessionObject) -> PathBuf {
        self.path(id, object)
    }

    fn publish(&self, temp: TempFile, id: &str, object: SessionObject) -> Result<(), Error> {
        temp.publish(&self.path(id, object))
    }

    fn staged_part(&self, id: &str, bytes: u64) -> TempFile {
        TempFile {
            path: self.path(id, SessionObject::RecordingPart),
            bytes,
        }
    }

    fn same_content(
        &self,
        temp: &TempFile,
        id: &str,
        object: SessionObject,
    ) -> Result<bool, Error> {
        use std::io::Read;
        let (a, b) = (temp.path.as_path(), self.path(id, object));
        let open = |p: &Path| std::fs::File::open(p).map_err(|e| Error::io("cannot open", p, e));
        let (mut fa, mut fb) = (open(a)?, open(&b)?);
        let len = |f: &std::fs::File, p: &Path| {
            f.metadata()
                .map(|m| m.len())
                .map_err(|e| Error::io("cannot stat", p, e))
        };
        if len(&fa, a)? != len(&fb, &b)? {
            return Ok(false);
        }
        let (mut ba, mut bb) = (vec![0u8; 1 << 20], vec![0u8; 1 << 20]);
        loop {
            let n = fa
                .read(&mut ba)
                .map_err(|e| Error::io("cannot read", a, e))?;
            if n == 0 {
                return Ok(true);
            }
            fb.read_exact(&mut bb[..n])
                .map_err(|e| Error::io("cannot read", &b, e))?;
            if ba[..n] != bb[..n] {
                return Ok(false);
            }
        }
    }

    fn remove_session(&self, id: &str) -> Result<(), Error> {
        // The folder goes out of sight in one rename, then is removed; what an older version's
        // delete left in `tmp/deleted-ID` goes too.
        let dir = self.session_dir(id);
        let trash = self.root.join("tmp").join(format!("deleted-{id}"));
        remove_folder(&trash)?;
        match std::fs::rename(&dir, &trash) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) => return Err(Error::io("cannot move away", &dir, e)),
        }
        remove_folder(&trash)
    }

    fn create_session(&self, id: &str) -> Result<(), Error> {
        let dir = self.session_dir(id).join("trials");
        std::fs::create_dir_all(&dir).map_err(|e| Error::io("cannot create", &dir, e))
    }

    fn playback_folder(&self, id: &str) -> PathBuf {
        self.session_dir(id).join("adb-pull")
    }

    fn scene_folder(&self, id: &str) -> PathBuf {
        self.session_dir(id).join("phone")
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
        let scratch = self.root.join("tmp").join(format!("phone-{}", new_id()));
        let kept = save(&scratch)
            && std::fs::write(scratch.join(SCENE_TAG), tag).is_ok()
            && std::fs::rename(&scratch, self.scene_folder(id)).is_ok();
        if !kept {
            let _ = std::fs::remove_dir_all(&scratch);
        }
        kept
    }

    fn receive<'a>(
        &'a self,
        body: BodyStream<'a>,
        limit: u64,
        what: &'static str,
    ) -> Upload<'a, TempFile> {
        Box::pin(self.receive_stream(body, limit, what))
    }

    fn receive_bytes_into<'a>(
        &'a self,
        body: BodyStream<'a>,
        limit: u64,
        what: &'static str,
        room: Reservation<'a>,
    ) -> Upload<'a, Vec<u8>> {
        Box::pin(self.read_stream(body, limit, what, room))
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
            let path = self.path(id, object);
            self.append(body, &path, offset, end, what, room).await
        })
    }
}

/// Why copying a body stopped.
enum Copy {
    /// The body broke off (the client went away): what arrived is whole and kept.
    BrokeOff(Error),
    /// Too large, or the disk failed: what arrived must not be used.
    Failed(Error),
}

/// Where a request body is being written: a buffered file, or memory.
struct Sink<'p, W> {
    out: W,
    /// Named in write errors.
    path: &'p Path,
    /// The length written once flushed.
    written: u64,
    idle: std::time::Duration,
    /// The disk quotas the bytes count against.
    room: Reservation<'p>,
}

impl<'p> Sink<'p, tokio::io::BufWriter<tokio::fs::File>> {
    fn new(
        file: tokio::fs::File,
        path: &'p Path,
        written: u64,
        idle: std::time::Duration,
        room: Reservation<'p>,
    ) -> Self {
        Sink {
            out: tokio::io::BufWriter::with_capacity(1 << 20, file),
            path,
            written,
            idle,
            room,
        }
    }
}

impl<W: tokio::io::AsyncWrite + Unpin> Sink<'_, W> {
    /// Copies `body` until it ends, refusing to grow the file past `limit` bytes; the
    /// buffer is flushed whatever happens, so `written` counts bytes in the file.
    async fn copy<S, E>(&mut self, body: &mut S, limit: u64, what: &'static str) -> Result<(), Copy>
    where
        S: Stream<Item = Result<Bytes, E>> + Unpin,
        E: std::fmt::Display,
    {
        let outcome = self.copy_unflushed(body, limit, what).await;
        let flushed = self
            .out
            .flush()
            .await
            .map_err(|e| Copy::Failed(Error::io("cannot write", self.path, e)));
        // A failed flush spoils even a broken-off prefix: it is not all in the file.
        flushed.and(outcome)
    }

    async fn copy_unflushed<S, E>(
        &mut self,
        body: &mut S,
        limit: u64,
        what: &'static str,
    ) -> Result<(), Copy>
    where
        S: Stream<Item = Result<Bytes, E>> + Unpin,
        E: std::fmt::Display,
    {
        // One timer for the whole body, pushed back only when it fires: a timer per chunk
        // cost a quarter of the upload throughput.
        let mut last_data = tokio::time::Instant::now();
        let stall = tokio::time::sleep(self.idle);
        tokio::pin!(stall);
        loop {
            let next = tokio::select! {
                biased;
                next = body.next() => next,
                () = &mut stall => {
                    let deadline = last_data + self.idle;
                    if deadline > tokio::time::Instant::now() {
                        stall.as_mut().reset(deadline);
                        continue;
                    }
                    return Err(Copy::BrokeOff(Error::BadRequest(format!(
                        "{what}: no data for {} s, the body is taken as broken off",
                        self.idle.as_secs_f64()
                    ))));
                }
            };
            let Some(chunk) = next else { break };
            let chunk = chunk.map_err(|e| {
                Copy::BrokeOff(Error::BadRequest(format!("{what}: body broke off: {e}")))
            })?;
            if self.written + chunk.len() as u64 > limit {
                return Err(Copy::Failed(Error::TooLarge { what, limit }));
            }
            self.room.add(chunk.len() as u64).map_err(Copy::Failed)?;
            self.out
                .write_all(&chunk)
                .await
                .map_err(|e| Copy::Failed(Error::io("cannot write", self.path, e)))?;
            self.written += chunk.len() as u64;
            last_data = tokio::time::Instant::now();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::body_stream;

    #[test]
    fn ids_are_unique_and_path_safe() {
        let ids: std::collections::HashSet<String> = (0..1000).map(|_| new_id()).collect();
        assert_eq!(ids.len(), 1000);
        assert!(ids.iter().all(|id| is_server_id(id)));
        for bad in [
            "../../x",
            "s0123456789abcdeF",
            "s0123456789abcde/",
            "",
            "s01234567",
        ] {
            assert!(!is_server_id(bad), "{bad}");
        }
    }

    #[tokio::test]
    async fn the_embedded_store_passes_the_conformance_suite() {
        let dir = tempfile::tempdir().unwrap();
        let files = Files::open(dir.path()).unwrap();
        crate::storage::conformance::blob_store(&files).await;
        // Nothing staged is left behind.
        assert_eq!(
            std::fs::read_dir(dir.path().join("tmp")).unwrap().count(),
            0
        );
    }

    #[tokio::test]
    async fn receive_enforces_the_limit_and_leaves_no_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        let files = Files::open(dir.path()).unwrap();
        let chunks = || {
            futures_util::stream::iter(
                (0..4).map(|_| Ok::<_, std::io::Error>(Bytes::from(vec![7u8; 1000]))),
            )
        };
        let err = files
            .receive(body_stream(chunks()), 3999, "recording")
            .await
            .unwrap_err();
        assert!(matches!(err, Error::TooLarge { limit: 3999, .. }));
        assert_eq!(
            std::fs::read_dir(dir.path().join("tmp")).unwrap().count(),
            0
        );
        let temp = files
            .receive(body_stream(chunks()), 4000, "recording")
            .await
            .unwrap();
        assert_eq!(temp.bytes, 4000);
        let dest = dir.path().join("sessions/x/recording");
        temp.publish(&dest).unwrap();
        assert_eq!(std::fs::read(&dest).unwrap(), vec![7u8; 4000]);
        assert_eq!(
            std::fs::read_dir(dir.path().join("tmp")).unwrap().count(),
            0
        );
    }

    #[tokio::test]
    async fn bytes_in_memory_keep_the_limit_and_a_broken_body_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let files = Files::open(dir.path()).unwrap();
        let body = || {
            futures_util::stream::iter(
                (0..3).map(|i| Ok::<_, std::io::Error>(Bytes::from(vec![i as u8; 10]))),
            )
        };
        let bytes = files
            .receive_bytes(body_stream(body()), 30, "trajectory")
            .await
            .unwrap();
        assert_eq!((bytes.len(), bytes[0], bytes[29]), (30, 0, 2));
        let err = files
            .receive_bytes(body_stream(body()), 29, "trajectory")
            .await
            .unwrap_err();
        assert!(
            matches!(
                err,
                Error::TooLarge {
                    what: "trajectory",
                    limit: 29
                }
            ),
            "{err}"
        );
        let err = files
            .receive_bytes(body_stream(broken_after(2)), 10_000, "trajectory")
            .await
            .unwrap_err();
        assert!(err.to_string().contains("broke off"), "{err}");
        assert_eq!(
            std::fs::read_dir(dir.path().join("tmp")).unwrap().count(),
            0
        );
    }

    fn room(files: &Files) -> Reservation<'_> {
        files.reserve(None, None).unwrap()
    }

    fn broken_after(chunks: usize) -> impl Stream<Item = Result<Bytes, std::io::Error>> + Unpin {
        futures_util::stream::iter((0..=chunks).map(move |i| {
            if i < chunks {
                Ok(Bytes::from(vec![i as u8; 1000]))
            } else {
                Err(std::io::Error::other("connection reset"))
            }
        }))
    }

    #[tokio::test]
    async fn a_broken_body_keeps_its_prefix_and_an_append_continues_it() {
        let dir = tempfile::tempdir().unwrap();
        let files = Files::open(dir.path()).unwrap();
        let part = dir.path().join("part");
        let broken = files
            .append(broken_after(3), &part, 0, 10_000, "recording", room(&files))
            .await
            .unwrap();
        assert_eq!(broken.len, 3000);
        let error = broken.broken.unwrap().to_string();
        assert!(error.contains("broke off"), "{error}");

        // Another break while appending: what arrived is kept.
        let len = files
            .append(
                broken_after(2),
                &part,
                3000,
                10_000,
                "recording",
                room(&files),
            )
            .await
            .unwrap();
        assert!(len.broken.is_some());
        assert_eq!(len.len, 5000);
        let kept = std::fs::read(&part).unwrap();
        assert_eq!(kept.len(), 5000);
        assert_eq!((kept[2999], kept[3000], kept[4999]), (2, 0, 1));
    }

    #[tokio::test]
    async fn an_append_past_its_range_or_at_the_wrong_offset_changes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let files = Files::open(dir.path()).unwrap();
        let part = dir.path().join("part");
        std::fs::write(&part, [9u8; 500]).unwrap();
        let err = files
            .append(broken_after(3), &part, 500, 2500, "recording", room(&files))
            .await
            .unwrap_err();
        assert!(
            matches!(err, Error::BadRequest(ref m) if m.contains("Content-Range")),
            "{err}"
        );
        assert_eq!(std::fs::read(&part).unwrap(), vec![9u8; 500]);
        let err = files
            .append(
                broken_after(1),
                &part,
                400,
                10_000,
                "recording",
                room(&files),
            )
            .await
            .unwrap_err();
        assert!(matches!(err, Error::Internal(_)), "{err}");
        assert_eq!(std::fs::read(&part).unwrap(), vec![9u8; 500]);
    }

    #[test]
    fn a_deleted_sessions_folder_is_removed_again_and_again() {
        let dir = tempfile::tempdir().unwrap();
        let files = Files::open(dir.path()).unwrap();
        let id = "s0123456789abcdef";
        std::fs::create_dir_all(dir.path().join(format!("sessions/{id}/trials"))).unwrap();
        std::fs::write(
            dir.path()
                .join(format!("sessions/{id}/trials/trial_000.txt")),
            "x",
        )
        .unwrap();
        // What an older version's interrupted delete left goes with it.
        std::fs::create_dir_all(dir.path().join(format!("tmp/deleted-{id}/trials"))).unwrap();
        files.remove_session(id).unwrap();
        assert!(!dir.path().join(format!("sessions/{id}")).exists());
        assert!(!dir.path().join(format!("tmp/deleted-{id}")).exists());
        assert!(!files.exists(id, SessionObject::Trial(0)));
        // Nothing left: success again (another sweep, a repeated delete).
        files.remove_session(id).unwrap();
        // Another session's folder stays.
        std::fs::create_dir_all(dir.path().join("sessions/s1111111111111111/trials")).unwrap();
        files.remove_session(id).unwrap();
        assert!(
            dir.path()
                .join("sessions/s1111111111111111/trials")
                .is_dir()
        );
    }

    #[test]
    fn a_restart_clears_what_uploads_and_deletes_left_in_tmp() {
        let dir = tempfile::tempdir().unwrap();
        let files = Files::open(dir.path()).unwrap();
        std::fs::create_dir_all(dir.path().join("tmp/deleted-s0123456789abcdef/trials")).unwrap();
        std::fs::write(dir.path().join("tmp/upload-x.part"), "half").unwrap();
        drop(files);
        Files::open(dir.path()).unwrap();
        assert_eq!(
            std::fs::read_dir(dir.path().join("tmp")).unwrap().count(),
            0
        );
    }
}
