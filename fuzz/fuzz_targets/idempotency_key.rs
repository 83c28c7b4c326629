//! The `Idempotency-Key` check of `POST /v1/sessions` on any header value bytes: a key it
//! accepts is the header's text, 1 to 128 bytes; a refusal is a 400.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sitar_server::fuzzing::idempotency_key;

fuzz_target!(|data: &[u8]| {
    match idempotency_key(data) {
        Ok(Some(key)) => {
            assert!((1..=128).contains(&key.len()), "{key:?}");
            assert_eq!(key.as_bytes(), data);
        }
        Ok(None) => {}
        Err(e) => assert!(matches!(e, sitar_server::Error::BadRequest(_)), "{e:?}"),
    }
});
