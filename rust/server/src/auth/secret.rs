//! Secrets on the wire: making tokens, hashing them for storage, and finding them in an
//! `Authorization` header, a cookie or a query string. Pure functions: the property tests and
//! the fuzz target call them with arbitrary input, and none of them panics.

use ring::rand::SecureRandom;

/// Every token starts with this, so a secret scanner (or a person) recognises one.
pub const TOKEN_PREFIX: &str = "sitar_";

/// The cookie the HTML pages authenticate with after a `?token=` visit.
pub const COOKIE_NAME: &str = "sitar_token";

/// Longest token accepted from a client (ours have 70 characters); longer input is unknown.
const MAX_TOKEN_LEN: usize = 128;

/// A new random token: the prefix and 256 bits from the system's secure generator, as 64
/// lower-case hex digits (URL-safe, no encoding needed in a query string or cookie).
pub fn new_token() -> Result<String, crate::Error> {
    let mut bytes = [0u8; 32];
    ring::rand::SystemRandom::new()
        .fill(&mut bytes)
        .map_err(|_| crate::Error::Internal("the system's random generator failed".into()))?;
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

/// The token of an `Authorization: Bearer TOKEN` header value (scheme case-insensitive, as
/// RFC 7235 says); `None` for another scheme or an implausible token.
pub fn bearer(header: &str) -> Option<&str> {
    let (scheme, rest) = header.trim().split_once(' ')?;
    if !scheme.eq_ignore_ascii_case("bearer") {
        return None;
    }
    let token = rest.trim_start_matches(' ');
    plausible(token).then_some(token)
}

/// The value of cookie `name` in a `Cookie` header (`a=1; b=2`), if plausible as a token.
pub fn cookie<'a>(header: &'a str, name: &str) -> Option<&'a str> {
    header
        .split(';')
        .filter_map(|pair| pair.trim().split_once('='))
        .find(|(key, _)| *key == name)
        .map(|(_, value)| value.trim().trim_matches('"'))
        .filter(|value| plausible(value))
}

/// The value of query parameter `name` (the raw text, not decoded: tokens need no decoding,
/// and one that would is not a token), if plausible as a token.
pub fn query_param<'a>(query: &'a str, name: &str) -> Option<&'a str> {
    query
        .split('&')
        .filter_map(|pair| pair.split_once('='))
        .find(|(key, _)| *key == name)
        .map(|(_, value)| value)
        .filter(|value| plausible(value))
}

/// `query` without any `name=…` parameter (what the redirect after a `?token=` visit keeps).
pub fn without_param(query: &str, name: &str) -> String {
    query
        .split('&')
        .filter(|pair| !pair.is_empty() && pair.split_once('=').map_or(*pair, |p| p.0) != name)
        .collect::<Vec<_>>()
        .join("&")
}

/// Whether a query string carries parameter `name` at all (plausible or not).
pub fn has_param(query: &str, name: &str) -> bool {
    query
        .split('&')
        .any(|pair| pair.split_once('=').map_or(pair, |p| p.0) == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

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

    #[test]
    fn headers_cookies_and_queries_give_the_token() {
        assert_eq!(bearer("Bearer sitar_ab"), Some("sitar_ab"));
        assert_eq!(bearer("bearer  sitar_ab "), Some("sitar_ab"));
        assert_eq!(bearer("Basic dXNlcjpwYXNz"), None);
        assert_eq!(bearer("Bearer"), None);
        assert_eq!(bearer("Bearer a b"), None);
        assert_eq!(bearer("Bearer <script>"), None);
        assert_eq!(
            cookie("a=1; sitar_token=sitar_x; b=2", COOKIE_NAME),
            Some("sitar_x")
        );
        assert_eq!(cookie("xsitar_token=sitar_x", COOKIE_NAME), None);
        assert_eq!(cookie("sitar_token=", COOKIE_NAME), None);
        assert_eq!(
            query_param("limit=5&token=sitar_q", "token"),
            Some("sitar_q")
        );
        assert_eq!(query_param("token=a%20b", "token"), None);
        assert_eq!(without_param("a=1&token=x&b=2", "token"), "a=1&b=2");
        assert_eq!(without_param("token=x", "token"), "");
        assert_eq!(without_param("tokens=x", "token"), "tokens=x");
        assert!(has_param("a&token", "token"));
        assert!(!has_param("a=token", "token"));
    }

    proptest! {
        // Whatever arrives, parsing never panics and anything it returns is a plausible
        // token that really occurs in the input.
        #[test]
        fn parsing_arbitrary_input_never_panics(input in any::<String>()) {
            for found in [bearer(&input), cookie(&input, COOKIE_NAME), query_param(&input, "token")]
                .into_iter()
                .flatten()
            {
                prop_assert!(plausible(found));
                prop_assert!(input.contains(found));
            }
            let rest = without_param(&input, "token");
            prop_assert!(query_param(&rest, "token").is_none());
        }

        // A token put in any of the three places comes back out unchanged.
        #[test]
        fn a_token_round_trips_through_every_carrier(
            token in "[A-Za-z0-9_-]{1,128}",
            other in "[a-z]{1,8}=[a-z0-9]{0,8}",
        ) {
            let header = format!("Bearer {token}");
            prop_assert_eq!(bearer(&header), Some(token.as_str()));
            let header = format!("{other}; {COOKIE_NAME}={token}; {other}");
            prop_assert_eq!(cookie(&header, COOKIE_NAME), Some(token.as_str()));
            let query = format!("{other}&token={token}");
            prop_assert_eq!(query_param(&query, "token"), Some(token.as_str()));
            prop_assert_eq!(without_param(&query, "token"), other.clone());
        }

        // Distinct tokens never share a digest, and comparisons agree with equality.
        #[test]
        fn digests_separate_tokens(a in "[a-z0-9_]{1,40}", b in "[a-z0-9_]{1,40}") {
            prop_assert_eq!(same_hash(&digest(&a).hash, &digest(&b).hash), a == b);
        }
    }
}
