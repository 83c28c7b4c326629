//! The scene of a simulated session from the running server: `GET /v1/sessions/{id}/scene.glb`
//! has one node per element of the phone's render plan and markers, and passes the Khronos
//! glTF validator (npm `gltf-validator`, pinned in `tools/npm`).

use std::path::PathBuf;

use sitar_client::{NewSession, SessionState};
use sitar_core::{DisplayRotation, SessionConfig};
use sitar_tests::*;

fn get_bytes(url: &str) -> (u16, String, Vec<u8>) {
    let mut response = agent().get(url).call().expect("request goes through");
    let ct = response
        .headers()
        .get("content-type")
        .and_then(|v| v.to_str().ok())
        .unwrap_or_default()
        .to_string();
    let status = response.status().as_u16();
    let body = response
        .body_mut()
        .with_config()
        .limit(64 << 20)
        .read_to_vec()
        .unwrap();
    (status, ct, body)
}

/// The children count of the root's group `name` in a GLB's JSON.
fn group_len(doc: &serde_json::Value, name: &str) -> usize {
    let nodes = doc["nodes"].as_array().unwrap();
    let root = &nodes[doc["scenes"][0]["nodes"][0].as_u64().unwrap() as usize];
    root["children"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| &nodes[i.as_u64().unwrap() as usize])
        .find(|n| n["name"] == name)
        .map(|g| g["children"].as_array().map_or(0, Vec::len))
        .unwrap_or_else(|| panic!("no group {name}"))
}

#[test]
fn the_scene_of_a_sim_session_matches_the_phones_render_plan_and_validates() {
    let dir = tempfile::tempdir().unwrap();
    let recording = sim_recording(dir.path(), "walk.rec", 10.0, 42);
    let server = start(sim_config(&dir.path().join("data"), 40.0, 2));
    let client = client(&server);
    let id = client
        .create_session(&NewSession {
            trials: 4,
            setting: "trim_mean_30".into(),
            playback: "sim".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    let url = format!("{}/v1/sessions/{id}/scene.glb", server.url());
    // Before the recording there is no scene: a JSON error, not a broken file.
    let (status, ct, _) = get_bytes(&url);
    assert_eq!((status, ct.as_str()), (409, "application/json"));
    client
        .upload_recording(&id, &recording, &mut |_, _| {})
        .unwrap();
    assert_eq!(wait_done(&client, &id).state, SessionState::Done);

    let (status, ct, glb) = get_bytes(&url);
    assert_eq!((status, ct.as_str()), (200, "model/gltf-binary"));
    // The phone's own session of the same walk, with the same results.
    let rec = sitar_sim::Recording::from_bytes(&std::fs::read(&recording).unwrap()).unwrap();
    let mut phone = rec
        .phone_session(
            SessionConfig::from_json(r#"{"convention":"arcore"}"#).unwrap(),
            DisplayRotation::Deg90,
        )
        .unwrap();
    phone
        .load_results(&client.results_json(&id).unwrap())
        .unwrap();
    let plan = phone.render_plan();
    let markers = phone.markers().unwrap();
    assert!(!markers.is_empty());
    let parsed = gltf::binary::Glb::from_slice(&glb).unwrap();
    let doc: serde_json::Value = serde_json::from_slice(&parsed.json).unwrap();
    assert_eq!(group_len(&doc, "trajectory"), plan.segments.len());
    assert_eq!(group_len(&doc, "joints"), plan.joints.len());
    assert_eq!(group_len(&doc, "frustums"), plan.frustums.len());
    assert_eq!(group_len(&doc, "markers"), markers.len());
    // A second request reads the kept phone session: the same bytes.
    assert_eq!(get_bytes(&url).2, glb);

    let tools = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tools/npm");
    if !tools.join("node_modules/gltf-validator").exists() {
        println!(
            "SKIPPED the Khronos glTF validator: run `npm ci --prefix tools/npm` (.ci/run does)"
        );
        return;
    }
    let file = dir.path().join("scene.glb");
    std::fs::write(&file, &glb).unwrap();
    let out = std::process::Command::new("node")
        .arg(tools.join("validate-gltf.mjs"))
        .arg(&file)
        .output()
        .expect("node runs");
    let reports: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        reports[0]["issues"]["numErrors"], 0,
        "{}",
        reports[0]["issues"]
    );
    assert!(out.status.success());
}
