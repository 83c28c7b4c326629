//! A token as the stores keep and list it: its record and the rule for its name.

use crate::error::Error;
use crate::model::role::Role;

/// A token as `sitar token list` shows it: never the token itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TokenInfo {
    /// The name given when it was made (unique).
    pub name: String,
    /// What it may do.
    pub role: Role,
    /// Made at, ms since the Unix epoch.
    pub created_ms: i64,
    /// Last request with it, ms since the Unix epoch (to the minute).
    pub last_used_ms: Option<i64>,
}

/// Token names: 1 to 64 letters, digits and `._-` (they appear in logs and listings).
pub(crate) fn check_token_name(name: &str) -> Result<(), Error> {
    let ok = !name.is_empty()
        && name.len() <= 64
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c));
    if ok {
        Ok(())
    } else {
        Err(Error::BadRequest(format!(
            "token name {name:?}: use 1 to 64 letters, digits, '.', '_' or '-'"
        )))
    }
}
