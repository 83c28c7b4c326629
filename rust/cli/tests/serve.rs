//! `sitar serve` as an operator runs it: the real binary on a free loopback port, with one
//! time-stamped log line per request on stderr naming the token, the admin token printed
//! once, `sitar token` working while it runs, and SIGTERM stopping it cleanly.

mod support;

use std::process::Command;
use std::time::{Duration, Instant};

use support::process::Serving;

#[test]
fn serve_listens_and_logs_every_request_that_changes_or_fails() {
    let data = tempfile::tempdir().unwrap();
    let mut serving = Serving::start(data.path(), &["--playback", "sim"]);
    let url = serving.url.clone();
    let url = url.as_str();
    assert!(data.path().join("sitar.db").is_file());

    // The new data directory's admin token: in the file (0600) and in the URL printed once.
    let printed = serving.wait_for("/?token=", Duration::from_secs(30));
    let admin = std::fs::read_to_string(data.path().join("admin.token")).unwrap();
    let admin = admin.trim();
    assert!(
        printed.ends_with(&format!("{url}/?token={admin}")),
        "{printed}"
    );
    // An app token made while the server runs, by the real binary: the only stdout line.
    let sitar = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_sitar"))
            .args(args)
            .arg("--data")
            .arg(data.path())
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    let app = sitar(&["token", "create", "--role", "app", "--name", "lab-phone"]);
    assert_eq!(app.lines().count(), 1, "{app}");
    let app = app.trim();
    let listed = sitar(&["token", "list"]);
    assert!(
        listed.contains("lab-phone") && listed.contains("admin"),
        "{listed}"
    );
    assert!(!listed.contains(app) && !listed.contains(admin), "{listed}");

    let client = sitar_client::Client::new(url)
        .unwrap()
        .with_server_token(app)
        .unwrap();
    client.health().unwrap();
    let id = client
        .create_session(&sitar_client::NewSession {
            trials: 3,
            setting: "median".into(),
            playback: "upload".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    let err = client
        .create_session(&sitar_client::NewSession {
            trials: 3,
            setting: "median".into(),
            playback: "floppy".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap_err();
    assert_eq!(err.status(), Some(400), "{err}");
    assert_eq!(
        client.status("s0000000000000000").unwrap_err().status(),
        Some(404)
    );

    let created = serving.wait_for(
        "POST /v1/sessions [lab-phone] → 201",
        Duration::from_secs(30),
    );
    // `2026-12-02T03:04:05.123Z INFO …`: an RFC 3339 stamp in UTC, then the level.
    let (stamp, rest) = created.split_once(' ').unwrap();
    assert!(
        stamp.len() == 24 && stamp.ends_with('Z') && stamp.as_bytes()[10] == b'T',
        "{created}"
    );
    assert!(rest.starts_with("INFO "), "{created}");
    serving.wait_for(
        "POST /v1/sessions [lab-phone] → 400",
        Duration::from_secs(30),
    );
    serving.wait_for(
        "GET /v1/sessions/s0000000000000000 [lab-phone] → 404",
        Duration::from_secs(30),
    );
    // Successful reads stay quiet: phones poll their status all the time.
    client.status(&id).unwrap();
    assert!(
        !serving.seen.iter().any(|l| l.contains("GET /healthz")),
        "{:#?}",
        serving.seen
    );
    // Revoked while it runs: the next request is refused.
    sitar(&["token", "revoke", "lab-phone"]);
    assert_eq!(client.status(&id).unwrap_err().status(), Some(401));
    serving.wait_for("→ 401", Duration::from_secs(30));
    // No token ever reaches the log.
    assert!(
        !serving
            .seen
            .iter()
            .any(|l| !l.contains("/?token=") && (l.contains(app) || l.contains(admin))),
        "{:#?}",
        serving.seen
    );

    // SIGTERM: a clean stop, exit status 0.
    let pid = serving.child.id().to_string();
    let killed = Command::new("kill").args(["-TERM", &pid]).status().unwrap();
    assert!(killed.success());
    serving.wait_for("SIGTERM: stopping", Duration::from_secs(30));
    let deadline = Instant::now() + Duration::from_secs(20);
    let status = loop {
        if let Some(status) = serving.child.try_wait().unwrap() {
            break status;
        }
        assert!(
            Instant::now() < deadline,
            "still running 20 s after SIGTERM"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(status.success(), "{status:?}");
}
