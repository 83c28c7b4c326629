//! Tokens a server has from its start: the admin token a new data directory gets (written to
//! `DATA/admin.token`, mode 0600, never overwritten), and tokens an embedding program
//! registers (the demo, the tests).

use std::path::Path;

use crate::auth::secret;
use crate::error::Error;
use crate::model::Role;
use crate::storage::TokenStore;
use crate::storage::instance;

pub use crate::storage::instance::ADMIN_TOKEN_FILE;

/// The name of the first admin token in `sitar token list`.
const ADMIN_TOKEN_NAME: &str = "admin";

/// A token registered at start ([`crate::config::ServerConfig::preset_tokens`]): its hash replaces
/// whatever a token of that name had.
#[derive(Clone, PartialEq, Eq)]
pub struct PresetToken {
    /// Its name (1 to 64 letters, digits, `._-`).
    pub name: String,
    /// What it may do.
    pub role: Role,
    /// The token (at least 22 characters of `[A-Za-z0-9_-]`: 128 bits when random).
    pub token: String,
}

impl std::fmt::Debug for PresetToken {
    // Never the token.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PresetToken")
            .field("name", &self.name)
            .field("role", &self.role)
            .finish_non_exhaustive()
    }
}

/// Registers the preset tokens; on a data directory without `admin.token` whose database has
/// no `admin` token yet, makes one and writes the file. Returns the new admin token, to be
/// shown once.
pub(crate) fn ensure_admin_token(
    data_dir: &Path,
    db: &dyn TokenStore,
    presets: &[PresetToken],
) -> Result<Option<String>, Error> {
    for preset in presets {
        if preset.token.len() < 22 || !secret::plausible(&preset.token) {
            return Err(Error::Config(format!(
                "preset token {:?}: use at least 22 characters of [A-Za-z0-9_-]",
                preset.name
            )));
        }
        db.set_token(&preset.name, preset.role, &preset.token)?;
    }
    let file = instance::admin_token_file(data_dir);
    if file.exists() || db.has_token(ADMIN_TOKEN_NAME)? {
        if !file.exists() {
            log::warn!(
                "{} is missing; `sitar token create --role admin` makes another admin token",
                file.display()
            );
        }
        return Ok(None);
    }
    let token = secret::new_token()?;
    instance::write_admin_token(data_dir, &token)?;
    match db.insert_token(ADMIN_TOKEN_NAME, Role::Admin, &token) {
        Ok(()) => Ok(Some(token)),
        // Another instance on the same database made it first: this one's file goes.
        Err(Error::Conflict(_)) => {
            instance::remove_admin_token(data_dir);
            log::info!("another instance made the admin token first (its DATA/admin.token)");
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::sqlite::SqliteStore;

    #[test]
    fn the_admin_token_is_made_once_and_never_overwritten() {
        let dir = tempfile::tempdir().unwrap();
        let db = SqliteStore::open(&dir.path().join("sitar.db")).unwrap();
        let token = ensure_admin_token(dir.path(), &db, &[]).unwrap().unwrap();
        let file = dir.path().join(ADMIN_TOKEN_FILE);
        assert_eq!(std::fs::read_to_string(&file).unwrap().trim(), token);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&file).unwrap().permissions().mode();
            assert_eq!(mode & 0o777, 0o600);
        }
        assert!(db.caller(&token).unwrap().unwrap().is_admin());
        // A second start leaves it alone, and so does one after the file was deleted.
        assert_eq!(ensure_admin_token(dir.path(), &db, &[]).unwrap(), None);
        std::fs::remove_file(&file).unwrap();
        assert_eq!(ensure_admin_token(dir.path(), &db, &[]).unwrap(), None);
        assert!(!file.exists());
    }

    #[test]
    fn short_preset_tokens_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let db = SqliteStore::open(&dir.path().join("sitar.db")).unwrap();
        let short = PresetToken {
            name: "t".into(),
            role: Role::App,
            token: "sitar_short".into(),
        };
        let err = ensure_admin_token(dir.path(), &db, &[short]).unwrap_err();
        assert!(err.to_string().contains("22 characters"), "{err}");
    }
}
