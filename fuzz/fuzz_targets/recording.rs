//! sitar-sim's recording reader (`Recording::from_bytes`: magic, version, JSON body). Input
//! without the header gets one, so the fuzzer spends its time on the body. What parses must
//! play a trial and round-trip through `to_bytes`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sitar_sim::{RECORDING_MAGIC, RECORDING_VERSION, Recording, play_trial};

fuzz_target!(|data: &[u8]| {
    let _ = Recording::from_bytes(data);
    let mut bytes = Vec::with_capacity(12 + data.len());
    bytes.extend_from_slice(RECORDING_MAGIC);
    bytes.extend_from_slice(&RECORDING_VERSION.to_le_bytes());
    bytes.extend_from_slice(data);
    let Ok(recording) = Recording::from_bytes(&bytes) else {
        return;
    };
    assert_eq!(play_trial(&recording, 0).len(), recording.frames());
    let _ = recording.scene_json();
    assert_eq!(
        Recording::from_bytes(&recording.to_bytes()).ok(),
        Some(recording)
    );
});
