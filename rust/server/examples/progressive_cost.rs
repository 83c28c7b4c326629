//! What progressive estimates cost the backend, in process CPU time.
//!
//! `cargo run --release -p sitar-server --example progressive_cost [-- --trials 100 --poses
//! 2820 --repeat 3 --sitar target/release/sitar --setting trim_mean_30]`
//!
//! The trials are `scripts/bench-vs-evo`'s (the estimator's synthetic generator, seed 11:
//! every 3rd trial drops about 1 % of its frames). The server runs as a child process (this
//! example, `--serve DIR`), so its CPU time is its own: user + system time of the whole
//! process from `/proc/PID/stat`, read before and after each run. Three figures, each the
//! median of `--repeat` runs:
//!
//! * (a) an `upload` session receiving the trials one by one with a progressive estimate
//!   after each: post a trial, wait until `results_trials` equals the trial count (status
//!   polled every 5 ms), post the next; then the final estimate;
//! * (b) the same session with progressive estimates off (`progressive_uploads = false`):
//!   post every trial, then one final estimate;
//! * (c) `sitar estimate` on the same files (`--sitar PATH`, or `target/release/sitar`
//!   when it exists; its CPU from this process's children times), else the same code path in
//!   this process (read the files, estimate, write the CSV).
//!
//! Printed: CPU seconds and wall seconds of each, and the ratios a/b and b/c. `--setting` picks
//! the sessions' and `sitar estimate`'s setting: with `mean`, whose progressive estimator path
//! costs about one one-shot estimate, a/b shows what the server's own share of progressive
//! results costs.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::time::{Duration, Instant};

use sitar_client::{Client, NewSession, SessionState};
use sitar_server::{PlaybackKind, Server, ServerConfig};

#[path = "../../estimator/examples/support/synthetic.rs"]
mod synthetic;

/// Clock ticks per second of `/proc/PID/stat` (`USER_HZ`: 100 on Linux).
const TICKS: f64 = 100.0;

/// (own, waited-for children's) user + system CPU seconds of process `pid`.
fn cpu_seconds(pid: &str) -> (f64, f64) {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    // Fields after the command name, which is in parentheses: field 14 (utime) is index 11.
    let fields: Vec<f64> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(0.0))
        .collect();
    let at = |i: usize| fields.get(i).copied().unwrap_or(0.0) / TICKS;
    (at(11) + at(12), at(13) + at(14))
}

/// Peak resident memory of process `pid` in MiB (`VmHWM`).
fn peak_mib(pid: &str) -> f64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0)
}

/// `--serve DIR [--no-progressive]`: the backend on a free port; prints its URL, stops when
/// stdin closes.
fn serve(dir: &Path, progressive: bool) {
    let mut config = ServerConfig::new(dir);
    config.playback = PlaybackKind::Upload;
    config.progressive_uploads = progressive;
    let server = Server::spawn(config, "127.0.0.1:0".parse().unwrap()).expect("server starts");
    println!("{}", server.url());
    std::io::stdout().flush().unwrap();
    let _ = std::io::stdin().read_to_end(&mut Vec::new());
    server.stop();
}

/// A backend in a child process.
struct Backend {
    child: Child,
    stdin: Option<ChildStdin>,
    url: String,
}

impl Backend {
    fn start(dir: &Path, progressive: bool) -> Backend {
        let mut command = Command::new(std::env::current_exe().unwrap());
        command.arg("--serve").arg(dir);
        if !progressive {
            command.arg("--no-progressive");
        }
        let mut child = command
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .expect("backend starts");
        let mut url = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut url)
            .unwrap();
        let stdin = child.stdin.take();
        Backend {
            child,
            stdin,
            url: url.trim().to_string(),
        }
    }

    fn pid(&self) -> String {
        self.child.id().to_string()
    }

    fn stop(mut self) {
        drop(self.stdin.take());
        self.child.wait().unwrap();
    }
}

