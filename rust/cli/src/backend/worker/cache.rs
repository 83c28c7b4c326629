//! The host's recordings, kept by content (`DIR/recordings/SHA256`): a recording is
//! downloaded once per host, however many of its trials the phones play. Bounded: after each
//! download the least recently used files go until the folder holds at most `max_bytes`
//! (the file just fetched always stays).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result, bail};

/// The recordings a host keeps.
pub struct RecordingCache {
    dir: PathBuf,
    max_bytes: u64,
    /// One download at a time: two phones leasing trials of one session fetch it once.
    fetching: Mutex<()>,
}

/// SHA-256 of a file, hex.
fn sha256_file(path: &Path) -> Result<String> {
    use std::io::Read;
    let mut file =
        std::fs::File::open(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut digest = ring::digest::Context::new(&ring::digest::SHA256);
    let mut buf = vec![0u8; 1 << 20];
    loop {
        let n = file
            .read(&mut buf)
            .with_context(|| format!("cannot read {}", path.display()))?;
        if n == 0 {
            break;
        }
        digest.update(&buf[..n]);
    }
    Ok(digest
        .finish()
        .as_ref()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
}

impl RecordingCache {
    /// The cache in `dir/recordings` (created), holding at most `max_bytes`.
    pub fn open(dir: &Path, max_bytes: u64) -> Result<RecordingCache> {
        let dir = dir.join("recordings");
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        // Half-fetched files of an earlier run are garbage.
        for entry in std::fs::read_dir(&dir)?.flatten() {
            if entry.file_name().to_string_lossy().ends_with(".part") {
                let _ = std::fs::remove_file(entry.path());
            }
        }
        Ok(RecordingCache {
            dir,
            max_bytes,
            fetching: Mutex::new(()),
        })
    }

    /// The recording with hash `sha256`: from the cache, or fetched with `fetch(part_file)`
    /// and checked against the hash first. Returns its path and whether it was fetched now.
    pub fn get(
        &self,
        sha256: &str,
        fetch: impl FnOnce(&Path) -> Result<()>,
    ) -> Result<(PathBuf, bool)> {
        if sha256.len() != 64 || !sha256.bytes().all(|b| b.is_ascii_hexdigit()) {
            bail!("the server named the recording {sha256:.80?}, not a SHA-256");
        }
        let path = self.dir.join(sha256);
        let _one = self.fetching.lock().unwrap_or_else(|e| e.into_inner());
        if path.is_file() {
            touch(&path);
            return Ok((path, false));
        }
        let part = self.dir.join(format!("{sha256}.part"));
        fetch(&part)?;
        let got = sha256_file(&part)?;
        if got != sha256 {
            let _ = std::fs::remove_file(&part);
            bail!("the recording fetched has SHA-256 {got}, the lease named {sha256}");
        }
        std::fs::rename(&part, &path)
            .with_context(|| format!("cannot rename into {}", path.display()))?;
        self.evict(&path);
        Ok((path, true))
    }

    /// Bytes held now.
    #[cfg(test)]
    pub fn bytes(&self) -> u64 {
        self.entries().iter().map(|(_, len, _)| len).sum()
    }

    fn entries(&self) -> Vec<(PathBuf, u64, std::time::SystemTime)> {
        let Ok(dir) = std::fs::read_dir(&self.dir) else {
            return Vec::new();
        };
        dir.flatten()
            .filter(|e| !e.file_name().to_string_lossy().ends_with(".part"))
            .filter_map(|e| {
                let meta = e.metadata().ok()?;
                Some((e.path(), meta.len(), meta.modified().ok()?))
            })
            .collect()
    }

    /// Removes the least recently used recordings (never `keep`) beyond the bound.
    fn evict(&self, keep: &Path) {
        let mut entries = self.entries();
        let mut total: u64 = entries.iter().map(|(_, len, _)| len).sum();
        entries.sort_by_key(|(_, _, used)| *used);
        for (path, len, _) in entries {
            if total <= self.max_bytes {
                break;
            }
            if path != keep && std::fs::remove_file(&path).is_ok() {
                log::info!("recording cache: removed {} ({len} bytes)", path.display());
                total -= len;
            }
        }
    }
}

/// Marks a cached file used now (its modification time orders the eviction).
fn touch(path: &Path) {
    if let Ok(file) = std::fs::File::options().append(true).open(path) {
        let _ = file.set_modified(std::time::SystemTime::now());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ABC: &str = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";

    #[test]
    fn a_recording_is_fetched_once_checked_and_the_cache_stays_bounded() {
        let dir = tempfile::tempdir().unwrap();
        let cache = RecordingCache::open(dir.path(), 4).unwrap();
        let (path, fetched) = cache
            .get(ABC, |part| Ok(std::fs::write(part, b"abc")?))
            .unwrap();
        assert!(fetched);
        assert_eq!(std::fs::read(&path).unwrap(), b"abc");
        // The second time comes from the cache: the fetch is never called.
        let (again, fetched) = cache.get(ABC, |_| bail!("fetched twice")).unwrap();
        assert_eq!((again, fetched), (path.clone(), false));
        // Bytes that do not match the hash are refused and not kept.
        let other = "0".repeat(64);
        let err = cache
            .get(&other, |part| Ok(std::fs::write(part, b"xyz")?))
            .unwrap_err();
        assert!(err.to_string().contains("SHA-256"), "{err}");
        assert!(!dir.path().join("recordings").join(&other).exists());
        // A second recording passes the 4-byte bound: the older one goes.
        let def = "cb8379ac2098aa165029e3938a51da0bcecfc008fd6795f401178647f96c5b34";
        let (newer, _) = cache
            .get(def, |part| Ok(std::fs::write(part, b"def")?))
            .unwrap();
        assert!(newer.is_file() && !path.exists());
        assert_eq!(cache.bytes(), 3);
        assert!(cache.get("../etc", |_| Ok(())).is_err());
    }
}
