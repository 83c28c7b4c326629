//! `DELETE /v1/sessions/{id}`: whole sessions go, with their files; a playing session's
//! playback is stopped first.

use std::path::Path;
use std::time::Duration;

use sitar_client::{NewSession, SessionState};
use sitar_tests::*;

fn session_dir(data: &Path, id: &str) -> std::path::PathBuf {
    data.join("sessions").join(id)
}

#[test]
fn finished_waiting_and_playing_sessions_are_deleted_whole() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    // 5× real time: a playback lasts long enough (about 1 s) to be caught in flight.
    let server = start(sim_config(&data, 5.0, 2));
    let client = client(&server);
    let rec = sim_recording(dir.path(), "walk.rec", 3.0, 5);
    let sim = |trials| NewSession {
        trials,
        setting: "median".into(),
        playback: "sim".into(),
        window_frames: None,
        pose_relation: None,
    };

    // A playing sim session: its playback stops, then it goes whole.
    let playing = client.create_session(&sim(40)).unwrap();
    client
        .upload_recording(&playing, &rec, &mut |_, _| {})
        .unwrap();
    client.delete_session(&playing).unwrap();
    assert_eq!(client.status(&playing).unwrap_err().status(), Some(404));
    assert!(!session_dir(&data, &playing).exists());

    // A finished one goes with its results.
    let played = client.create_session(&sim(3)).unwrap();
    client
        .upload_recording(&played, &rec, &mut |_, _| {})
        .unwrap();
    let status = wait_done(&client, &played);
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert!(session_dir(&data, &played).join("results.csv").is_file());
    client.delete_session(&played).unwrap();
    assert_eq!(client.status(&played).unwrap_err().status(), Some(404));
    assert_eq!(client.results_csv(&played).unwrap_err().status(), Some(404));
    assert!(!session_dir(&data, &played).exists());
    // Deleted means gone: a second delete is a 404, like any unknown id.
    assert_eq!(
        client.delete_session(&played).unwrap_err().status(),
        Some(404)
    );

    // An upload session waiting for trials, with a trial and a recording.
    let waiting = client
        .create_session(&NewSession {
            trials: 4,
            setting: "median".into(),
            playback: "upload".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    let trial = sitar_sim::simulate_trials(&sitar_sim::Recording::demo(3.0, 30.0, 5).unwrap(), 1);
    client.upload_trial(&waiting, &tum_text(&trial[0])).unwrap();
    let (status, _, _) = raw(
        "PUT",
        &format!("{}/v1/sessions/{waiting}/recording", server.url()),
        Some("application/octet-stream"),
        b"0123456789",
        &[],
    );
    assert_eq!(status, 202);
    assert!(session_dir(&data, &waiting).join("trials").is_dir());
    client.delete_session(&waiting).unwrap();
    assert!(!session_dir(&data, &waiting).exists());
    assert_eq!(
        client
            .upload_trial(&waiting, &tum_text(&trial[0]))
            .unwrap_err()
            .status(),
        Some(404)
    );

    // Path-like and unknown ids are plain 404s; nothing outside the data directory moves.
    for id in ["..%2F..%2Fx", "s0000000000000000"] {
        let (status, ct, body) = raw(
            "DELETE",
            &format!("{}/v1/sessions/{id}", server.url()),
            None,
            b"",
            &[],
        );
        assert_eq!(error_code(status, &ct, &body, 404), "not_found", "{id}");
    }
    assert!(data.join("sitar.db").is_file());
    // Nothing of the deleted sessions is left, in sessions/ or in tmp/.
    let left: Vec<_> = tree(&data)
        .into_iter()
        .filter(|p| p.starts_with("sessions") || p.starts_with("tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");

    // The server goes on: a new session plays to the end.
    let next = client
        .create_session(&NewSession {
            trials: 2,
            setting: "median".into(),
            playback: "sim".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    client
        .upload_recording(&next, &rec, &mut |_, _| {})
        .unwrap();
    let status = wait_done(&client, &next);
    assert_eq!(status.state, SessionState::Done, "{status:?}");
}

#[test]
fn past_the_retention_sessions_go_by_themselves_but_never_in_flight() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    // 2× real time, one phone: a 3 s recording plays for about 1.5 s per trial, so two
    // trials play well past a retention of 1 s.
    let mut config = sim_config(&data, 2.0, 1);
    config.retention = Some(Duration::from_secs(1));
    config.retention_sweep = Duration::from_millis(50);
    let server = start(config);
    let client = client(&server);
    let rec = sim_recording(dir.path(), "walk.rec", 3.0, 5);
    let new = |trials: u32, playback: &str| {
        client
            .create_session(&NewSession {
                trials,
                setting: "median".into(),
                playback: playback.into(),
                window_frames: None,
                pose_relation: None,
            })
            .unwrap()
    };
    let gone = |id: &str| {
        let deadline = std::time::Instant::now() + Duration::from_secs(60);
        loop {
            match client.status(id) {
                Ok(s) => assert_ne!(s.state, SessionState::Failed, "{s:?}"),
                Err(e) if e.status() == Some(404) => break,
                Err(e) => panic!("{e}"),
            }
            assert!(std::time::Instant::now() < deadline, "{id} never swept");
            std::thread::sleep(Duration::from_millis(20));
        }
        assert!(!session_dir(&data, id).exists(), "{id}");
    };

    let abandoned = new(3, "upload");
    let playing = new(2, "sim");
    client
        .upload_recording(&playing, &rec, &mut |_, _| {})
        .unwrap();
    // Abandoned (created, never uploaded): gone once a second old.
    gone(&abandoned);
    // In flight, although created as long ago: still there, still playing.
    let status = client.status(&playing).unwrap();
    assert_eq!(status.state, SessionState::Playing, "{status:?}");
    assert!(session_dir(&data, &playing).join("recording").is_file());
    // Done, then a second later, gone too.
    gone(&playing);
}
