//! The `Content-Range` parser of `PUT /v1/sessions/{id}/recording`. What it accepts is
//! `bytes START-LAST/TOTAL` with START <= LAST < TOTAL, and writing it back the canonical way
//! parses to the same range.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sitar_server::fuzzing::content_range;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Some((start, last, total)) = content_range(text) {
        assert!(start <= last && last < total, "{text:?}");
        assert!(text.trim().starts_with("bytes "), "{text:?}");
        let canonical = format!("bytes {start}-{last}/{total}");
        assert_eq!(content_range(&canonical), Some((start, last, total)));
    }
});
