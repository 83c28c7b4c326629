//! sitar-core's session config (`SessionConfig::from_json`). An accepted config must be
//! valid, write back to JSON that parses equal, and start a session.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sitar_core::{Session, SessionConfig};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(config) = SessionConfig::from_json(text) else {
        return;
    };
    assert!(config.validate().is_ok());
    assert_eq!(
        SessionConfig::from_json(&config.to_json()).ok(),
        Some(config.clone())
    );
    assert!(Session::try_new(config).is_ok());
});
