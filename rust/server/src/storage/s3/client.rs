//! The bucket, as synchronous and async calls: object_store's S3 client runs on a small
//! runtime of the store's own, so its connections never belong to a runtime that may end
//! first, and a synchronous trait method waits for it without entering a runtime
//! (`storage::blocking`).

use std::future::Future;
use std::sync::Arc;

use axum::body::Bytes;
use object_store::aws::AmazonS3;
use object_store::path::Path as Key;
use object_store::{ObjectStoreExt, PutPayload};

use crate::error::Error;

/// Threads of the client's runtime.
const THREADS: usize = 2;

/// The bucket's client and the runtime it runs on.
pub(crate) struct Bucket {
    pub s3: Arc<AmazonS3>,
    /// Where this installation's objects start (`PREFIX` of `s3://BUCKET/PREFIX`).
    pub prefix: Key,
    /// What `--store` said (for messages).
    pub url: String,
    runtime: Option<tokio::runtime::Runtime>,
}

impl Drop for Bucket {
    fn drop(&mut self) {
        // Dropping a runtime blocks, which panics inside another runtime's task.
        if let Some(runtime) = self.runtime.take() {
            runtime.shutdown_background();
        }
    }
}

/// An object store failure, naming the object.
pub(crate) fn s3_error(key: &Key, e: object_store::Error) -> Error {
    Error::Database(format!("object store, {key}: {e}"))
}

impl Bucket {
    /// The bucket of `url` (`s3://BUCKET/PREFIX`), its endpoint, region and credentials
    /// from the `AWS_*` variables.
    pub fn open(url: &str) -> Result<Bucket, Error> {
        let parsed = url.strip_prefix("s3://").ok_or_else(|| {
            Error::Config(format!("--store {url:?}: expected s3://BUCKET/PREFIX"))
        })?;
        let (bucket, prefix) = parsed.split_once('/').unwrap_or((parsed, ""));
        if bucket.is_empty() {
            return Err(Error::Config(format!(
                "--store {url:?}: the bucket is missing"
            )));
        }
        let s3 = object_store::aws::AmazonS3Builder::from_env()
            .with_bucket_name(bucket)
            .build()
            .map_err(|e| Error::Config(format!("--store {url:?}: {e}")))?;
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(THREADS)
            .thread_name("sitar-s3")
            .enable_all()
            .build()
            .map_err(|e| Error::Internal(format!("cannot start the S3 client's runtime: {e}")))?;
        Ok(Bucket {
            s3: Arc::new(s3),
            prefix: Key::from(prefix.trim_matches('/')),
            url: url.to_string(),
            runtime: Some(runtime),
        })
    }

    /// The key of `relative` (slash-separated) under the prefix.
    pub fn key(&self, relative: &str) -> Key {
        let mut parts: Vec<String> = self
            .prefix
            .parts()
            .map(|p| p.as_ref().to_string())
            .collect();
        parts.extend(
            relative
                .split('/')
                .filter(|p| !p.is_empty())
                .map(str::to_string),
        );
        Key::from(parts.join("/"))
    }

    fn handle(&self) -> Result<&tokio::runtime::Handle, Error> {
        self.runtime
            .as_ref()
            .map(|r| r.handle())
            .ok_or_else(|| Error::Internal("the S3 client's runtime has stopped".into()))
    }

