//! The blob store: every byte the server keeps for a session (recordings and their resumable
//! parts, trials, results, history, evidence, thumbnails, the scene), named by
//! [`SessionObject`] — typed names built from server-made ids and checked numbers only.
//! [`super::files::Files`] is the embedded implementation (the data directory's
//! `sessions/ID/` folders); `storage::conformance` holds the suite every implementation
//! passes. The server holds an `Arc<dyn BlobStore>`.
//!
//! The guarantees callers rely on: a whole object is replaced atomically (readers see the old
//! bytes or the new); an upload is staged, checked and then published whole, and a body
//! that breaks off publishes nothing; a resumable part keeps exactly the bytes that arrived;
//! every byte counts against the disk quotas ([`Reservation`]) while it streams.

use std::future::Future;
use std::path::{Path, PathBuf};
use std::pin::Pin;

use axum::body::Bytes;
use futures_util::{Stream, StreamExt};

use crate::error::Error;
use crate::storage::keys::SessionObject;
use crate::storage::quota::Reservation;
use crate::storage::staged::{Appended, TempFile};

/// A request body as the blob store reads it; a transport error is kept as its text, which
/// the answer names.
pub(crate) type BodyStream<'a> = Pin<Box<dyn Stream<Item = Result<Bytes, String>> + Send + 'a>>;

/// What an upload method returns: its work, to be awaited on the request's task.
pub(crate) type Upload<'a, T> = Pin<Box<dyn Future<Output = Result<T, Error>> + Send + 'a>>;

/// `stream` (an axum body, a multipart field) as a [`BodyStream`].
pub(crate) fn body_stream<'a, S, E>(stream: S) -> BodyStream<'a>
where
    S: Stream<Item = Result<Bytes, E>> + Send + 'a,
    E: std::fmt::Display,
{
    Box::pin(stream.map(|chunk| chunk.map_err(|e| e.to_string())))
}

/// A stored object being read ([`BlobStore::open`]): its length and its bytes.
pub(crate) struct ObjectReader {
    /// Its length in bytes.
    pub len: u64,
    /// Its bytes, from the first.
    pub bytes: Box<dyn std::io::Read + Send>,
}

/// Every byte the server keeps for its sessions.
pub(crate) trait BlobStore: Send + Sync {
    /// Room for an upload into session `id`'s objects (`None`: a new session's, only the
    /// global quota applies); `declared` bytes that cannot fit are refused at once.
    fn reserve(&self, id: Option<&str>, declared: Option<u64>) -> Result<Reservation<'_>, Error>;
    /// Makes room for a new session's objects.
    fn create_session(&self, id: &str) -> Result<(), Error>;
    /// Whether session `id`'s `object` is stored.
    fn exists(&self, id: &str, object: SessionObject) -> bool;
    /// Session `id`'s `object` whole; `None` when it is not stored. For objects bounded on
    /// the way in (trials, results, evidence, logs); a recording is [`BlobStore::peek`]ed at
    /// or [`BlobStore::open`]ed, never read whole.
    fn get(&self, id: &str, object: SessionObject) -> Result<Option<Vec<u8>>, Error>;
    /// At most the first `max` bytes of session `id`'s `object` (all of it when shorter): a
    /// header, read without the rest; `None` when it is not stored.
    fn peek(&self, id: &str, object: SessionObject, max: usize) -> Result<Option<Vec<u8>>, Error>;
    /// Session `id`'s `object` as a reader of its bytes in order, a bounded chunk at a time
    /// (downloads, hashes: never whole in memory); `None` when it is not stored.
    fn open(&self, id: &str, object: SessionObject) -> Result<Option<ObjectReader>, Error>;
    /// The length of session `id`'s `object`; `None` when it is not stored.
    fn len(&self, id: &str, object: SessionObject) -> Result<Option<u64>, Error>;
    /// Stores session `id`'s `object` whole, replacing it atomically.
    fn put(&self, id: &str, object: SessionObject, bytes: &[u8]) -> Result<(), Error>;
    /// Appends one line to session `id`'s `object` (a log: a crash may lose the last line,
    /// never an earlier one).
    fn append_line(&self, id: &str, object: SessionObject, line: &str) -> Result<(), Error>;
    /// Removes session `id`'s `object` if it is stored.
    fn remove(&self, id: &str, object: SessionObject) -> Result<(), Error>;
    /// A local file holding session `id`'s `object`, for tools that need a path (adb push,
    /// the sim player, the MP4 check).
    fn local_file(&self, id: &str, object: SessionObject) -> PathBuf;

