//! The original Unity app's routes, called as it calls them (multipart form uploads).

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

    // The app posts the recording and, once the answer comes, fetches
    // /results.csv: the answer must wait until the session is done.
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
    let answer: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(answer["state"], "done", "{body}");
    let id = answer["id"].as_str().unwrap().to_string();
    let expected = direct_csv(&sitar_sim::simulate_trials(&rec, 4), "trim_mean_30");
    let (status, ct, csv) = raw("GET", &format!("{base}/results.csv"), None, b"", &[]);
    assert_eq!(status, 200, "{csv}");
    assert!(ct.starts_with("text/csv"));
    assert_same_results(&csv, &expected);

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

    assert_same_results(&client(&server).results_csv(&id).unwrap(), &csv);
}
