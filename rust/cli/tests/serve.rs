//! `sitar serve` as an operator runs it: the real binary on a free loopback port, with one
//! time-stamped log line per request on stderr naming the token, the admin token printed
//! once, `sitar token` working while it runs, and SIGTERM stopping it cleanly.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

struct Serving {
    child: Child,
    lines: Receiver<String>,
    seen: Vec<String>,
}

impl Serving {
    /// Waits for a stderr line containing `needle`; panics with what was seen after 30 s.
    fn wait_for(&mut self, needle: &str) -> String {
        let deadline = Instant::now() + Duration::from_secs(30);
        if let Some(line) = self.seen.iter().find(|l| l.contains(needle)) {
            return line.clone();
        }
        while let Some(left) = deadline.checked_duration_since(Instant::now()) {
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    self.seen.push(line.clone());
                    if line.contains(needle) {
                        return line;
                    }
                }
                Err(_) => break,
            }
        }
        panic!("no line with {needle:?} in {:#?}", self.seen);
    }
}

impl Drop for Serving {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[test]
fn serve_listens_and_logs_every_request_that_changes_or_fails() {
    let data = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_sitar"))
        .args([
            "serve",
            "--addr",
            "127.0.0.1:0",
            "--playback",
            "sim",
            "--data",
        ])
        .arg(data.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run sitar serve");
    // stdout and stderr in one stream of lines.
    let (tx, lines) = channel();
    let stderr = child.stderr.take().unwrap();
    let stdout = child.stdout.take().unwrap();
    let tx_out = tx.clone();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx_out.send(line).is_err() {
                return;
            }
        }
    });
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                return;
            }
        }
    });
    let mut serving = Serving {
        child,
        lines,
        seen: Vec::new(),
    };
    let listening = serving.wait_for("listening on http://");
    let url = &listening[listening.find("http://").unwrap()..];
    assert!(data.path().join("sitar.db").is_file());

    // The new data directory's admin token: in the file (0600) and in the URL printed once.
    let printed = serving.wait_for("/?token=");
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

    let created = serving.wait_for("POST /v1/sessions [lab-phone] → 201");
    // `2026-12-02T03:04:05.123Z INFO …`: an RFC 3339 stamp in UTC, then the level.
    let (stamp, rest) = created.split_once(' ').unwrap();
    assert!(
        stamp.len() == 24 && stamp.ends_with('Z') && stamp.as_bytes()[10] == b'T',
        "{created}"
    );
    assert!(rest.starts_with("INFO "), "{created}");
    serving.wait_for("POST /v1/sessions [lab-phone] → 400");
    serving.wait_for("GET /v1/sessions/s0000000000000000 [lab-phone] → 404");
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
    serving.wait_for("→ 401");
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
    serving.wait_for("SIGTERM: stopping");
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
