//! An embedded installation as `sitar migrate` reads it: the data directory's database, held
//! under SQLite's exclusive lock for the whole copy ([`SqliteSource`]), and its session
//! folders' objects, named by [`SessionObject`]. Also the cluster stores it copies into,
//! with their local scratch in `DATA/tmp/migrate` (the next server start on the folder
//! empties `DATA/tmp`; the copy removes it when it ends).

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::error::Error;
use crate::storage::blobs::BlobStore;
use crate::storage::embedded::DATABASE_FILE;
pub(crate) use crate::storage::files::is_server_id;
use crate::storage::keys::SessionObject;
use crate::storage::postgres::{PgStore, is_postgres_url, redact};
use crate::storage::s3::S3Blobs;
use crate::storage::sqlite::export::SqliteSource;
use crate::storage::staged::TempFile;

/// Folders inside a session's folder that are working files or caches, never copied.
const WORKING_FOLDERS: &[&str] = &["phone", "adb-pull"];

/// A SHA-256 as lowercase hex.
pub(crate) type Sha256 = String;

/// An embedded data directory, locked.
pub(crate) struct Installation {
    dir: PathBuf,
    /// The database, under the exclusive lock.
    pub db: SqliteSource,
    scratch: PathBuf,
}

/// The objects of one session's folder.
#[derive(Debug, Default)]
pub(crate) struct Objects {
    /// Each object and its length, in a stable order.
    pub found: Vec<(SessionObject, u64)>,
    /// Files that are no object of this version (named in the summary, not copied).
    pub unknown: Vec<String>,
}

impl Installation {
    /// Opens data directory `dir`; a server running on it is refused, naming it.
    pub(crate) fn open(dir: &Path) -> Result<Installation, Error> {
        let db = SqliteSource::open(&dir.join(DATABASE_FILE))?;
        let scratch = dir.join("tmp").join("migrate");
        if scratch.exists() {
            std::fs::remove_dir_all(&scratch)
                .map_err(|e| Error::io("cannot empty", &scratch, e))?;
        }
        std::fs::create_dir_all(&scratch).map_err(|e| Error::io("cannot create", &scratch, e))?;
        Ok(Installation {
            dir: dir.to_path_buf(),
            db,
            scratch,
        })
    }

    /// The cluster stores of `database` (Postgres; migrations applied) and `store` (an
    /// S3-compatible bucket), with this copy's scratch folder as the bucket's local folder.
    pub(crate) fn open_target(
        &self,
        database: &str,
        store: &str,
    ) -> Result<(PgStore, S3Blobs), Error> {
        if !is_postgres_url(database) {
            return Err(Error::Config(format!(
                "--database {}: expected postgres://USER@HOST:PORT/DATABASE",
                redact(database)
            )));
        }
        let db = PgStore::open(database)?;
        let idle = std::time::Duration::from_secs(60);
        let blobs = S3Blobs::open(store, &self.scratch.join("store"), idle, u64::MAX, u64::MAX)?;
        Ok((db, blobs))
    }

    /// The session ids that have a folder, sorted.
    pub(crate) fn folders(&self) -> Result<Vec<String>, Error> {
        let root = self.dir.join("sessions");
        let mut ids: Vec<String> = match std::fs::read_dir(&root) {
            Ok(entries) => entries
                .flatten()
                .filter(|e| e.path().is_dir())
                .filter_map(|e| e.file_name().to_str().map(str::to_string))
                .filter(|id| crate::storage::files::is_server_id(id))
                .collect(),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
            Err(e) => return Err(Error::io("cannot list", &root, e)),
        };
        ids.sort();
        Ok(ids)
    }

    fn path(&self, id: &str, object: SessionObject) -> PathBuf {
        debug_assert!(crate::storage::files::is_server_id(id));
        self.dir
            .join("sessions")
            .join(id)
            .join(object.relative_path())
    }

