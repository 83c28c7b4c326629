//! A request body sent on to the bucket while it arrives, beside the staged copy the checks
//! read: receiving and uploading overlap instead of following each other. Nothing becomes
//! visible here: a large body goes into a multipart upload that the caller completes (it is
//! invisible until then) or aborts; a small one stays in memory for one PUT.
//!
//! Bounds: [`QUEUED_CHUNKS`] body chunks wait for the uploader (hyper's chunks are at most
//! its read buffer, about 400 KiB), one part is filled while [`PARTS_IN_FLIGHT`] are sent:
//! about 46 MiB per upload. A slow bucket slows the body down (backpressure), it never grows
//! memory.

use std::sync::Arc;

use axum::body::Bytes;
use futures_util::StreamExt;
use object_store::aws::AmazonS3;
use object_store::path::Path as Key;
use object_store::{MultipartUpload, ObjectStoreExt, PutPayload};
use tokio::sync::mpsc;

use super::client::{PART_BYTES, PARTS_IN_FLIGHT, s3_error};
use crate::error::Error;
use crate::storage::blobs::BodyStream;

/// Body chunks waiting for the uploader at most.
pub(crate) const QUEUED_CHUNKS: usize = 16;

/// What the uploader holds once the body has ended: every byte it was given, not yet
/// visible in the bucket.
pub(crate) enum Sent {
    /// Fewer than [`PART_BYTES`]: kept in memory for one PUT.
    Small(Vec<Bytes>),
    /// Uploaded as the parts of a multipart upload of `key`, to be completed or aborted.
    Parts(Box<dyn MultipartUpload>),
}

impl std::fmt::Debug for Sent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Sent::Small(chunks) => write!(f, "Sent::Small({} chunks)", chunks.len()),
            Sent::Parts(_) => write!(f, "Sent::Parts"),
        }
    }
}

impl Sent {
    /// Makes the bytes the object at `key` (the key the upload was started for); its entity tag.
    pub async fn store(self, s3: Arc<AmazonS3>, key: Key) -> Result<Option<String>, Error> {
        let put = match self {
            Sent::Small(chunks) => s3.put(&key, PutPayload::from_iter(chunks)).await,
            Sent::Parts(mut upload) => upload.complete().await,
        };
        put.map(|p| p.e_tag).map_err(|e| s3_error(&key, e))
    }

    /// Gives the bytes up (an unfinished multipart upload is aborted, freeing its parts).
    pub async fn abort(self, key: Key) {
        if let Sent::Parts(mut upload) = self
            && let Err(e) = upload.abort().await
        {
            log::warn!("cannot abort the multipart upload of {key}: {e}");
        }
    }
}

/// `body` as it was, each chunk also handed to `to` (waiting while the uploader is
/// [`QUEUED_CHUNKS`] behind). A chunk is shared, not copied. Once the uploader has stopped
/// (an error it reports when joined) the body goes on alone; dropping the stream ends the
/// uploader's input.
pub(crate) fn tee<'a>(body: BodyStream<'a>, to: mpsc::Sender<Bytes>) -> BodyStream<'a> {
    Box::pin(futures_util::stream::unfold(
        (body, Some(to)),
        |(mut body, mut to)| async move {
            let item = body.next().await?;
            if let (Ok(chunk), Some(sender)) = (&item, &to)
                && sender.send(chunk.clone()).await.is_err()
            {
                to = None;
            }
            Some((item, (body, to)))
        },
    ))
}

/// Sends what arrives on `chunks` to the bucket for `key`, in parts of exactly
/// [`PART_BYTES`] (the last one shorter) with at most [`PARTS_IN_FLIGHT`] at once, the
/// multipart upload started only once a whole part has arrived. Returns what it holds and
/// how many bytes; on a failure the upload is aborted.
pub(crate) async fn upload(
    s3: Arc<AmazonS3>,
    key: Key,
    mut chunks: mpsc::Receiver<Bytes>,
) -> Result<(Sent, u64), Error> {
    let mut part: Vec<Bytes> = Vec::new();
    let mut filled = 0usize;
    let mut total = 0u64;
    let mut upload: Option<Box<dyn MultipartUpload>> = None;
    let mut in_flight = tokio::task::JoinSet::new();
    while let Some(mut chunk) = chunks.recv().await {
        total += chunk.len() as u64;
        while filled + chunk.len() >= PART_BYTES {
            part.push(chunk.split_to(PART_BYTES - filled));
            let multipart = match &mut upload {
                Some(started) => started,
                None => upload.insert(
                    s3.put_multipart(&key)
                        .await
                        .map_err(|e| s3_error(&key, e))?,
                ),
            };
            while in_flight.len() >= PARTS_IN_FLIGHT {
                if let Err(e) = joined(in_flight.join_next().await, &key) {
                    multipart.abort().await.ok();
                    return Err(e);
                }
            }
            in_flight.spawn(multipart.put_part(PutPayload::from_iter(part.drain(..))));
            filled = 0;
        }
        if !chunk.is_empty() {
            filled += chunk.len();
            part.push(chunk);
        }
    }
    let Some(mut multipart) = upload else {
        return Ok((Sent::Small(part), total));
    };
    if filled > 0 {
        in_flight.spawn(multipart.put_part(PutPayload::from_iter(part)));
    }
    while !in_flight.is_empty() {
        if let Err(e) = joined(in_flight.join_next().await, &key) {
            multipart.abort().await.ok();
            return Err(e);
        }
    }
    Ok((Sent::Parts(multipart), total))
}

/// A part's upload, as ended.
fn joined(
    ended: Option<Result<object_store::Result<()>, tokio::task::JoinError>>,
    key: &Key,
) -> Result<(), Error> {
    match ended {
        None | Some(Ok(Ok(()))) => Ok(()),
        Some(Ok(Err(e))) => Err(s3_error(key, e)),
        Some(Err(e)) => Err(Error::Internal(format!(
            "a part of {key} was not sent: {e}"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chunks a tee hands on are the body's, in order, and the body is unchanged.
    #[tokio::test]
    async fn a_tee_hands_on_every_chunk_and_leaves_the_body_as_it_was() {
        let chunks: Vec<Result<Bytes, String>> = vec![
            Ok(Bytes::from_static(b"ab")),
            Ok(Bytes::from_static(b"cde")),
            Err("cut".into()),
        ];
        let (to, mut received) = mpsc::channel(QUEUED_CHUNKS);
        let body: BodyStream<'_> = Box::pin(futures_util::stream::iter(chunks));
        let seen: Vec<_> = tee(body, to).collect().await;
        assert_eq!(seen.len(), 3);
        assert_eq!(seen[1].as_ref().unwrap(), &Bytes::from_static(b"cde"));
        assert!(seen[2].is_err());
        assert_eq!(received.recv().await.unwrap(), Bytes::from_static(b"ab"));
        assert_eq!(received.recv().await.unwrap(), Bytes::from_static(b"cde"));
        assert!(
            received.recv().await.is_none(),
            "the tee ended the uploader's input"
        );
    }

    /// An uploader that went away does not stop the body.
    #[tokio::test]
    async fn the_body_goes_on_when_the_uploader_has_stopped() {
        let (to, received) = mpsc::channel(1);
        drop(received);
        let chunks: Vec<Result<Bytes, String>> =
            (0..5).map(|_| Ok(Bytes::from_static(b"x"))).collect();
        let body: BodyStream<'_> = Box::pin(futures_util::stream::iter(chunks));
        assert_eq!(tee(body, to).count().await, 5);
    }
}
