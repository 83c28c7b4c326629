//! The scene of a simulated session from the running server: `GET /v1/sessions/{id}/scene.glb`
//! has one node per element of the phone's render plan and markers, and passes the Khronos
//! glTF validator (npm `gltf-validator`, pinned in `tools/npm`). A real recording (uploaded
//! trials) whose phone sent its camera evidence gets surface points and markers where the
//! phone's depth samples were.

use std::path::PathBuf;

use sitar_client::{NewSession, SessionState};
use sitar_core::{DisplayRotation, SessionConfig};
use sitar_tests::*;

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
    let (status, ct, _) = get_bytes(&url, Some(ADMIN_TOKEN));
    assert_eq!((status, ct.as_str()), (409, "application/json"));
    client
        .upload_recording(&id, &recording, &mut |_, _| {})
        .unwrap();
    assert_eq!(wait_done(&client, &id).state, SessionState::Done);
    // Built ahead when the session finished, before anyone asks for it: the report's first
    // load does not pay for rebuilding the walk.
    let built = dir
        .path()
        .join(format!("data/sessions/{id}/phone/source.txt"));
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while !built.exists() {
        assert!(std::time::Instant::now() < deadline, "no scene built ahead");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }

    let (status, ct, glb) = get_bytes(&url, Some(ADMIN_TOKEN));
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
    assert_eq!(get_bytes(&url, Some(ADMIN_TOKEN)).2, glb);

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

#[test]
fn a_real_recording_with_evidence_gets_the_phones_surface_points_and_markers() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 40.0, 2));
    let base = server.url();
    // The user's phone on the demo walk, with images and depth: its evidence.
    let recording = sitar_sim::Recording::demo(10.0, 30.0, 42).unwrap();
    let mut phone = phone_walk_with_evidence(&recording);
    let folder = dir.path().join("phone");
    phone.save(&folder).unwrap();
    // Three trials from outside SLAM runs: the walk itself (the reference), and two whose
    // drift grows along the walk, so its later part is medium and high.
    let gt = recording.walk().ground_truth.clone();
    let app = client_with(&server, APP_TOKEN);
    let id = upload_session(&app, 3);
    for trial in 0..3u32 {
        let mut t = gt.clone();
        let n = t.len() as f64;
        for (i, p) in t.positions.iter_mut().enumerate() {
            let drift = 0.25 * f64::from(trial) * (i as f64 / n).powi(2);
            let phase = i as f64 * 0.37 + f64::from(trial);
            *p += glam::DVec3::new(phase.sin(), (1.3 * phase).cos(), (0.7 * phase).sin()) * drift;
        }
        app.upload_trial(&id, &tum_text(&t)).unwrap();
    }
    assert!(app.upload_evidence(&id, &folder).unwrap().is_some());
    let (status, _, body) = raw(
        "POST",
        &format!("{base}/v1/sessions/{id}/estimate"),
        None,
        b"",
        &[("authorization", &format!("Bearer {APP_TOKEN}"))],
    );
    assert!(matches!(status, 202 | 409), "{status} {body}");
    assert_eq!(wait_done(&app, &id).state, SessionState::Done);

    let (status, _, body) = get_bytes(
        &format!("{base}/v1/sessions/{id}/scene.json"),
        Some(ADMIN_TOKEN),
    );
    assert_eq!(status, 200);
    let scene: serde_json::Value = serde_json::from_slice(&body).unwrap();
    assert!(
        scene["source"]
            .as_str()
            .unwrap()
            .contains("surface distances"),
        "{}",
        scene["source"]
    );
    // One surface point per valid depth sample of the phone, where the phone's was (the
    // reference trial is the walk itself; the depth camera is a centred pinhole).
    let expected: Vec<glam::DVec3> = phone
        .subtrajectories()
        .iter()
        .filter_map(|s| s.depth.sample().map(|d| d.point))
        .collect();
    let got: Vec<f64> = scene["surface"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(expected.len() > 10, "{} depth samples", expected.len());
    assert_eq!(got.len(), 3 * expected.len());
    let mut worst = 0.0f64;
    for (p, q) in got.chunks(3).zip(&expected) {
        worst = worst.max(glam::DVec3::new(p[0], p[1], p[2]).distance(*q));
    }
    assert!(worst < 0.02, "surface points off by up to {worst} m");
    // Markers: sitar-core's selection on those points; each at one of the phone's points.
    phone.load_results(&app.results_json(&id).unwrap()).unwrap();
    let phone_markers = phone.markers().unwrap();
    let markers = scene["markers"].as_array().unwrap();
    assert!(
        !phone_markers.is_empty(),
        "the drifting trials give medium/high spots"
    );
    assert_eq!(markers.len(), phone_markers.len());
    for (m, pm) in markers.iter().zip(&phone_markers) {
        let p: Vec<f64> = m["p"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert!(glam::DVec3::new(p[0], p[1], p[2]).distance(pm.position) < 0.02);
        assert_eq!(m["sub"], pm.subtrajectory);
    }
    println!(
        "real recording with evidence: {} surface points (worst {:.1} mm off), {} markers",
        expected.len(),
        worst * 1000.0,
        markers.len()
    );
    server.stop();
}
