//! One session with 20-frame windows and the rotational estimate, three ways: the backend
//! over loopback (`window_frames: 20, pose_relation: "angle_deg"`), `sitar estimate --delta
//! 20 -r angle_deg` on the same files, and evo's RPE (angle_deg, delta 20 frames, all pairs)
//! aggregated with scipy's `trim_mean(…, 0.3)` (`scripts/golden/make_window_golden.py`).
//! The first two are the same text; both equal the golden numbers to 1e-9.

use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

use sitar_client::{Client, NewSession, SessionOptions, SessionState};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn backend_cli_and_evo_agree_on_20_frame_angle_windows() {
    let golden: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(
            repo().join("rust/server/tests/data/golden_window_20_angle_deg.json"),
        )
        .unwrap(),
    )
    .unwrap();
    let trials: Vec<PathBuf> = golden["trials"]
        .as_array()
        .unwrap()
        .iter()
        .map(|name| {
            repo()
                .join("rust/estimator/tests/data/trials")
                .join(name.as_str().unwrap())
        })
        .collect();
    assert_eq!((golden["delta"].as_u64(), trials.len()), (Some(20), 8));

    // The backend, over loopback.
    let data = tempfile::tempdir().unwrap();
    let mut config = sitar_server::ServerConfig::new(data.path());
    config.playback = sitar_server::PlaybackKind::Upload;
    let server = sitar_server::Server::spawn(config, "127.0.0.1:0".parse().unwrap()).unwrap();
    let admin = std::fs::read_to_string(data.path().join(sitar_server::ADMIN_TOKEN_FILE)).unwrap();
    let client = Client::new(&server.url())
        .unwrap()
        .with_server_token(&admin)
        .unwrap();
    let id = client
        .create_session_with(
            &NewSession {
                trials: 8,
                setting: golden["setting"].as_str().unwrap().into(),
                playback: "upload".into(),
                window_frames: Some(20),
                pose_relation: Some("angle_deg".into()),
            },
            &SessionOptions::default(),
        )
        .unwrap();
    for path in &trials {
        client
            .upload_trial(&id, &std::fs::read_to_string(path).unwrap())
            .unwrap();
    }
    client.start_estimate(&id).unwrap();
    let status = client
        .wait(
            &id,
            Duration::from_millis(20),
            Duration::from_secs(60),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(
        (status.state, status.results_trials),
        (SessionState::Done, 8)
    );
    let served = client.results_json(&id).unwrap();

    // `sitar estimate`, with the backend's degree classes (its defaults are in metres).
    let out = Command::new(env!("CARGO_BIN_EXE_sitar"))
        .args([
            "estimate",
            "--delta",
            "20",
            "-r",
            "angle_deg",
            "--format",
            "json",
        ])
        .args(["--medium", "2", "--high", "4"])
        .args(&trials)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed = String::from_utf8(out.stdout).unwrap();
    assert_eq!(printed.trim_end(), served, "the CLI and the backend differ");

    // evo + scipy.
    let doc: serde_json::Value = serde_json::from_str(&served).unwrap();
    assert_eq!(doc["window_frames"], 20);
    assert_eq!(doc["pose_relation"], "angle_deg");
    assert_eq!(doc["unit"], "deg");
    assert_eq!(doc["trials"], 8);
    let windows = doc["windows"].as_array().unwrap();
    let expected = golden["windows"].as_array().unwrap();
    assert_eq!(windows.len(), expected.len());
    let mut worst: f64 = 0.0;
    for (w, e) in windows.iter().zip(expected) {
        assert_eq!(w["start"].as_i64(), e[0].as_i64(), "{w}");
        assert_eq!(w["pairs"].as_u64(), e[2].as_u64(), "{w}");
        for (key, column) in [("error_deg", 1), ("spread_deg", 3)] {
            let difference = (w[key].as_f64().unwrap() - e[column].as_f64().unwrap()).abs();
            assert!(
                difference <= 1e-9,
                "{key} of window {}: {w} vs {e}",
                w["start"]
            );
            worst = worst.max(difference);
        }
    }
    println!(
        "{} windows agree with evo + scipy; largest difference {worst:.1e}°",
        windows.len()
    );
    server.stop();
}
