//! A `sitar serve` process on loopback for the instance tests: its output lines, its URL,
//! killed (SIGKILL) when dropped; and the cluster services of `scripts/cluster-services`.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

/// A running `sitar serve`, its output lines and its URL.
pub struct Serving {
    pub child: Child,
    lines: Receiver<String>,
    pub seen: Vec<String>,
    pub url: String,
}

impl Serving {
    /// Starts `sitar serve --playback sim` on a free port with `extra` arguments.
    pub fn start(data: &Path, extra: &[&str]) -> Serving {
        let mut child = Command::new(env!("CARGO_BIN_EXE_sitar"))
            .args([
                "serve",
                "--addr",
                "127.0.0.1:0",
                "--playback",
                "sim",
                "--data",
            ])
            .arg(data)
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run sitar serve");
        let (tx, lines) = channel();
        let out = child.stdout.take().unwrap();
        let err = child.stderr.take().unwrap();
        let tx_out = tx.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                if tx_out.send(line).is_err() {
                    return;
                }
            }
        });
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    return;
                }
            }
        });
        let mut serving = Serving {
            child,
            lines,
            seen: Vec::new(),
            url: String::new(),
        };
        let listening = serving.wait_for("listening on http://", Duration::from_secs(60));
        serving.url = listening[listening.find("http://").unwrap()..].to_string();
        serving
    }

    /// Takes the output lines printed so far.
    pub fn drain(&mut self) {
        while let Ok(line) = self.lines.try_recv() {
            self.seen.push(line);
        }
    }

    /// Waits up to `limit` for an output line containing `needle`; panics with what was
    /// seen.
    pub fn wait_for(&mut self, needle: &str, limit: Duration) -> String {
        if let Some(line) = self.seen.iter().find(|l| l.contains(needle)) {
            return line.clone();
        }
        let deadline = Instant::now() + limit;
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
        panic!("no line with {needle:?} in {limit:?}: {:#?}", self.seen);
    }

    /// Whether any line so far contains `needle`.
    pub fn said(&mut self, needle: &str) -> bool {
        self.drain();
        self.seen.iter().any(|l| l.contains(needle))
    }

    pub fn client(&self, token: &str) -> sitar_client::Client {
        sitar_client::Client::new(&self.url)
            .unwrap()
            .with_server_token(token)
            .unwrap()
    }

    /// Kills the process at once (SIGKILL), as a crash would.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Serving {
    fn drop(&mut self) {
        self.kill();
    }
}

/// `METHOD url/path` with the bearer `token` through curl: (HTTP status, body).
pub fn request(method: &str, url: &str, path: &str, token: &str) -> (String, String) {
    let out = Command::new("curl")
        .args(["-s", "-X", method, "-w", "\n%{http_code}"])
        .args(["-H", &format!("Authorization: Bearer {token}")])
        .arg(format!("{url}{path}"))
        .output()
        .expect("curl");
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let (body, status) = text.rsplit_once('\n').unwrap_or(("", &text));
    (status.trim().to_string(), body.to_string())
}
