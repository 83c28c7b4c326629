//! A session's object read as a stream of chunks (a playback host fetching a recording of
//! gigabytes): never whole in memory, 256 KiB at a time.

use axum::body::Bytes;
use futures_util::Stream;
use tokio::io::AsyncReadExt;

use crate::Error;
use crate::storage::blobs::BlobStore;
use crate::storage::keys::SessionObject;

/// Chunks read at a time.
const CHUNK: usize = 256 << 10;

/// `object` of session `id`: its length and its bytes as a stream. A read error ends the
/// stream with that error (the reader sees a short body).
pub(crate) async fn object_stream(
    blobs: &dyn BlobStore,
    id: &str,
    object: SessionObject,
) -> Result<
    (
        u64,
        impl Stream<Item = Result<Bytes, std::io::Error>> + use<>,
    ),
    Error,
> {
    let path = blobs.local_file(id, object);
    let file = tokio::fs::File::open(&path)
        .await
        .map_err(|e| Error::io("cannot read", &path, e))?;
    let len = file
        .metadata()
        .await
        .map_err(|e| Error::io("cannot read", &path, e))?
        .len();
    let chunks = futures_util::stream::unfold(Some(file), |file| async move {
        let mut file = file?;
        let mut buf = vec![0u8; CHUNK];
        match file.read(&mut buf).await {
            Ok(0) => None,
            Ok(n) => {
                buf.truncate(n);
                Some((Ok(Bytes::from(buf)), Some(file)))
            }
            Err(e) => Some((Err(e), None)),
        }
    });
    Ok((len, chunks))
}
