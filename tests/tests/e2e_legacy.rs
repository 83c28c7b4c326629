//! The original Unity app's routes, called as it calls them (multipart form uploads).

use std::time::{Duration, Instant};

use sitar_tests::*;

#[test]
fn unity_app_flow_over_legacy_routes() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let mut config = sim_config(&data, 30.0, 1);
    config.default_trials = 4;
    let server = start(config);
    let base = server.url();

    // Before any session: no results.
    let (status, ct, body) = raw("GET", &format!("{base}/results.csv"), None, b"", &[]);
    assert_eq!(error_code(status, &ct, &body, 404), "not_found");
    // Timestamps before a recording: 409.
    let (ct_ts, body_ts) = multipart("timestamps", "timestamps.txt", b"1 0 0 0 0 0 0 1\n");
    let (status, ct, body) = raw(
        "POST",
        &format!("{base}/timestamps"),
        Some(&ct_ts),
        &body_ts,
        &[],
    );
    assert_eq!(error_code(status, &ct, &body, 409), "conflict");

    let rec = sitar_sim::Recording::demo(3.0, 30.0, 5).unwrap();
    let (ct_rec, body_rec) = multipart("recording", "recording.mp4", &rec.to_bytes());
    let (status, _, body) = raw(
        "POST",
        &format!("{base}/recording"),
        Some(&ct_rec),
        &body_rec,
        &[],
    );
    assert_eq!(status, 200, "{body}");
    let id = serde_json::from_str::<serde_json::Value>(&body).unwrap()["id"]
        .as_str()
        .unwrap()
        .to_string();

    let timestamps = tum_text(&rec.walk().ground_truth);
    let (ct_ts, body_ts) = multipart("timestamps", "timestamps.txt", timestamps.as_bytes());
    let (status, _, body) = raw(
        "POST",
        &format!("{base}/timestamps"),
        Some(&ct_ts),
        &body_ts,
        &[],
    );
    assert_eq!(status, 200, "{body}");
    assert_eq!(
        std::fs::read_to_string(data.join("sessions").join(&id).join("timestamps.txt")).unwrap(),
        timestamps
    );

    // The app polls /results.csv until the session is done.
    let started = Instant::now();
    let csv = loop {
        let (status, ct, body) = raw("GET", &format!("{base}/results.csv"), None, b"", &[]);
        if status == 200 {
            assert!(ct.starts_with("text/csv"));
            break body;
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "no results: {status} {body}"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    let expected = direct_csv(&sitar_sim::simulate_trials(&rec, 4), "trim_mean_30");
    assert_same_results(&csv, &expected);
    assert_same_results(&client(&server).results_csv(&id).unwrap(), &csv);
}