    /// Runs `work` on the client's runtime and waits for it (from synchronous code).
    pub fn block<T: Send + 'static>(
        &self,
        work: impl Future<Output = Result<T, Error>> + Send + 'static,
    ) -> Result<T, Error> {
        let (answer, receive) = std::sync::mpsc::sync_channel(1);
        self.handle()?.spawn(async move {
            let _ = answer.send(work.await);
        });
        crate::storage::blocking::wait(receive)
            .unwrap_or_else(|| Err(Error::Internal("an S3 call was dropped".into())))
    }

    /// Runs `work` on the client's runtime and awaits it (from async code on any runtime).
    pub async fn spawn<T: Send + 'static>(
        &self,
        work: impl Future<Output = Result<T, Error>> + Send + 'static,
    ) -> Result<T, Error> {
        self.handle()?
            .spawn(work)
            .await
            .map_err(|e| Error::Internal(format!("an S3 call failed: {e}")))?
    }

    /// Starts `work` on the client's runtime at once; its handle, to await later.
    pub fn start<T: Send + 'static>(
        &self,
        work: impl Future<Output = T> + Send + 'static,
    ) -> Result<tokio::task::JoinHandle<T>, Error> {
        Ok(self.handle()?.spawn(work))
    }

    /// The object's bytes; `None` when it is not stored.
    pub fn get(&self, key: Key) -> Result<Option<Vec<u8>>, Error> {
        let s3 = self.s3.clone();
        self.block(async move {
            match s3.get(&key).await {
                Ok(got) => Ok(Some(
                    got.bytes().await.map_err(|e| s3_error(&key, e))?.to_vec(),
                )),
                Err(object_store::Error::NotFound { .. }) => Ok(None),
                Err(e) => Err(s3_error(&key, e)),
            }
        })
    }

    /// At most the first `max` bytes of the object (one ranged GET); `None` when it is not
    /// stored.
    pub fn get_start(&self, key: Key, max: usize) -> Result<Option<Vec<u8>>, Error> {
        let Some((len, _)) = self.head(key.clone())? else {
            return Ok(None);
        };
        let end = len.min(max as u64);
        if end == 0 {
            return Ok(Some(Vec::new()));
        }
        let s3 = self.s3.clone();
        self.block(async move {
            match s3.get_range(&key, 0..end).await {
                Ok(bytes) => Ok(Some(bytes.to_vec())),
                Err(object_store::Error::NotFound { .. }) => Ok(None),
                Err(e) => Err(s3_error(&key, e)),
            }
        })
    }

    /// The object as a blocking reader of its length: one GET, whose body is read as the
    /// reader asks for it (a chunk of the HTTP body at a time, never the object whole);
    /// `None` when it is not stored.
    pub fn reader(self: &Arc<Self>, key: Key) -> Result<Option<(u64, BucketReader)>, Error> {
        let s3 = self.s3.clone();
        let name = key.clone();
        let got = self.block(async move {
            match s3.get(&name).await {
                Ok(got) => Ok(Some((got.meta.size, got.into_stream()))),
                Err(object_store::Error::NotFound { .. }) => Ok(None),
                Err(e) => Err(s3_error(&name, e)),
            }
        })?;
        Ok(got.map(|(len, body)| {
            (
                len,
                BucketReader {
                    bucket: self.clone(),
                    key,
                    body: Some(body),
                    chunk: Bytes::new(),
                },
            )
        }))
    }

    /// The object's size and entity tag; `None` when it is not stored.
    pub fn head(&self, key: Key) -> Result<Option<(u64, String)>, Error> {
        let s3 = self.s3.clone();
        self.block(async move {
            match s3.head(&key).await {
                Ok(meta) => Ok(Some((meta.size, meta.e_tag.unwrap_or_default()))),
                Err(object_store::Error::NotFound { .. }) => Ok(None),
                Err(e) => Err(s3_error(&key, e)),
            }
        })
    }

    /// Stores `bytes` whole (an S3 PUT replaces an object atomically).
    pub fn put(&self, key: Key, bytes: Vec<u8>) -> Result<(), Error> {
        let s3 = self.s3.clone();
        self.block(async move {
            s3.put(&key, PutPayload::from(bytes))
                .await
                .map(|_| ())
                .map_err(|e| s3_error(&key, e))
        })
    }

    /// Deletes the object if it is stored.
    pub fn delete(&self, key: Key) -> Result<(), Error> {
        let s3 = self.s3.clone();
        self.block(async move { delete(&s3, &key).await })
    }

    /// Every object under `relative` (a folder), with its size and last change.
    pub fn list(&self, relative: &str) -> Result<Vec<object_store::ObjectMeta>, Error> {
        let (s3, key) = (self.s3.clone(), self.key(relative));
        self.block(async move { list(&s3, &key).await })
    }
}

