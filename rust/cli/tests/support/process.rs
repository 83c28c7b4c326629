//! `sitar` processes for the real-process tests: their output lines as they come, signals,
//! and a `sitar serve` on a free loopback port with its URL. Killed (SIGKILL) when dropped,
//! and let go on first should a test have stopped them.

use std::ffi::OsStr;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

/// A running `sitar` whose stdout and stderr lines are collected.
pub struct Proc {
    pub child: Child,
    lines: Receiver<String>,
    pub seen: Vec<String>,
}

impl Proc {
    /// Runs `sitar ARGS`.
    pub fn sitar(args: &[&str]) -> Proc {
        Proc::sitar_with(args, &[])
    }

    /// Runs `sitar ARGS` with extra environment variables.
    pub fn sitar_with(args: &[&str], env: &[(&str, &OsStr)]) -> Proc {
        let mut command = Command::new(env!("CARGO_BIN_EXE_sitar"));
        for (name, value) in env {
            command.env(name, value);
        }
        let mut child = command
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run sitar");
        let (tx, lines) = channel();
        let streams: [Box<dyn std::io::Read + Send>; 2] = [
            Box::new(child.stdout.take().expect("piped stdout")),
            Box::new(child.stderr.take().expect("piped stderr")),
        ];
        for stream in streams {
            let tx = tx.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(stream).lines().map_while(Result::ok) {
                    if tx.send(line).is_err() {
                        return;
                    }
                }
            });
        }
        Proc {
            child,
            lines,
            seen: Vec::new(),
        }
    }

    /// Takes the lines that arrived so far.
    pub fn drain(&mut self) {
        while let Ok(line) = self.lines.try_recv() {
            self.seen.push(line);
        }
    }

    /// Waits up to `limit` for a line containing `needle` (one seen before counts); panics
    /// with every line seen.
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
        let ended = self.child.try_wait().ok().flatten();
        panic!(
            "no line with {needle:?} in {limit:?} (exit: {ended:?}): {:#?}",
            self.seen
        );
    }

    /// Whether any line so far contains `needle`.
    pub fn said(&mut self, needle: &str) -> bool {
        self.drain();
        self.seen.iter().any(|l| l.contains(needle))
    }

    /// Sends signal `name` (`KILL`, `STOP`, `CONT`…) with `kill`.
    pub fn signal(&self, name: &str) {
        let status = Command::new("kill")
            .args([&format!("-{name}"), &self.child.id().to_string()])
            .status()
            .expect("kill");
        assert!(status.success(), "kill -{name}");
    }

    /// Kills the process at once (SIGKILL), as a crash would, and reaps it.
    pub fn kill(&mut self) {
        // A stopped child must go on to die (a reaped one's pid may be another's now).
        if matches!(self.child.try_wait(), Ok(None)) {
            let _ = Command::new("kill")
                .args(["-CONT", &self.child.id().to_string()])
                .status();
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        self.kill();
    }
}

/// A running `sitar serve` on a free loopback port and its URL.
pub struct Serving {
    pub process: Proc,
    pub url: String,
}

impl Serving {
    /// Runs `sitar serve --addr 127.0.0.1:0 --data DATA ARGS` and waits for its URL.
    pub fn start(data: &Path, args: &[&str]) -> Serving {
        let data = data.to_str().expect("a UTF-8 data folder");
        let mut all = vec!["serve", "--addr", "127.0.0.1:0", "--data", data];
        all.extend_from_slice(args);
        Serving::run(&all)
    }

    /// `sitar serve` with in-process sim playback (2 phones at 30×) and `extra` arguments.
    pub fn sim(data: &Path, extra: &[&str]) -> Serving {
        let mut args = vec![
            "--playback",
            "sim",
            "--sim-speed",
            "30",
            "--sim-devices",
            "2",
        ];
        args.extend_from_slice(extra);
        Serving::start(data, &args)
    }

    /// Runs `sitar ARGS` (a `serve` with its own `--addr`) and waits for its URL.
    pub fn run(args: &[&str]) -> Serving {
        let mut process = Proc::sitar(args);
        let line = process.wait_for("listening on http://", Duration::from_secs(60));
        let url = line[line.find("http://").expect("a URL")..]
            .trim()
            .to_string();
        Serving { process, url }
    }

    /// A client of this instance with `token`.
    pub fn client(&self, token: &str) -> sitar_client::Client {
        sitar_client::Client::new(&self.url)
            .unwrap()
            .with_server_token(token)
            .unwrap()
    }
}

impl std::ops::Deref for Serving {
    type Target = Proc;
    fn deref(&self) -> &Proc {
        &self.process
    }
}

impl std::ops::DerefMut for Serving {
    fn deref_mut(&mut self) -> &mut Proc {
        &mut self.process
    }
}

/// The admin token `sitar serve` wrote in its data folder `data` (the first instance on a
/// database writes it).
pub fn admin_token(data: &Path) -> String {
    std::fs::read_to_string(data.join("admin.token"))
        .unwrap()
        .trim()
        .to_string()
}

/// `sitar token create --role ROLE --name NAME PLACE…` (`--data DIR` or `--database URL`):
/// the token it printed.
pub fn create_token(place: &[&str], role: &str, name: &str) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_sitar"))
        .args(["token", "create", "--role", role, "--name", name])
        .args(place)
        .output()
        .expect("run sitar token create");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap().trim().to_string()
}

/// A `sitar worker --playback sim` host `name` of `slots` phones playing at `speed`× real
/// time (its folder `dir/name`), connected to `url` and registered.
pub fn sim_host(url: &str, token: &str, name: &str, slots: &str, speed: &str, dir: &Path) -> Proc {
    let folder = dir.join(name);
    let mut host = Proc::sitar(&[
        "worker",
        "--server",
        url,
        "--token",
        token,
        "--playback",
        "sim",
        "--slots",
        slots,
        "--sim-speed",
        speed,
        "--name",
        name,
        "--data",
        folder.to_str().expect("a UTF-8 folder"),
    ]);
    host.wait_for("sitar worker: host", Duration::from_secs(60));
    host
}

/// The `Upload-Offset` a `HEAD` of session `id`'s recording at `url` answers for upload key
/// `key` (through curl).
pub fn upload_offset(url: &str, token: &str, id: &str, key: &str) -> usize {
    let out = Command::new("curl")
        .args(["-s", "-I", "-H", &format!("Authorization: Bearer {token}")])
        .args(["-H", &format!("Idempotency-Key: {key}")])
        .arg(format!("{url}/v1/sessions/{id}/recording"))
        .output()
        .expect("curl");
    let head = String::from_utf8_lossy(&out.stdout).to_string();
    head.lines()
        .find_map(|l| {
            let (name, value) = l.split_once(':')?;
            name.eq_ignore_ascii_case("upload-offset")
                .then(|| value.trim().parse().ok())?
        })
        .unwrap_or_else(|| panic!("no Upload-Offset in {head}"))
}
