//! The `POST /v1/sessions` JSON body → playback kind and estimate settings, with the
//! handler's error texts. A refusal is a 400 whose message stays short whatever the body
//! (it quotes at most short prefixes of the client's input).
#![no_main]

use libfuzzer_sys::fuzz_target;
use sitar_server::fuzzing::session_request;

fuzz_target!(|data: &[u8]| {
    match session_request(data) {
        Ok((_, window_frames, unit)) => {
            assert!((2..=1000).contains(&window_frames), "{window_frames}");
            assert!(matches!(unit, "m" | "deg"), "{unit}");
        }
        Err(sitar_server::Error::BadRequest(message)) => {
            // Two quoted prefixes of 200 bytes (+ "…") and the fixed words around them.
            assert!(
                message.len() <= 1024,
                "{} bytes: {message:.300}",
                message.len()
            );
        }
        Err(other) => panic!("not a 400: {other:?}"),
    }
});
