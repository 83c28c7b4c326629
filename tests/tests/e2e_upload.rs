//! The `upload` playback: trials from an outside SLAM run, estimate on request.

use std::time::Duration;

use sitar_client::{Error, NewSession, SessionState};
use sitar_tests::*;

#[test]
fn uploaded_trials_are_estimated_exactly_and_never_duplicated() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 10.0, 1));
    let client = client(&server);
    let id = client
        .create_session(&NewSession {
            trials: 5,
            setting: "median".into(),
            playback: "upload".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    let rec = sitar_sim::Recording::demo(4.0, 30.0, 11).unwrap();
    let trials = sitar_sim::simulate_trials(&rec, 5);

    // Estimate before 2 trials: 409 with a reason.
    let err = client.start_estimate(&id).unwrap_err();
    assert_eq!(err.status(), Some(409), "{err}");
    client.upload_trial(&id, &tum_text(&trials[0])).unwrap();
    assert!(matches!(
        client.start_estimate(&id),
        Err(Error::Server { status: 409, .. })
    ));

    // Garbage TUM: 422 naming the line; nothing stored.
    let err = client
        .upload_trial(&id, "1 2 3\nhello world\n")
        .unwrap_err();
    match &err {
        Error::Server {
            status: 422,
            message,
            ..
        } => assert!(message.contains("trial:1:"), "{message}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(client.status(&id).unwrap().trials_done, 1);

    // The same idempotency key twice (a retry): one trial.
    let url = format!("{}/v1/sessions/{id}/trials", server.url());
    let text = tum_text(&trials[1]);
    let key = [("Idempotency-Key", "trial-1")];
    let (s1, _, b1) = raw("POST", &url, Some("text/plain"), text.as_bytes(), &key);
    let (s2, _, b2) = raw("POST", &url, Some("text/plain"), text.as_bytes(), &key);
    // The retry gets the first answer again (same status, same trial index).
    assert_eq!((s1, s2), (201, 201));
    assert_eq!(b1, b2);
    assert_eq!(client.status(&id).unwrap().trials_done, 2);

    for t in &trials[2..] {
        client.upload_trial(&id, &tum_text(t)).unwrap();
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
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert_eq!((status.trials_done, status.results_trials), (5, 5));
    assert_same_results(
        &client.results_csv(&id).unwrap(),
        &direct_csv(&trials, "median"),
    );
    let json: serde_json::Value = serde_json::from_str(&client.results_json(&id).unwrap()).unwrap();
    assert_eq!(json["setting"], "median");

    // A finished session takes no more trials.
    assert_eq!(
        client
            .upload_trial(&id, &tum_text(&trials[0]))
            .unwrap_err()
            .status(),
        Some(409)
    );
}