    /// Stages `body` whole, refusing more than `limit` bytes (and what would pass the global
    /// disk quota); [`BlobStore::publish`] moves it into place. A body that breaks off leaves
    /// nothing.
    fn receive<'a>(
        &'a self,
        body: BodyStream<'a>,
        limit: u64,
        what: &'static str,
    ) -> Upload<'a, TempFile>;
    /// Reads `body` into memory under `room`'s quotas, refusing more than `limit` bytes (a
    /// trial or an evidence table: parsed from these bytes, then stored once). A body that
    /// breaks off or stalls is a 400.
    fn receive_bytes_into<'a>(
        &'a self,
        body: BodyStream<'a>,
        limit: u64,
        what: &'static str,
        room: Reservation<'a>,
    ) -> Upload<'a, Vec<u8>>;
    /// [`BlobStore::receive_bytes_into`] under the global quota alone.
    fn receive_bytes<'a>(
        &'a self,
        body: BodyStream<'a>,
        limit: u64,
        what: &'static str,
    ) -> Upload<'a, Vec<u8>> {
        match self.reserve(None, None) {
            Ok(room) => self.receive_bytes_into(body, limit, what, room),
            Err(e) => Box::pin(std::future::ready(Err(e))),
        }
    }
    /// Appends `body` to session `id`'s `object` (a kept prefix), which must be `offset` bytes
    /// long, refusing to grow it beyond `end` bytes. A body that breaks off keeps what
    /// arrived; any other failure cuts the object back to `offset`.
    #[allow(clippy::too_many_arguments)]
    fn append_to<'a>(
        &'a self,
        body: BodyStream<'a>,
        id: &'a str,
        object: SessionObject,
        offset: u64,
        end: u64,
        what: &'static str,
        room: Reservation<'a>,
    ) -> Upload<'a, Appended>;
    /// Moves a staged upload into place as session `id`'s `object`, atomically (as
    /// `RecordingPart`: the whole kept prefix, replacing what was kept).
    fn publish(&self, temp: TempFile, id: &str, object: SessionObject) -> Result<(), Error>;
    /// Session `id`'s kept recording prefix, `bytes` long, as a staged upload.
    fn staged_part(&self, id: &str, bytes: u64) -> TempFile;
    /// Whether the staged upload `temp` holds exactly the bytes of session `id`'s `object`.
    fn same_content(&self, temp: &TempFile, id: &str, object: SessionObject)
    -> Result<bool, Error>;
    /// Removes every object of deleted session `id`, wherever a delete may have left it
    /// (idempotent: objects already gone, or none at all, are success; another instance may be
    /// removing them at the same time). Called once its row is gone (`storage::deletes`).
    fn remove_session(&self, id: &str) -> Result<(), Error>;

    /// A local folder for session `id`'s playback working files (trials pulled from the
    /// phones before they are parsed); removed with the session.
    fn playback_folder(&self, id: &str) -> PathBuf;

    /// The local folder of the phone session rebuilt for session `id`'s scene (a cache:
    /// rebuilt when missing); also its key in in-memory caches.
    fn scene_folder(&self, id: &str) -> PathBuf;
    /// The kept scene of session `id` and the tag of what it was built from.
    fn kept_scene(&self, id: &str) -> Option<(PathBuf, String)>;
    /// Forgets the kept scene of session `id`.
    fn discard_scene(&self, id: &str);
    /// Keeps a scene built from `tag`: `save` writes it into a scratch folder, which is put in
    /// place whole. Whether it was kept.
    fn keep_scene(&self, id: &str, tag: &str, save: &mut dyn FnMut(&Path) -> bool) -> bool;
}
