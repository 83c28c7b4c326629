//! Answers sent as a stream of bounded chunks, never whole in memory: a session's stored
//! object (a recording of gigabytes to a playback host, the phone's log) read from either
//! store, or bytes written on a blocking thread (`trials.zip`).
//!
//! Bounds, per answer: the writer fills one [`CHUNK`] while at most [`QUEUED`] wait for the
//! client; a slow or stalled client makes the writer wait (backpressure), so an answer holds
//! about 1.5 MiB whatever it sends.

use std::io::Write;
use std::sync::Arc;

use axum::body::{Body, Bytes};
use tokio::sync::mpsc;

use crate::error::Error;
use crate::storage::blobs::BlobStore;
use crate::storage::keys::SessionObject;

/// Bytes sent at a time.
pub(crate) const CHUNK: usize = 256 << 10;

/// Chunks waiting for the client at most.
pub(crate) const QUEUED: usize = 4;

/// An answer body written by `write` on a blocking thread, [`CHUNK`] bytes at a time. A
/// failure of `write` (named with `what` in the log) ends the body with an error, so the
/// client sees a cut-off answer rather than a complete-looking short one; a client that goes
/// away ends the writer at its next chunk.
pub(crate) fn written_body(
    what: &'static str,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()> + Send + 'static,
) -> Body {
    let (to, chunks) = mpsc::channel::<std::io::Result<Bytes>>(QUEUED);
    tokio::task::spawn_blocking(move || {
        let mut out = ChunkWriter {
            to: to.clone(),
            buf: Vec::new(),
        };
        let written = write(&mut out).and_then(|()| out.flush());
        if let Err(e) = written {
            if e.kind() != std::io::ErrorKind::BrokenPipe {
                log::warn!("{what}: the answer was cut off: {e}");
            }
            let _ = to.blocking_send(Err(e));
        }
    });
    Body::from_stream(futures_util::stream::unfold(chunks, |mut chunks| async {
        chunks.recv().await.map(|chunk| (chunk, chunks))
    }))
}

/// Session `id`'s `object` as an answer body, with its length; `None` when it is not stored.
/// Opened off the async runtime (a bucket's first bytes take a request).
pub(crate) async fn object_body(
    blobs: Arc<dyn BlobStore>,
    id: &str,
    object: SessionObject,
) -> Result<Option<(u64, Body)>, Error> {
    let owned = id.to_string();
    let opened = tokio::task::spawn_blocking(move || blobs.open(&owned, object))
        .await
        .map_err(|e| Error::Internal(format!("opening {}: {e}", object.relative_path())))??;
    Ok(opened.map(|mut found| {
        let body = written_body("a stored object", move |out| {
            std::io::copy(&mut found.bytes, out).map(|_| ())
        });
        (found.len, body)
    }))
}

/// Bytes written into [`CHUNK`]-sized chunks sent on a bounded channel (waiting while it is
/// full).
struct ChunkWriter {
    to: mpsc::Sender<std::io::Result<Bytes>>,
    buf: Vec<u8>,
}

impl ChunkWriter {
    fn send(&mut self) -> std::io::Result<()> {
        if self.buf.is_empty() {
            return Ok(());
        }
        let chunk = Bytes::from(std::mem::take(&mut self.buf));
        self.to.blocking_send(Ok(chunk)).map_err(|_| {
            std::io::Error::new(std::io::ErrorKind::BrokenPipe, "the client went away")
        })
    }
}

impl Write for ChunkWriter {
    fn write(&mut self, data: &[u8]) -> std::io::Result<usize> {
        if self.buf.capacity() == 0 {
            self.buf.reserve_exact(CHUNK);
        }
        let n = data.len().min(CHUNK - self.buf.len());
        self.buf.extend_from_slice(&data[..n]);
        if self.buf.len() == CHUNK {
            self.send()?;
        }
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.send()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    async fn collected(body: Body) -> Result<Vec<u8>, String> {
        axum::body::to_bytes(body, usize::MAX)
            .await
            .map(|b| b.to_vec())
            .map_err(|e| e.to_string())
    }

    /// Every byte arrives, in order, in chunks of at most [`CHUNK`].
    #[tokio::test]
    async fn a_written_body_carries_every_byte_in_bounded_chunks() {
        let data: Vec<u8> = (0..(3 * CHUNK + 17) as u32).map(|i| i as u8).collect();
        let expected = data.clone();
        let body = written_body("test", move |out| out.write_all(&data));
        let mut stream = body.into_data_stream();
        let mut got = Vec::new();
        while let Some(chunk) = futures_util::StreamExt::next(&mut stream).await {
            let chunk = chunk.unwrap();
            assert!(chunk.len() <= CHUNK);
            got.extend_from_slice(&chunk);
        }
        assert!(got == expected);
    }

    /// A writer that fails ends the body with an error, not with a short complete body.
    #[tokio::test]
    async fn a_failed_writer_cuts_the_body_off() {
        let body = written_body("test", |out| {
            out.write_all(&[1; 1000])?;
            Err(std::io::Error::other("disk gone"))
        });
        assert!(collected(body).await.is_err());
    }

    /// A stored object streams from the store as stored; a missing one is `None`.
    #[tokio::test]
    async fn an_object_body_is_the_stored_object() {
        use crate::storage::files::Files;
        let dir = tempfile::tempdir().unwrap();
        let files = Files::open(dir.path()).unwrap();
        let id = "s3000000000000001";
        files.create_session(id).unwrap();
        let bytes: Vec<u8> = (0..(CHUNK * 2 + 5) as u32).map(|i| (i * 7) as u8).collect();
        files.put(id, SessionObject::Trial(0), &bytes).unwrap();
        let blobs: Arc<dyn BlobStore> = Arc::new(files);
        let (len, body) = object_body(blobs.clone(), id, SessionObject::Trial(0))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(len, bytes.len() as u64);
        assert!(collected(body).await.unwrap() == bytes);
        assert!(
            object_body(blobs, id, SessionObject::Trial(1))
                .await
                .unwrap()
                .is_none()
        );
    }
}
