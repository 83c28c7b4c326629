use std::hash::{BuildHasher, Hasher};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use axum::body::Bytes;
use futures_util::{Stream, StreamExt};
use tokio::io::AsyncWriteExt;

use crate::Error;

/// The data directory's file layout. Every path is made here, from
/// server-made ids and indices only: no client-supplied name becomes a path.
///
/// ```text
/// DATA/sitar.db                       SQLite: sessions, trials, jobs, devices
/// DATA/tmp/upload-*.part              uploads in progress (cleared at start)
/// DATA/sessions/ID/recording          the uploaded recording (mp4 or sim recording)
/// DATA/sessions/ID/trials/trial_NNN.txt   one TUM file per finished trial
/// DATA/sessions/ID/timestamps.txt     legacy POST /timestamps upload
/// DATA/sessions/ID/results.csv|json   latest published estimate
/// ```
#[derive(Debug, Clone)]
pub(crate) struct Files {
    root: PathBuf,
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
        // Half-written uploads of a dead process are garbage.
        if let Ok(entries) = std::fs::read_dir(root.join("tmp")) {
            for entry in entries.flatten() {
                let _ = std::fs::remove_file(entry.path());
            }
        }
        Ok(Files {
            root: root.to_path_buf(),
        })
    }

    pub fn session_dir(&self, id: &str) -> PathBuf {
        debug_assert!(is_server_id(id));
        self.root.join("sessions").join(id)
    }

    pub fn recording(&self, id: &str) -> PathBuf {
        self.session_dir(id).join("recording")
    }

    pub fn trial(&self, id: &str, index: u32) -> PathBuf {
        self.session_dir(id)
            .join("trials")
            .join(format!("trial_{index:03}.txt"))
    }

    pub fn timestamps(&self, id: &str) -> PathBuf {
        self.session_dir(id).join("timestamps.txt")
    }

    pub fn results_csv(&self, id: &str) -> PathBuf {
        self.session_dir(id).join("results.csv")
    }

    pub fn results_json(&self, id: &str) -> PathBuf {
        self.session_dir(id).join("results.json")
    }

    pub fn create_session_dirs(&self, id: &str) -> Result<(), Error> {
        let dir = self.session_dir(id).join("trials");
        std::fs::create_dir_all(&dir).map_err(|e| Error::io("cannot create", &dir, e))
    }

    fn temp_path(&self) -> PathBuf {
        self.root
            .join("tmp")
            .join(format!("upload-{}.part", new_id()))
    }

    /// Streams `body` into a temporary file, refusing more than `limit` bytes.
    /// The caller moves the result into place with [`Files::publish`].
    pub async fn receive<S, E>(
        &self,
        mut body: S,
        limit: u64,
        what: &'static str,
    ) -> Result<TempFile, Error>
    where
        S: Stream<Item = Result<Bytes, E>> + Unpin,
        E: std::fmt::Display,
    {
        let temp = TempFile {
            path: self.temp_path(),
            bytes: 0,
        };
        let file = tokio::fs::File::create(&temp.path)
            .await
            .map_err(|e| Error::io("cannot create", &temp.path, e))?;
        let mut out = tokio::io::BufWriter::with_capacity(1 << 20, file);
        let mut temp = temp;
        while let Some(chunk) = body.next().await {
            let chunk =
                chunk.map_err(|e| Error::BadRequest(format!("{what}: body broke off: {e}")))?;
            temp.bytes += chunk.len() as u64;
            if temp.bytes > limit {
                return Err(Error::TooLarge { what, limit });
            }
            out.write_all(&chunk)
                .await
                .map_err(|e| Error::io("cannot write", &temp.path, e))?;
        }
        out.flush()
            .await
            .map_err(|e| Error::io("cannot write", &temp.path, e))?;
        Ok(temp)
    }

    /// Writes small server-made content atomically (temp file + rename).
    pub fn write_atomic(&self, dest: &Path, content: &[u8]) -> Result<(), Error> {
        let temp = TempFile {
            path: self.temp_path(),
            bytes: content.len() as u64,
        };
        std::fs::write(&temp.path, content)
            .map_err(|e| Error::io("cannot write", &temp.path, e))?;
        temp.publish(dest)
    }
}

/// An upload in `DATA/tmp`; removed on drop unless published.
#[derive(Debug)]
pub(crate) struct TempFile {
    pub path: PathBuf,
    pub bytes: u64,
}

impl TempFile {
    /// Moves the file to `dest` (same file system: an atomic rename).
    pub fn publish(self, dest: &Path) -> Result<(), Error> {
        if let Some(parent) = dest.parent() {
            std::fs::create_dir_all(parent).map_err(|e| Error::io("cannot create", parent, e))?;
        }
        std::fs::rename(&self.path, dest)
            .map_err(|e| Error::io("cannot move upload to", dest, e))?;
        std::mem::forget(self);
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    async fn receive_enforces_the_limit_and_leaves_no_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        let files = Files::open(dir.path()).unwrap();
        let chunks = || {
            futures_util::stream::iter(
                (0..4).map(|_| Ok::<_, std::io::Error>(Bytes::from(vec![7u8; 1000]))),
            )
        };
        let err = files
            .receive(chunks(), 3999, "recording")
            .await
            .unwrap_err();
        assert!(matches!(err, Error::TooLarge { limit: 3999, .. }));
        assert_eq!(
            std::fs::read_dir(dir.path().join("tmp")).unwrap().count(),
            0
        );
        let temp = files.receive(chunks(), 4000, "recording").await.unwrap();
        assert_eq!(temp.bytes, 4000);
        let dest = dir.path().join("sessions/x/recording");
        temp.publish(&dest).unwrap();
        assert_eq!(std::fs::read(&dest).unwrap(), vec![7u8; 4000]);
        assert_eq!(
            std::fs::read_dir(dir.path().join("tmp")).unwrap().count(),
            0
        );
    }
}
