//! Access tokens as `sitar token` manages them: names checked, a token shown once when it is
//! made (the store keeps only its hash, [`crate::storage::metadata::TokenStore`]).
//! `sitar token` opens the data directory's embedded store, so it works while the server
//! runs.

use std::path::Path;

use crate::auth::secret;
use crate::error::Error;
use crate::model::{Role, TokenInfo};
use crate::storage::open::open_metadata;

/// Makes a token named `name` with `role` in the data directory's database and returns it
/// (the only time it is shown: only its hash is stored).
pub fn create_token(data_dir: &Path, role: Role, name: &str) -> Result<String, Error> {
    create_token_at(data_dir, None, role, name)
}

/// The tokens of the data directory's database, oldest first.
pub fn list_tokens(data_dir: &Path) -> Result<Vec<TokenInfo>, Error> {
    list_tokens_at(data_dir, None)
}

/// Revokes the token named `name`: its next request is answered 401. Whether it existed.
pub fn revoke_token(data_dir: &Path, name: &str) -> Result<bool, Error> {
    revoke_token_at(data_dir, None, name)
}

/// [`create_token`] in the Postgres database at `database` when given (`sitar token create
/// --database URL`), else in the data directory's.
pub fn create_token_at(
    data_dir: &Path,
    database: Option<&str>,
    role: Role,
    name: &str,
) -> Result<String, Error> {
    let token = secret::new_token()?;
    open_metadata(data_dir, database)?.insert_token(name, role, &token)?;
    Ok(token)
}

/// [`list_tokens`] of the Postgres database at `database` when given.
pub fn list_tokens_at(data_dir: &Path, database: Option<&str>) -> Result<Vec<TokenInfo>, Error> {
    open_metadata(data_dir, database)?.tokens()
}

/// [`revoke_token`] in the Postgres database at `database` when given.
pub fn revoke_token_at(data_dir: &Path, database: Option<&str>, name: &str) -> Result<bool, Error> {
    open_metadata(data_dir, database)?.revoke_token(name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Caller;
    use crate::storage::TokenStore;
    use crate::storage::sqlite::SqliteStore;

    #[test]
    fn only_hashes_are_stored_and_revocation_is_immediate() {
        let dir = tempfile::tempdir().unwrap();
        let token = create_token(dir.path(), Role::App, "phone-1").unwrap();
        let db = SqliteStore::open(&dir.path().join("sitar.db")).unwrap();
        assert!(matches!(
            db.caller(&token).unwrap(),
            Some(Caller::Token {
                role: Role::App,
                ..
            })
        ));
        assert_eq!(db.caller("sitar_nope").unwrap(), None);
        assert_eq!(db.caller("").unwrap(), None);
        // The raw token appears nowhere in the database file (nor its WAL).
        for file in ["sitar.db", "sitar.db-wal"] {
            if let Ok(bytes) = std::fs::read(dir.path().join(file)) {
                let text = String::from_utf8_lossy(&bytes);
                assert!(
                    !text.contains(&token[crate::model::token_secret::TOKEN_PREFIX.len()..]),
                    "{file}"
                );
            }
        }
        let listed = list_tokens(dir.path()).unwrap();
        assert_eq!(listed.len(), 1);
        assert_eq!(listed[0].name, "phone-1");
        assert!(listed[0].last_used_ms.is_some(), "the lookup touched it");
        // The same name twice is refused; a bad name is named.
        assert!(create_token(dir.path(), Role::App, "phone-1").is_err());
        let err = create_token(dir.path(), Role::App, "a b")
            .unwrap_err()
            .to_string();
        assert!(err.contains("token name"), "{err}");
        assert!(revoke_token(dir.path(), "phone-1").unwrap());
        assert!(!revoke_token(dir.path(), "phone-1").unwrap());
        assert_eq!(db.caller(&token).unwrap(), None);
        assert_eq!(db.token_count().unwrap(), 0);
    }
}
