//! A session's estimate settings end to end: `window_frames` and `pose_relation` are checked
//! when the session is created (a 400 names the key), stored, used by the estimate and
//! recorded in the results, the status and the report.

use sitar_client::{NewSession, SessionOptions, SessionState};
use sitar_estimator::{EstimateOptions, PoseRelation, Setting, Thresholds};
use sitar_tests::*;

#[test]
fn bad_settings_are_400s_that_name_their_key() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 20.0, 1));
    let url = format!("{}/v1/sessions", server.url());
    for (body, key) in [
        (r#"{"window_frames":1}"#, "window_frames"),
        (r#"{"window_frames":1001}"#, "window_frames"),
        (r#"{"window_frames":"20"}"#, "window_frames"),
        (r#"{"window_frames":-3}"#, "window_frames"),
        (r#"{"pose_relation":"angle_rad"}"#, "pose_relation"),
        (r#"{"pose_relation":"sideways"}"#, "pose_relation"),
        (r#"{"pose_relation":7}"#, "pose_relation"),
        (r#"{"trials":"3"}"#, "trials"),
        (r#"{"setting":"trim_mean_33"}"#, "setting"),
        (r#"{"frames":20}"#, "frames"),
    ] {
        let (status, ct, text) = raw("POST", &url, Some("application/json"), body.as_bytes(), &[]);
        assert_eq!(error_code(status, &ct, &text, 400), "bad_request", "{body}");
        let message: serde_json::Value = serde_json::from_str(&text).unwrap();
        let message = message["error"]["message"].as_str().unwrap();
        assert!(message.contains(key), "{body}: {message}");
    }
    // The edges of the range are accepted.
    for frames in [2, 1000] {
        let body = format!(r#"{{"window_frames":{frames},"playback":"upload"}}"#);
        let (status, _, text) = raw("POST", &url, Some("application/json"), body.as_bytes(), &[]);
        assert_eq!(status, 201, "{text}");
    }
}

#[test]
fn an_upload_session_with_20_frame_angle_windows_is_estimated_recorded_and_reported_so() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 20.0, 1));
    let client = client(&server);
    let options = SessionOptions::default();
    let new = NewSession {
        trials: 3,
        setting: "median".into(),
        playback: "upload".into(),
        window_frames: Some(20),
        pose_relation: Some("angle_deg".into()),
    };
    let id = client.create_session_with(&new, &options).unwrap();
    let status_url = format!("{}/v1/sessions/{id}", server.url());
    let status: serde_json::Value =
        serde_json::from_str(&raw("GET", &status_url, None, b"", &[]).2).unwrap();
    assert_eq!(
        (
            &status["window_frames"],
            &status["pose_relation"],
            &status["setting"]
        ),
        (&20.into(), &"angle_deg".into(), &"median".into())
    );
    let typed = client.status(&id).unwrap();
    assert_eq!(typed.window_frames, Some(20));
    assert_eq!(typed.pose_relation.as_deref(), Some("angle_deg"));

    let rec = sitar_sim::Recording::demo(4.0, 30.0, 3).unwrap();
    let trials = sitar_sim::simulate_trials(&rec, 3);
    for (n, trial) in trials.iter().enumerate() {
        client.upload_trial(&id, &tum_text(trial)).unwrap();
        if n >= 1 {
            wait_results(&client, &id, n as u32 + 1);
        }
    }
    client.start_estimate(&id).unwrap();
    assert_eq!(wait_done(&client, &id).state, SessionState::Done);

    let expected = direct_estimate(
        &trials,
        &EstimateOptions {
            setting: Setting::Median,
            delta: 20,
            pose_relation: PoseRelation::RotationAngleDeg,
            ..EstimateOptions::default()
        },
    );
    let text = client.results_json(&id).unwrap();
    assert_same_results(&text, &expected.to_json(Thresholds::DEFAULT_DEG));
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(json["window_frames"], 20);
    assert_eq!(json["pose_relation"], "angle_deg");
    assert_eq!(json["unit"], "deg");
    let windows = json["windows"].as_array().unwrap();
    // 20-frame windows: the last starts 20 frames before the end.
    assert_eq!(windows.len(), trials[0].len() - 20);
    for w in windows {
        let error = w["error_deg"].as_f64().unwrap();
        assert!(w.get("error_m").is_none(), "{w}");
        assert_eq!(w["class"], Thresholds::DEFAULT_DEG.classify(error).name());
    }
    // Legacy CSV: still `start,error`, the error in the results' unit.
    assert_same_results(&client.results_csv(&id).unwrap(), &expected.to_legacy_csv());
    let report = client.report_html(&id).unwrap();
    assert!(report.contains("<th>error (°)</th>"), "{report}");
    assert!(report.contains("<td>20 frames</td>") && report.contains("angle_deg (deg)"));
    assert!(report.contains("medium ≥ 2.0°, high ≥ 4.0°"), "{report}");
    let (_, _, page) = raw("GET", &format!("{}/", server.url()), None, b"", &[]);
    assert!(page.contains("median (20 frames, angle_deg)"), "{page}");
}

#[test]
fn a_sim_session_plays_and_stops_adaptively_on_its_own_windows() {
    let dir = tempfile::tempdir().unwrap();
    let recording = sim_recording(dir.path(), "walk.rec", 4.0, 7);
    let server = start(sim_config(&dir.path().join("data"), 40.0, 1));
    let client = client(&server);
    let options = SessionOptions {
        adaptive_min_trials: Some(4),
        adaptive_k: Some(3),
        ..SessionOptions::default()
    };
    let new = NewSession {
        trials: 30,
        setting: "trim_mean_30".into(),
        playback: "sim".into(),
        window_frames: Some(15),
        pose_relation: None,
    };
    let id = client.create_session_with(&new, &options).unwrap();
    client
        .upload_recording(&id, &recording, &mut |_, _| {})
        .unwrap();
    let status = wait_done(&client, &id);
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert!(status.trials_done < 30, "{status:?}");
    let rec = sitar_sim::Recording::from_bytes(&std::fs::read(&recording).unwrap()).unwrap();
    let expected = direct_estimate(
        &sitar_sim::simulate_trials(&rec, status.trials_done),
        &EstimateOptions {
            delta: 15,
            ..EstimateOptions::default()
        },
    );
    let text = client.results_json(&id).unwrap();
    assert_same_results(&text, &expected.to_json(Thresholds::DEFAULT_M));
    assert!(
        text.contains(r#""window_frames":15,"unit":"m""#),
        "{}",
        &text[..200]
    );
}