/// An object's body read from synchronous code ([`Bucket::reader`]): each read that finds
/// the last chunk used up waits for the next one on the client's runtime, so at most one
/// chunk of the HTTP body is held here (a few KiB to a few hundred).
pub(crate) struct BucketReader {
    bucket: Arc<Bucket>,
    key: Key,
    /// `None` once it has ended or failed.
    body: Option<futures_util::stream::BoxStream<'static, object_store::Result<Bytes>>>,
    chunk: Bytes,
}

impl std::io::Read for BucketReader {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        use futures_util::StreamExt;
        while self.chunk.is_empty() {
            let Some(mut body) = self.body.take() else {
                return Ok(0);
            };
            let key = self.key.clone();
            let next = self.bucket.block(async move {
                match body.next().await {
                    None => Ok((None, None)),
                    Some(Ok(chunk)) => Ok((Some(chunk), Some(body))),
                    Some(Err(e)) => Err(s3_error(&key, e)),
                }
            });
            match next {
                Ok((chunk, body)) => {
                    self.body = body;
                    match chunk {
                        Some(chunk) => self.chunk = chunk,
                        None => return Ok(0),
                    }
                }
                Err(e) => return Err(std::io::Error::other(e.to_string())),
            }
        }
        let n = buf.len().min(self.chunk.len());
        buf[..n].copy_from_slice(&self.chunk.split_to(n));
        Ok(n)
    }
}

/// Deletes `key` if it is stored.
pub(crate) async fn delete(s3: &AmazonS3, key: &Key) -> Result<(), Error> {
    match s3.delete(key).await {
        Ok(()) | Err(object_store::Error::NotFound { .. }) => Ok(()),
        Err(e) => Err(s3_error(key, e)),
    }
}

/// Every object under `key`.
pub(crate) async fn list(s3: &AmazonS3, key: &Key) -> Result<Vec<object_store::ObjectMeta>, Error> {
    use futures_util::TryStreamExt;
    use object_store::ObjectStore;
    s3.list(Some(key))
        .try_collect()
        .await
        .map_err(|e| s3_error(key, e))
}

/// Uploads the local file `path` as `key`: one PUT when small, else a multipart upload of
/// [`PART_BYTES`] parts (nothing is visible until it completes; an abandoned one is aborted).
/// The stored object's entity tag.
pub(crate) async fn upload_file(
    s3: Arc<AmazonS3>,
    path: std::path::PathBuf,
    key: Key,
) -> Result<Option<String>, Error> {
    use tokio::io::AsyncReadExt;
    let mut file = tokio::fs::File::open(&path)
        .await
        .map_err(|e| Error::io("cannot open", &path, e))?;
    let len = file
        .metadata()
        .await
        .map_err(|e| Error::io("cannot stat", &path, e))?
        .len();
    if len <= PART_BYTES as u64 {
        let mut bytes = Vec::with_capacity(len as usize);
        file.read_to_end(&mut bytes)
            .await
            .map_err(|e| Error::io("cannot read", &path, e))?;
        return s3
            .put(&key, PutPayload::from(bytes))
            .await
            .map(|put| put.e_tag)
            .map_err(|e| s3_error(&key, e));
    }
    let upload = s3
        .put_multipart(&key)
        .await
        .map_err(|e| s3_error(&key, e))?;
    let mut writer = object_store::WriteMultipart::new_with_chunk_size(upload, PART_BYTES);
    let mut buffer = vec![0u8; 1 << 20];
    loop {
        let n = match file.read(&mut buffer).await {
            Ok(n) => n,
            Err(e) => {
                let _ = writer.abort().await;
                return Err(Error::io("cannot read", &path, e));
            }
        };
        if n == 0 {
            break;
        }
        // At most a few parts in flight: memory stays bounded.
        if let Err(e) = writer.wait_for_capacity(PARTS_IN_FLIGHT).await {
            return Err(s3_error(&key, e));
        }
        writer.write(&buffer[..n]);
    }
    writer
        .finish()
        .await
        .map(|put| put.e_tag)
        .map_err(|e| s3_error(&key, e))
}

/// Size of a multipart upload's parts (S3's minimum is 5 MiB).
pub(crate) const PART_BYTES: usize = 8 << 20;

/// Parts of one multipart upload sent at once.
pub(crate) const PARTS_IN_FLIGHT: usize = 4;
