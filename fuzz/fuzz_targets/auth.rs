//! The token and cookie parsing of every request: `Authorization: Bearer`, the `Cookie`
//! header, `?token=` and the redirect that drops it. Whatever arrives, what comes out is a
//! plausible token found verbatim in the input, and the query without the token has none.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sitar_server::fuzzing::{
    COOKIE_NAME, bearer, cookie, has_param, plausible, query_param, without_param,
};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for found in [
        bearer(text),
        cookie(text, COOKIE_NAME),
        query_param(text, "token"),
    ]
    .into_iter()
    .flatten()
    {
        assert!(plausible(found), "{found:?}");
        assert!(text.contains(found));
    }
    if query_param(text, "token").is_some() {
        assert!(has_param(text, "token"));
    }
    let rest = without_param(text, "token");
    assert!(!has_param(&rest, "token"), "{rest:?}");
    assert!(rest.len() <= text.len());
});
