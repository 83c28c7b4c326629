//! A restart in the middle of a job: the session resumes where it was, nothing is lost.

use std::time::{Duration, Instant};

use sitar_client::{NewSession, SessionState};
use sitar_tests::*;

#[test]
fn a_restart_mid_playback_resumes_and_a_missing_recording_fails_with_a_reason() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let recording = sim_recording(dir.path(), "walk.rec", 3.0, 9);
    // 3 s at 6× → 0.5 s per trial, 8 trials ≈ 4 s.
    let server = start(sim_config(&data, 6.0, 1));
    let client = client(&server);
    let new = NewSession {
        trials: 8,
        setting: "trim_mean_30".into(),
        playback: "sim".into(),
        window_frames: None,
        pose_relation: None,
    };
    let id = client.create_session(&new).unwrap();
    let doomed = client.create_session(&new).unwrap();
    client
        .upload_recording(&id, &recording, &mut |_, _| {})
        .unwrap();
    client
        .upload_recording(&doomed, &recording, &mut |_, _| {})
        .unwrap();
    let started = Instant::now();
    loop {
        let s = client.status(&id).unwrap();
        if s.trials_done >= 3 {
            assert_eq!(s.state, SessionState::Playing);
            break;
        }
        assert!(started.elapsed() < Duration::from_secs(30), "{s:?}");
        std::thread::sleep(Duration::from_millis(20));
    }
    server.stop();
    let stopped_at = client.status(&id).err().is_some();
    assert!(stopped_at, "the server is down");
    std::fs::remove_file(data.join("sessions").join(&doomed).join("recording")).unwrap();

    let server = start(sim_config(&data, 6.0, 1));
    let client = client_for(&server);
    let s = client.status(&id).unwrap();
    assert!(
        s.trials_done >= 3 && s.state != SessionState::Failed,
        "{s:?}"
    );
    let status = client
        .wait(
            &id,
            Duration::from_millis(50),
            Duration::from_secs(60),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert_eq!(status.trials_done, 8);
    // Same numbers as an uninterrupted run: the resumed trials continue the playback indices.
    let rec = sitar_sim::Recording::from_bytes(&std::fs::read(&recording).unwrap()).unwrap();
    assert_same_results(
        &client.results_csv(&id).unwrap(),
        &direct_csv(&sitar_sim::simulate_trials(&rec, 8), "trim_mean_30"),
    );
    let doc: serde_json::Value = serde_json::from_str(
        &raw(
            "GET",
            &format!("{}/v1/sessions/{id}", server.url()),
            None,
            b"",
            &[],
        )
        .2,
    )
    .unwrap();
    let jobs: Vec<_> = doc["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["state"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(jobs, vec!["interrupted", "done"]);

    let lost = client.status(&doomed).unwrap();
    assert_eq!(lost.state, SessionState::Failed);
    let reason = lost.error.unwrap_or_default();
    assert!(reason.contains("recording is missing"), "{reason}");
}

fn client_for(server: &sitar_server::ServerHandle) -> sitar_client::Client {
    client(server)
}
