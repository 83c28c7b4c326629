//! What a token is and what the stores keep of it: making one, its SHA-256 digest, the
//! constant-time comparison and the form a token must have. Pure functions that never panic.

use ring::rand::SecureRandom;

/// Every token starts with this, so a secret scanner (or a person) recognises one.
pub const TOKEN_PREFIX: &str = "sitar_";

/// Longest token accepted from a client (ours have 70 characters); longer input is unknown.
const MAX_TOKEN_LEN: usize = 128;

/// A new random token: the prefix and 256 bits from the system's secure generator, as 64
/// lower-case hex digits (URL-safe, no encoding needed in a query string or cookie).
pub fn new_token() -> Result<String, crate::error::Error> {
    let mut bytes = [0u8; 32];
    ring::rand::SystemRandom::new()
        .fill(&mut bytes)
        .map_err(|_| {
            crate::error::Error::Internal("the system's random generator failed".into())
        })?;
    let mut token = String::with_capacity(TOKEN_PREFIX.len() + 64);
    token.push_str(TOKEN_PREFIX);
    for b in bytes {
        token.push_str(&format!("{b:02x}"));
    }
    Ok(token)
}

/// What the database keeps of a token: its SHA-256, and the first 8 bytes of that as the
/// index a lookup goes by (the full hashes are then compared in constant time).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Digest {
    pub lookup: [u8; 8],
    pub hash: [u8; 32],
}

pub fn digest(token: &str) -> Digest {
    let d = ring::digest::digest(&ring::digest::SHA256, token.as_bytes());
    let mut hash = [0u8; 32];
    hash.copy_from_slice(d.as_ref());
    let mut lookup = [0u8; 8];
    lookup.copy_from_slice(&hash[..8]);
    Digest { lookup, hash }
}

/// Equal hashes, compared in constant time.
pub fn same_hash(a: &[u8], b: &[u8]) -> bool {
    use subtle::ConstantTimeEq;
    a.len() == b.len() && bool::from(a.ct_eq(b))
}

/// Whether `s` could be a token at all: 1 to 128 characters of `[A-Za-z0-9_-]`. Anything
/// else is refused before it reaches the database.
pub fn plausible(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= MAX_TOKEN_LEN
        && s.bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_are_long_random_and_url_safe() {
        let a = new_token().unwrap();
        let b = new_token().unwrap();
        assert_ne!(a, b);
        assert_eq!(a.len(), TOKEN_PREFIX.len() + 64);
        assert!(plausible(&a));
        assert!(a.starts_with(TOKEN_PREFIX));
        // 256 bits: every hex digit appears over a few tokens (not a counter, not constant).
        let many: String = (0..20).map(|_| new_token().unwrap()).collect();
        for digit in "0123456789abcdef".chars() {
            assert!(many.contains(digit), "{digit}");
        }
    }

    #[test]
    fn the_digest_is_sha256_of_the_token() {
        // `printf abc | sha256sum`
        let d = digest("abc");
        let hex: String = d.hash.iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(
            hex,
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert_eq!(d.lookup, d.hash[..8]);
        assert!(same_hash(&d.hash, &digest("abc").hash));
        assert!(!same_hash(&d.hash, &digest("abd").hash));
        assert!(!same_hash(&d.hash, &d.hash[..31]));
    }
}
