//! Every bad input gets a JSON 4xx, nothing lands outside the data directory, and the server keeps serving.

use sitar_tests::*;

#[test]
fn bad_inputs_are_json_4xx_and_write_nothing_outside_the_data_dir() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let mut config = sim_config(&data, 50.0, 1);
    config.max_recording_bytes = 10_000;
    config.max_trajectory_bytes = 2_000;
    let server = start(config);
    let base = server.url();
    let post = |path: &str, ct: Option<&str>, body: &[u8]| {
        raw("POST", &format!("{base}{path}"), ct, body, &[])
    };
    let expect = |(s, ct, b): (u16, String, String), status: u16, code: &str| {
        assert_eq!(error_code(s, &ct, &b, status), code, "{b}");
        b
    };

    // Session creation: content type, JSON, fields.
    expect(
        post("/v1/sessions", Some("text/plain"), b"{}"),
        415,
        "unsupported_media_type",
    );
    // Every key is optional: no body, or `{}` unlabelled or labelled as curl does, is a
    // session with the server's defaults.
    for (ct, body) in [
        (None, &b""[..]),
        (Some("application/json"), b""),
        (None, b"{}"),
        (Some("application/x-www-form-urlencoded"), b"{}"),
        (Some("application/json"), b" {} "),
    ] {
        let (s, _, b) = post("/v1/sessions", ct, body);
        assert_eq!(s, 201, "{ct:?} {body:?}: {b}");
        let created: serde_json::Value = serde_json::from_str(&b).unwrap();
        let status = client(&server)
            .status(created["id"].as_str().unwrap())
            .unwrap();
        assert_eq!(
            status.trials_total,
            sitar_server::ServerConfig::new("").default_trials,
            "{b}"
        );
    }
    expect(
        post("/v1/sessions", Some("application/json"), b"{not json"),
        400,
        "bad_request",
    );
    let b = expect(
        post(
            "/v1/sessions",
            Some("application/json"),
            br#"{"trials":3,"playback":"sim","colour":1}"#,
        ),
        400,
        "bad_request",
    );
    assert!(b.contains("colour"), "{b}");
    let b = expect(
        post(
            "/v1/sessions",
            Some("application/json"),
            br#"{"trials":"3","playback":"sim"}"#,
        ),
        400,
        "bad_request",
    );
    assert!(b.contains("trials") || b.contains("string"), "{b}");
    expect(
        post(
            "/v1/sessions",
            Some("application/json"),
            br#"{"trials":0,"playback":"sim"}"#,
        ),
        400,
        "bad_request",
    );
    let b = expect(
        post(
            "/v1/sessions",
            Some("application/json"),
            br#"{"trials":3,"playback":"ftp"}"#,
        ),
        400,
        "bad_request",
    );
    assert!(b.contains("ftp"));
    let b = expect(
        post(
            "/v1/sessions",
            Some("application/json"),
            br#"{"trials":3,"playback":"sim","setting":"trim_mean_33"}"#,
        ),
        400,
        "bad_request",
    );
    assert!(b.contains("trim_mean_33"));

    // Unknown sessions, including path-like ids.
    for id in ["s0000000000000000", "..%2F..%2Fx", "%2e%2e", "nope"] {
        let (s, ct, b) = raw("GET", &format!("{base}/v1/sessions/{id}"), None, b"", &[]);
        expect((s, ct, b), 404, "not_found");
        let (s, ct, b) = raw(
            "PUT",
            &format!("{base}/v1/sessions/{id}/recording"),
            Some("application/octet-stream"),
            b"abc",
            &[],
        );
        expect((s, ct, b), 404, "not_found");
    }
    expect(
        raw("GET", &format!("{base}/no/such/route"), None, b"", &[]),
        404,
        "not_found",
    );
    expect(
        raw(
            "PUT",
            &format!("{base}/healthz"),
            Some("text/plain"),
            b"",
            &[],
        ),
        405,
        "method_not_allowed",
    );

    // A real session to abuse.
    let client = client(&server);
    let sim = sitar_client::NewSession {
        trials: 3,
        setting: "mean".into(),
        playback: "sim".into(),
        window_frames: None,
        pose_relation: None,
    };
    let id = client.create_session(&sim).unwrap();
    let rec_url = format!("{base}/v1/sessions/{id}/recording");
    let (ct_mp, body_mp) = multipart("recording", "../../x", b"data");
    expect(
        raw("PUT", &rec_url, Some(&ct_mp), &body_mp, &[]),
        415,
        "unsupported_media_type",
    );
    expect(
        raw(
            "PUT",
            &rec_url,
            Some("application/octet-stream"),
            &vec![1u8; 10_001],
            &[],
        ),
        413,
        "too_large",
    );
    expect(
        raw("PUT", &rec_url, Some("application/octet-stream"), b"", &[]),
        400,
        "bad_request",
    );
    // Not a sim recording: refused at upload with one clear message, the session still
    // waiting for a recording.
    let (s, _, body) = raw(
        "PUT",
        &rec_url,
        Some("application/octet-stream"),
        b"definitely not a recording",
        &[],
    );
    assert_eq!(s, 422, "{body}");
    let message = serde_json::from_str::<serde_json::Value>(&body).unwrap()["error"]["message"]
        .as_str()
        .unwrap()
        .to_owned();
    assert_eq!(
        message.matches("not a sitar-sim recording").count(),
        1,
        "{message}"
    );
    assert!(message.contains("\"SITARSIM\" header"), "{message}");
    assert_eq!(
        client.status(&id).unwrap().state,
        sitar_client::SessionState::Created
    );
    expect(
        post(&format!("/v1/sessions/{id}/estimate"), None, b""),
        409,
        "conflict",
    );
    expect(
        raw(
            "GET",
            &format!("{base}/v1/sessions/{id}/results.csv"),
            None,
            b"",
            &[],
        ),
        409,
        "conflict",
    );

    // Trials: wrong playback, content type, garbage, oversize.
    let up = client
        .create_session(&sitar_client::NewSession {
            trials: 3,
            setting: "mean".into(),
            playback: "upload".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    let trials_url = format!("/v1/sessions/{up}/trials");
    expect(
        post(
            &format!("/v1/sessions/{id}/trials"),
            Some("text/plain"),
            b"1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n",
        ),
        409,
        "conflict",
    );
    expect(
        post(&trials_url, Some("application/json"), b"{}"),
        415,
        "unsupported_media_type",
    );
    // curl's default label for a raw body is read as the raw TUM it is.
    expect(
        post(
            &trials_url,
            Some("application/x-www-form-urlencoded"),
            b"1 0 0 0 0 0 0 1\n2 0 0 nan 0 0 0 1\n",
        ),
        422,
        "invalid_content",
    );
    let b = expect(
        post(
            &trials_url,
            Some("text/plain"),
            b"1 0 0 0 0 0 0 1\n2 0 0 x 0 0 0 1\n",
        ),
        422,
        "invalid_content",
    );
    assert!(b.contains("trial:2:7"), "{b}");
    expect(
        post(&trials_url, Some("text/plain"), &[0xff, 0xfe, 0x00]),
        422,
        "invalid_content",
    );
    expect(
        post(&trials_url, Some("text/plain"), &vec![b'1'; 2_001]),
        413,
        "too_large",
    );
    expect(
        post(&format!("/v1/sessions/{up}/estimate"), None, b""),
        409,
        "conflict",
    );
    // The report before any estimate is an HTML page saying what it waits for (a browser
    // opens it), while the results themselves are still a JSON 409.
    let (status, ct, page) = raw(
        "GET",
        &format!("{base}/v1/sessions/{up}/report"),
        None,
        b"",
        &[],
    );
    assert_eq!(status, 200, "{page}");
    assert!(ct.starts_with("text/html"), "{ct}");
    assert!(page.contains("<b>0 of 3 trials played</b>"), "{page}");
    expect(
        raw(
            "GET",
            &format!("{base}/v1/sessions/{up}/results.json"),
            None,
            b"",
            &[],
        ),
        409,
        "conflict",
    );

    // Legacy multipart: not multipart, malformed, missing field, oversize, path-like file name.
    expect(
        post("/recording", Some("application/json"), b"{}"),
        415,
        "unsupported_media_type",
    );
    expect(
        post(
            "/recording",
            Some("multipart/form-data; boundary=xyz"),
            b"this is not multipart",
        ),
        400,
        "bad_request",
    );
    let (ct_other, body_other) = multipart("video", "a.mp4", b"1234");
    let b = expect(
        post("/recording", Some(&ct_other), &body_other),
        400,
        "bad_request",
    );
    assert!(b.contains("recording"));
    let (ct_big, body_big) = multipart("recording", "big.mp4", &vec![0u8; 20_000]);
    expect(
        post("/recording", Some(&ct_big), &body_big),
        413,
        "too_large",
    );
    let (ct_ts, body_ts) = multipart("timestamps", "../../x", &vec![b'1'; 3_000]);
    expect(
        post("/timestamps", Some(&ct_ts), &body_ts),
        413,
        "too_large",
    );

    // A path-like file name on a good upload never becomes a path.
    let rec = sitar_sim::Recording::demo(2.0, 30.0, 1).unwrap().to_bytes();
    let (ct_ok, body_ok) = multipart("recording", "../../x", &rec[..rec.len().min(9_000)]);
    // The legacy answer waits for the session; this cut-off recording cannot
    // be played, so it ends as a JSON error that says why.
    let (s, ct, body) = post("/recording", Some(&ct_ok), &body_ok);
    assert_eq!(error_code(s, &ct, &body, 500), "playback");
    assert!(body.contains("failed"), "{body}");

    // Still serving; nothing outside the data directory; no upload left in tmp.
    client.health().unwrap();
    drop(server);
    let outside: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(outside, vec![std::ffi::OsString::from("data")]);
    assert!(!dir.path().parent().unwrap().join("x").exists());
    let files = tree(&data);
    assert!(
        files
            .iter()
            .all(|p| !p.to_string_lossy().contains("x.") && p.file_name().unwrap() != "x"),
        "{files:?}"
    );
    assert!(files.iter().all(|p| !p.starts_with("tmp")), "{files:?}");
}
