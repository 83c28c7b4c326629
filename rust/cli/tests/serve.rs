//! `sitar serve` as an operator runs it: the real binary on a free loopback port, with one
//! log line per request on stderr.

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
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run sitar serve");
    let (tx, lines) = channel();
    let stderr = child.stderr.take().unwrap();
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

    let client = sitar_client::Client::new(url).unwrap();
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

    let created = serving.wait_for("POST /v1/sessions → 201");
    assert!(created.starts_with("sitar serve: info: "), "{created}");
    serving.wait_for("POST /v1/sessions → 400");
    serving.wait_for("GET /v1/sessions/s0000000000000000 → 404");
    // Successful reads stay quiet: phones poll their status all the time.
    client.status(&id).unwrap();
    serving.wait_for("GET /v1/sessions/s0000000000000000 → 404");
    assert!(
        !serving.seen.iter().any(|l| l.contains("GET /healthz")),
        "{:#?}",
        serving.seen
    );
}