/// One run: (server CPU s, wall s, peak server memory MiB, status polls).
fn run_session(texts: &[String], setting: &str, progressive: bool) -> (f64, f64, f64, u32) {
    let data = tempfile::tempdir().unwrap();
    let backend = Backend::start(data.path(), progressive);
    let admin = std::fs::read_to_string(data.path().join(sitar_server::ADMIN_TOKEN_FILE)).unwrap();
    let client = Client::new(&backend.url)
        .unwrap()
        .with_timeout(Duration::from_secs(600))
        .with_server_token(&admin)
        .unwrap();
    let id = client
        .create_session(&NewSession {
            trials: texts.len() as u32,
            setting: setting.into(),
            playback: "upload".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    let mut polls = 0;
    let mut wait = |done: &dyn Fn(&sitar_client::SessionStatus) -> bool| loop {
        polls += 1;
        let status = client.status(&id).unwrap();
        assert_ne!(status.state, SessionState::Failed, "{status:?}");
        if done(&status) {
            return status;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let (cpu0, _) = cpu_seconds(&backend.pid());
    let started = Instant::now();
    for (k, text) in texts.iter().enumerate() {
        client.upload_trial(&id, text).unwrap();
        let n = k as u32 + 1;
        if progressive && n >= 2 {
            wait(&|s| s.results_trials == n);
        }
    }
    client.start_estimate(&id).unwrap();
    let status = wait(&|s| s.state == SessionState::Done);
    assert_eq!(status.results_trials, texts.len() as u32);
    let wall = started.elapsed().as_secs_f64();
    let (cpu1, _) = cpu_seconds(&backend.pid());
    let peak = peak_mib(&backend.pid());
    backend.stop();
    (cpu1 - cpu0, wall, peak, polls)
}

/// `sitar estimate FILES` (CPU s, wall s): the binary when there is one, else its code path.
fn run_cli(sitar: Option<&Path>, files: &[PathBuf], setting: &str) -> (f64, f64) {
    let started = Instant::now();
    match sitar {
        Some(sitar) => {
            let (_, children0) = cpu_seconds("self");
            let out = Command::new(sitar)
                .arg("estimate")
                .args(["--setting", setting])
                .args(files)
                .output()
                .expect("sitar runs");
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let (_, children1) = cpu_seconds("self");
            (children1 - children0, started.elapsed().as_secs_f64())
        }
        None => {
            let (own0, _) = cpu_seconds("self");
            let trials: Vec<_> = files
                .iter()
                .map(|f| sitar_estimator::read_tum(f).unwrap())
                .collect();
            let options = sitar_estimator::EstimateOptions {
                setting: setting.parse().expect("a setting name"),
                ..Default::default()
            };
            let estimate = sitar_estimator::estimate(&trials, &options).unwrap();
            std::hint::black_box(estimate.to_legacy_csv());
            let (own1, _) = cpu_seconds("self");
            (own1 - own0, started.elapsed().as_secs_f64())
        }
    }
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        (values[n / 2 - 1] + values[n / 2]) / 2.0
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--serve") {
        let progressive = !args.iter().any(|a| a == "--no-progressive");
        return serve(Path::new(&args[1]), progressive);
    }
    let value = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let trials: usize = value("--trials").map_or(100, |v| v.parse().unwrap());
    let poses: usize = value("--poses").map_or(2820, |v| v.parse().unwrap());
    let repeat: usize = value("--repeat").map_or(3, |v| v.parse().unwrap());
    let setting = value("--setting").unwrap_or_else(|| sitar_core::DEFAULT_SETTING.into());
    let sitar = value("--sitar").map(PathBuf::from).or_else(|| {
        let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/release/sitar");
        built.is_file().then_some(built)
    });

    let dir = tempfile::tempdir().unwrap();
    let files = synthetic::write_trials(dir.path(), trials, poses, 11, true);
    let texts: Vec<String> = files
        .iter()
        .map(|f| std::fs::read_to_string(f).unwrap())
        .collect();
    println!(
        "{trials} trials x {poses} poses (every 3rd drops frames), {setting}, {repeat} runs \
         each; CPU = user + system of the server process"
    );
    let (mut a, mut b, mut c) = (Vec::new(), Vec::new(), Vec::new());
    for run in 0..repeat {
        let progressive = run_session(&texts, &setting, true);
        let one_final = run_session(&texts, &setting, false);
        let cli = run_cli(sitar.as_deref(), &files, &setting);
        println!(
            "run {run}: (a) {:.2} CPU s, {:.2} s wall, {:.0} MiB peak, {} polls; \
             (b) {:.2} CPU s, {:.2} s wall, {:.0} MiB peak; (c) {:.2} CPU s, {:.2} s wall",
            progressive.0,
            progressive.1,
            progressive.2,
            progressive.3,
            one_final.0,
            one_final.1,
            one_final.2,
            cli.0,
            cli.1
        );
        a.push(progressive);
        b.push(one_final);
        c.push(cli);
    }
    let cpu = |runs: &[(f64, f64, f64, u32)]| median(runs.iter().map(|r| r.0).collect());
    let wall = |runs: &[(f64, f64, f64, u32)]| median(runs.iter().map(|r| r.1).collect());
    let (a_cpu, b_cpu) = (cpu(&a), cpu(&b));
    let c_cpu = median(c.iter().map(|r| r.0).collect());
    let c_wall = median(c.iter().map(|r| r.1).collect());
    println!("medians:");
    println!(
        "(a) progressive estimate after every trial: {a_cpu:.2} CPU s ({:.2} s wall)",
        wall(&a)
    );
    println!(
        "(b) one final estimate:                     {b_cpu:.2} CPU s ({:.2} s wall)",
        wall(&b)
    );
    println!(
        "(c) sitar estimate on the files ({}): {c_cpu:.2} CPU s ({c_wall:.2} s wall)",
        if sitar.is_some() {
            "binary"
        } else {
            "in process"
        }
    );
    println!("a/b = {:.1}x   b/c = {:.2}x", a_cpu / b_cpu, b_cpu / c_cpu);
}
