//! Secrets on the wire: finding a token in an `Authorization` header, a cookie or a query
//! string (what a token is and how it is kept: [`crate::model::token_secret`]). Pure
//! functions: the property tests and the fuzz target call them with arbitrary input, and
//! none of them panics.

pub use crate::model::token_secret::{new_token, plausible};

/// The cookie the HTML pages authenticate with after a `?token=` visit.
pub const COOKIE_NAME: &str = "sitar_token";

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
    use crate::model::token_secret::{digest, same_hash};
    use proptest::prelude::*;

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
