//! Each instance's own files in its data directory, beside the stores: the admin token the
//! first start writes (`DATA/admin.token`), the self-signed TLS certificate of `--tls`
//! (`DATA/tls/cert.pem`, `DATA/tls/key.pem`) and the instance's id (`DATA/instance.id`, made
//! on first start: a restarted instance knows the sessions it played before). Secrets are written readable by their owner
//! only (mode 0600) and synced before they are used.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::error::Error;

/// The file in the data directory that holds the admin token made on first start.
pub const ADMIN_TOKEN_FILE: &str = "admin.token";

/// The file in the data directory that holds the instance's id.
pub const INSTANCE_ID_FILE: &str = "instance.id";

/// The longest instance id read back from [`INSTANCE_ID_FILE`].
const INSTANCE_ID_MAX: usize = 64;

/// This instance's id: read from `DATA/instance.id`, or made (`i` and 16 random hex digits)
/// and written there on first start. A file whose id is empty, longer than 64 characters or
/// has characters other than ASCII letters, digits, `-` and `_` is an error naming it.
pub(crate) fn instance_id(data_dir: &Path) -> Result<String, Error> {
    let path = data_dir.join(INSTANCE_ID_FILE);
    match std::fs::read_to_string(&path) {
        Ok(text) => {
            let id = text.trim();
            let fine = !id.is_empty()
                && id.len() <= INSTANCE_ID_MAX
                && id
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
            if !fine {
                return Err(Error::Config(format!(
                    "{}: line 1 is not an instance id (1 to {INSTANCE_ID_MAX} ASCII letters,                      digits, '-' or '_'); remove the file to make a new one",
                    path.display()
                )));
            }
            Ok(id.to_string())
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let mut bytes = [0u8; 8];
            ring::rand::SecureRandom::fill(&ring::rand::SystemRandom::new(), &mut bytes)
                .map_err(|_| Error::Internal("no random bytes for the instance id".into()))?;
            let id: String = std::iter::once("i".to_string())
                .chain(bytes.iter().map(|b| format!("{b:02x}")))
                .collect();
            write_secret(&path, &format!("{id}\n"), true)?;
            Ok(id)
        }
        Err(e) => Err(Error::io("cannot read", &path, e)),
    }
}

/// Where data directory `data_dir` keeps its admin token.
pub(crate) fn admin_token_file(data_dir: &Path) -> PathBuf {
    data_dir.join(ADMIN_TOKEN_FILE)
}

/// Writes the admin token to a file that must not exist yet, readable by its owner only.
pub(crate) fn write_admin_token(data_dir: &Path, token: &str) -> Result<(), Error> {
    write_secret(&admin_token_file(data_dir), &format!("{token}\n"), true)
}

/// Removes the admin token file this instance wrote when another instance on the same
/// database made the admin token first.
pub(crate) fn remove_admin_token(data_dir: &Path) {
    let _ = std::fs::remove_file(admin_token_file(data_dir));
}

/// The self-signed certificate and key of data directory `data_dir` (`tls/cert.pem`,
/// `tls/key.pem`), and whether both exist.
pub(crate) fn tls_pair(data_dir: &Path) -> (PathBuf, PathBuf, bool) {
    let dir = data_dir.join("tls");
    let (cert, key) = (dir.join("cert.pem"), dir.join("key.pem"));
    let both = cert.exists() && key.exists();
    (cert, key, both)
}

/// Writes a self-signed certificate and its key (mode 0600) into data directory `data_dir`.
pub(crate) fn write_tls_pair(data_dir: &Path, cert_pem: &str, key_pem: &str) -> Result<(), Error> {
    let (cert, key, _) = tls_pair(data_dir);
    if let Some(dir) = cert.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::io("cannot create", dir, e))?;
    }
    write_secret(&key, key_pem, false)?;
    write_file(&cert, cert_pem)
}

/// Writes `text` readable by its owner only; `new` refuses a file that exists already.
fn write_secret(path: &Path, text: &str, new: bool) -> Result<(), Error> {
    let mut options = std::fs::OpenOptions::new();
    options.write(true);
    if new {
        options.create_new(true);
    } else {
        options.create(true).truncate(true);
    }
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::mode(&mut options, 0o600);
    let mut file = options
        .open(path)
        .map_err(|e| Error::io("cannot create", path, e))?;
    file.write_all(text.as_bytes())
        .and_then(|()| file.sync_all())
        .map_err(|e| Error::io("cannot write", path, e))
}

fn write_file(path: &Path, text: &str) -> Result<(), Error> {
    std::fs::write(path, text).map_err(|e| Error::io("cannot write", path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_instance_id_is_made_once_and_a_bad_one_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let id = instance_id(dir.path()).unwrap();
        assert!(id.starts_with('i') && id.len() == 17, "{id}");
        assert_eq!(instance_id(dir.path()).unwrap(), id);
        let other = tempfile::tempdir().unwrap();
        assert_ne!(instance_id(other.path()).unwrap(), id);
        std::fs::write(dir.path().join(INSTANCE_ID_FILE), "two words\n").unwrap();
        let err = instance_id(dir.path()).unwrap_err().to_string();
        assert!(
            err.contains("instance.id") && err.contains("line 1"),
            "{err}"
        );
    }
}