    /// The objects in session `id`'s folder (none when it has no folder).
    pub(crate) fn objects(&self, id: &str) -> Result<Objects, Error> {
        let folder = self.dir.join("sessions").join(id);
        let mut objects = Objects::default();
        let mut pending = vec![folder.clone()];
        while let Some(dir) = pending.pop() {
            let entries = match std::fs::read_dir(&dir) {
                Ok(entries) => entries,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) => return Err(Error::io("cannot list", &dir, e)),
            };
            for entry in entries {
                let entry = entry.map_err(|e| Error::io("cannot list", &dir, e))?;
                let path = entry.path();
                let relative = path
                    .strip_prefix(&folder)
                    .unwrap_or(&path)
                    .to_string_lossy()
                    .replace('\\', "/");
                let meta = entry
                    .metadata()
                    .map_err(|e| Error::io("cannot stat", &path, e))?;
                if meta.is_dir() {
                    if !WORKING_FOLDERS.contains(&relative.as_str()) {
                        pending.push(path);
                    }
                    continue;
                }
                match SessionObject::from_relative_path(&relative) {
                    Some(object) => objects.found.push((object, meta.len())),
                    None => objects.unknown.push(format!("sessions/{id}/{relative}")),
                }
            }
        }
        objects
            .found
            .sort_by_key(|(object, _)| object.relative_path());
        objects.unknown.sort();
        Ok(objects)
    }

    /// The SHA-256 of session `id`'s `object` here.
    pub(crate) fn sha256(&self, id: &str, object: SessionObject) -> Result<Sha256, Error> {
        sha256_file(&self.path(id, object))
    }

    /// Stores session `id`'s `object` from here in `blobs`, replacing what is there.
    pub(crate) fn copy_into(
        &self,
        id: &str,
        object: SessionObject,
        blobs: &dyn BlobStore,
    ) -> Result<(), Error> {
        let path = self.path(id, object);
        // A second name for the file, which publishing consumes (the original stays).
        let link = self
            .scratch
            .join(format!("link-{}", crate::storage::files::new_id()));
        if std::fs::hard_link(&path, &link).is_err() {
            std::fs::copy(&path, &link).map_err(|e| Error::io("cannot copy", &path, e))?;
        }
        let bytes = std::fs::metadata(&link)
            .map_err(|e| Error::io("cannot stat", &link, e))?
            .len();
        blobs.publish(TempFile { path: link, bytes }, id, object)
    }

    /// Removes this copy's scratch folder.
    pub(crate) fn close(self) {
        if let Err(e) = std::fs::remove_dir_all(&self.scratch) {
            log::warn!("cannot remove {}: {e}", self.scratch.display());
        }
    }
}

/// The SHA-256 of session `id`'s `object` in `blobs`, and its length; `None` when it is not
/// stored. Read from the store a chunk at a time.
pub(crate) fn sha256_in(
    blobs: &dyn BlobStore,
    id: &str,
    object: SessionObject,
) -> Result<Option<(u64, Sha256)>, Error> {
    let Some(found) = blobs.open(id, object)? else {
        return Ok(None);
    };
    let sha = sha256_of(found.bytes).map_err(|e| {
        Error::Internal(format!(
            "cannot read {} of {id}: {e}",
            object.relative_path()
        ))
    })?;
    Ok(Some((found.len, sha)))
}

/// The SHA-256 of the file at `path`.
fn sha256_file(path: &Path) -> Result<Sha256, Error> {
    let file = std::fs::File::open(path).map_err(|e| Error::io("cannot open", path, e))?;
    sha256_of(file).map_err(|e| Error::io("cannot read", path, e))
}

/// The SHA-256 of what `bytes` holds, read in 1 MiB blocks.
fn sha256_of(mut bytes: impl Read) -> std::io::Result<Sha256> {
    let mut context = ring::digest::Context::new(&ring::digest::SHA256);
    let mut buffer = vec![0u8; 1 << 20];
    loop {
        let n = bytes.read(&mut buffer)?;
        if n == 0 {
            break;
        }
        context.update(&buffer[..n]);
    }
    Ok(hex(context.finish().as_ref()))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_session_folder_lists_its_objects_and_names_strangers() {
        let dir = tempfile::tempdir().unwrap();
        crate::storage::sqlite::SqliteStore::open(&dir.path().join(DATABASE_FILE)).unwrap();
        let id = "s0123456789abcdef";
        let folder = dir.path().join("sessions").join(id);
        for (path, text) in [
            ("recording", "rec"),
            ("trials/trial_000.txt", "0 0 0 0 0 0 0 1\n"),
            ("thumbnails/3.jpg", "jpg"),
            ("phone_log/anchors.csv", "a"),
            ("phone/session.json", "{}"),
            ("notes.txt", "?"),
        ] {
            let path = folder.join(path);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, text).unwrap();
        }
        let install = Installation::open(dir.path()).unwrap();
        assert_eq!(install.folders().unwrap(), [id]);
        let objects = install.objects(id).unwrap();
        let found: Vec<_> = objects.found.iter().map(|(o, _)| *o).collect();
        // Sorted by path; the phone's working folder is left out.
        assert_eq!(
            found,
            [
                SessionObject::Anchors,
                SessionObject::Recording,
                SessionObject::Thumbnail(3),
                SessionObject::Trial(0),
            ]
        );
        assert_eq!(objects.unknown, [format!("sessions/{id}/notes.txt")]);
        assert_eq!(
            install.sha256(id, SessionObject::Recording).unwrap(),
            // sha256("rec")
            hex(ring::digest::digest(&ring::digest::SHA256, b"rec").as_ref())
        );
        assert!(
            install
                .objects("s00000000000000ff")
                .unwrap()
                .found
                .is_empty()
        );
    }
}
