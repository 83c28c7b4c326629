//! `GET /v1/sessions` and the `GET /` page: what the server holds, newest first.

use sitar_client::{NewSession, SessionState};
use sitar_tests::*;

#[test]
fn the_list_and_the_page_show_the_newest_sessions_with_their_links() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 20.0, 2));
    let client = client(&server);
    let base = server.url();

    let (status, ct, page) = raw("GET", &format!("{base}/"), None, b"", &[]);
    assert_eq!(status, 200);
    assert!(ct.starts_with("text/html"), "{ct}");
    assert!(page.contains("No sessions yet"), "{page}");
    let (status, _, body) = raw("GET", &format!("{base}/v1/sessions"), None, b"", &[]);
    assert_eq!(status, 200);
    assert_eq!(body, r#"{"sessions":[]}"#);

    let played = client
        .create_session(&NewSession {
            trials: 2,
            setting: "median".into(),
            playback: "sim".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    let rec = sim_recording(dir.path(), "walk.rec", 3.0, 5);
    client
        .upload_recording(&played, &rec, &mut |_, _| {})
        .unwrap();
    let done = wait_done(&client, &played);
    assert_eq!(done.state, SessionState::Done, "{done:?}");
    let waiting = client
        .create_session(&NewSession {
            trials: 3,
            setting: "mean".into(),
            playback: "upload".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();

    // Newest first, each entry the session's status.
    let (_, ct, body) = raw("GET", &format!("{base}/v1/sessions"), None, b"", &[]);
    assert!(ct.starts_with("application/json"), "{ct}");
    let list: serde_json::Value = serde_json::from_str(&body).unwrap();
    let sessions = list["sessions"].as_array().unwrap();
    let ids: Vec<&str> = sessions.iter().map(|s| s["id"].as_str().unwrap()).collect();
    assert_eq!(ids, [waiting.as_str(), played.as_str()]);
    assert_eq!(sessions[0]["state"], "created");
    assert_eq!(sessions[1]["state"], "done");
    assert_eq!(sessions[1]["results_trials"], 2);
    let (_, _, body) = raw(
        "GET",
        &format!("{base}/v1/sessions?limit=1"),
        None,
        b"",
        &[],
    );
    let list: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(list["sessions"].as_array().unwrap().len(), 1);
    for bad in ["limit=0", "limit=lots", "offset=3"] {
        let (status, ct, body) = raw("GET", &format!("{base}/v1/sessions?{bad}"), None, b"", &[]);
        assert_eq!(error_code(status, &ct, &body, 400), "bad_request", "{bad}");
    }

    // The page: both sessions, a report link only where there are results.
    let (_, _, page) = raw("GET", &format!("{base}/"), None, b"", &[]);
    assert!(page.contains("http-equiv=\"refresh\""));
    let row_of = |id: &str| {
        page.lines()
            .find(|l| l.contains(&format!("<code>{id}</code>")))
            .unwrap_or_else(|| panic!("no row for {id}: {page}"))
            .to_string()
    };
    let played_row = row_of(&played);
    assert!(
        played_row.contains(&format!("href=\"/v1/sessions/{played}/report\"")),
        "{played_row}"
    );
    assert!(played_row.contains("<td>done</td>") && played_row.contains("<td>2/2</td>"));
    let waiting_row = row_of(&waiting);
    assert!(!waiting_row.contains("/report"), "{waiting_row}");
    assert!(waiting_row.contains("<td>created</td>") && waiting_row.contains("<td>0/3</td>"));
    assert!(page.find(&waiting).unwrap() < page.find(&played).unwrap());
    // Creation time, ETA, which phone played which trials; why the devices table is empty.
    assert!(played_row.contains("<td>20"), "{played_row}");
    // Two simulated phones share the two trials: every trial is listed under a phone.
    let played_by = &played_row[played_row.find("played-by").unwrap()..];
    let played_by = &played_by[..played_by.find("</td>").unwrap()];
    assert!(played_by.contains("<code>sim:"), "{played_by}");
    assert!(
        played_by.contains(": 0") && (played_by.contains(": 1") || played_by.contains("0–1")),
        "{played_by}"
    );
    assert!(
        page.contains("id=\"devices-empty\">None: this server plays back on simulated phones"),
        "{page}"
    );
    let (_, headers) = {
        let response = agent().get(&format!("{base}/")).call().unwrap();
        (response.status(), response.headers().clone())
    };
    let csp = headers["content-security-policy"].to_str().unwrap();
    assert!(
        csp.contains("script-src 'self'") && csp.contains("default-src 'none'"),
        "{csp}"
    );
    assert!(headers.get("access-control-allow-origin").is_none());
    // The linked report is there.
    let (status, _, report) = raw(
        "GET",
        &format!("{base}/v1/sessions/{played}/report"),
        None,
        b"",
        &[],
    );
    assert_eq!(status, 200);
    assert!(report.contains("<svg"));
}
