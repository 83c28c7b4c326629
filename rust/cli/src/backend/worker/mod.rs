//! `sitar worker`: a playback host. It connects out to `sitar serve --playback-workers 0`
//! with a worker token, reports its phones, heartbeats, leases one trial at a time per free
//! phone, fetches each recording once (kept by content hash), plays the trial and uploads it.

mod cache;
mod slot;

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use sitar_client::Client;
use sitar_server::{AdbConfig, AdbPlayback};

use cache::RecordingCache;

/// Runs a playback host: leases trials from a `sitar serve --playback-workers 0` and plays
/// them on this machine's phones (adb) or simulated phones (sim).
#[derive(clap::Args, Debug)]
#[command(after_help = WORKER_HELP)]
pub struct Args {
    /// The server's address (http://HOST:PORT or https://…).
    #[arg(long, value_name = "URL")]
    server: String,
    /// A worker token (`sitar token create --role worker`); it may use the worker routes only.
    #[arg(
        long,
        value_name = "TOKEN",
        required_unless_present = "token_file",
        conflicts_with = "token_file"
    )]
    token: Option<String>,
    /// A file holding the worker token (its first line): keeps it out of the process list.
    #[arg(long, value_name = "FILE")]
    token_file: Option<PathBuf>,
    /// With an https:// server: the SHA-256 fingerprint of its certificate (as `sitar serve
    /// --tls` prints it); the worker then trusts that certificate only.
    #[arg(long, value_name = "HEX")]
    server_cert_sha256: Option<String>,
    /// sim plays on simulated phones (--slots of them), adb on this machine's phones.
    #[arg(long, value_enum)]
    playback: Playback,
    /// Simulated phones (sim); with adb, every ready phone of `adb devices` is one.
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..=256))]
    slots: u32,
    /// This host's name in the server's devices listing [default: the machine's host name].
    #[arg(long)]
    name: Option<String>,
    /// Folder of the recording cache (created if missing).
    #[arg(long, value_name = "DIR", default_value = "sitar-worker")]
    data: PathBuf,
    /// MiB of recordings kept (least recently used go first beyond it).
    #[arg(long, value_name = "MIB", default_value_t = 4096)]
    cache_mib: u64,
    /// Sim playback speed (1 = real time).
    #[arg(long, default_value_t = 1.0)]
    sim_speed: f64,
    /// The adb executable.
    #[arg(long, default_value = "adb")]
    adb: PathBuf,
    /// Package of the playback app on the phones.
    #[arg(long = "adb-package", value_name = "PACKAGE", default_value = AdbConfig::DEFAULT_PACKAGE)]
    adb_package: String,
    /// Activity of the playback app.
    #[arg(long = "adb-activity", value_name = "ACTIVITY", default_value = AdbConfig::DEFAULT_ACTIVITY)]
    adb_activity: String,
    /// Folder on the phones [default: /sdcard/Android/data/PACKAGE/files].
    #[arg(long = "adb-remote-dir", value_name = "DIR")]
    adb_remote_dir: Option<String>,
    /// Log level: error, warn, info, debug or trace [default: RUST_LOG's, else info].
    #[arg(long, value_name = "LEVEL")]
    log_level: Option<log::LevelFilter>,
}

const WORKER_HELP: &str = "\
The server must run with --playback-workers 0 (it then plays nothing itself). Each phone
leases one trial at a time; a host that stops heartbeating loses its leases after the
server's --lease-s (60 s) and its trials are played elsewhere; a phone failing twice in a
row is taken out of service until the worker starts again.

Example:
  sitar token create --data sitar-data --role worker --name lab-host-1
  sitar worker --server http://10.0.0.5:8000 --token sitar_… --playback adb";

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
enum Playback {
    Adb,
    Sim,
}

/// What the slots and the heartbeat share.
pub(crate) struct Host {
    client: Client,
    /// The server-made id; replaced when the server forgot the host and it registered again.
    id: Mutex<String>,
    /// Each busy phone's lease and the flag that stops its playback.
    held: Mutex<HashMap<String, (String, Arc<AtomicBool>)>>,
    cache: RecordingCache,
    stop: AtomicBool,
}

impl Host {
    pub(crate) fn id(&self) -> String {
        self.id.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    fn held(&self) -> std::sync::MutexGuard<'_, HashMap<String, (String, Arc<AtomicBool>)>> {
        self.held.lock().unwrap_or_else(|e| e.into_inner())
    }
}

fn host_name(args: &Args) -> String {
    args.name.clone().unwrap_or_else(|| {
        std::fs::read_to_string("/proc/sys/kernel/hostname")
            .ok()
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| "worker".into())
    })
}

/// The token of `--token`, or the first line of `--token-file`.
fn worker_token(args: &Args) -> Result<String> {
    match (&args.token, &args.token_file) {
        (Some(token), _) => Ok(token.clone()),
        (None, Some(file)) => {
            let text = std::fs::read_to_string(file)
                .with_context(|| format!("--token-file {}", file.display()))?;
            let token = text.lines().next().unwrap_or("").trim().to_string();
            if token.is_empty() {
                bail!("--token-file {}: the first line is empty", file.display());
            }
            Ok(token)
        }
        (None, None) => bail!("give --token or --token-file"),
    }
}

/// The phones to report: sim's slots, or adb's ready phones now.
fn phones(playback: Playback, slots: u32, adb: &AdbPlayback) -> Vec<String> {
    match playback {
        Playback::Sim => (0..slots).map(|i| format!("sim:{i}")).collect(),
        Playback::Adb => adb
            .list()
            .map(|list| {
                list.into_iter()
                    .filter(|(_, state)| state == "device")
                    .map(|(serial, _)| serial)
                    .collect()
            })
            .unwrap_or_else(|e| {
                log::warn!("adb devices: {e}");
                Vec::new()
            }),
    }
}

pub fn run(args: Args) -> Result<()> {
    crate::backend::logging::init(args.log_level);
    if !(args.sim_speed.is_finite() && args.sim_speed > 0.0) {
        bail!("--sim-speed {} is not a positive number", args.sim_speed);
    }
    let mut client = Client::new(&args.server)
        .context("--server")?
        .with_timeout(Duration::from_secs(60))
        .with_server_token(&worker_token(&args)?)
        .context("--token")?;
    if let Some(pin) = &args.server_cert_sha256 {
        client = client
            .with_server_cert_sha256(pin)
            .context("--server-cert-sha256")?;
    }
    let mut adb_config = AdbConfig {
        adb_path: args.adb.clone(),
        package: args.adb_package.clone(),
        activity: args.adb_activity.clone(),
        remote_dir: args.adb_remote_dir.clone(),
        ..AdbConfig::default()
    };
    adb_config.poll_interval = Duration::from_secs(1);
    adb_config
        .check()
        .context("sitar worker --adb-package/--adb-activity/--adb-remote-dir")?;
    let adb = AdbPlayback::new(adb_config);
    let name = host_name(&args);
    let kind = match args.playback {
        Playback::Adb => "adb",
        Playback::Sim => "sim",
    };
    let present = phones(args.playback, args.slots, &adb);
    let registered = register(&client, &name, kind, &present, &args.server)?;
    eprintln!(
        "sitar worker: host {name} ({}) with {} {kind} phone(s) on {}; leases last {} s",
        registered.host,
        present.len(),
        args.server,
        registered.lease_s
    );
    let host = Arc::new(Host {
        client,
        id: Mutex::new(registered.host.clone()),
        held: Mutex::new(HashMap::new()),
        cache: RecordingCache::open(&args.data, args.cache_mib.saturating_mul(1 << 20))?,
        stop: AtomicBool::new(false),
    });
    let player = slot::Player {
        playback: args.playback == Playback::Sim,
        sim_speed: args.sim_speed,
        adb: adb.clone(),
        work: args.data.join("work"),
    };
    let mut started: Vec<String> = Vec::new();
    let heartbeat = Duration::from_secs_f64(registered.heartbeat_s.clamp(0.05, 30.0));
    loop {
        // New phones (adb) get a slot of their own; a slot never ends while the worker runs.
        for phone in &present_or(&present, args.playback, args.slots, &adb) {
            if !started.contains(phone) {
                started.push(phone.clone());
                let (host, player, phone) = (host.clone(), player.clone(), phone.clone());
                std::thread::Builder::new()
                    .name(format!("slot-{phone}"))
                    .spawn(move || slot::run(&host, &player, &phone))
                    .context("starting a phone's thread")?;
            }
        }
        std::thread::sleep(heartbeat);
        beat(&host, &name, kind, &phones(args.playback, args.slots, &adb));
        if host.stop.load(Ordering::SeqCst) {
            return Ok(());
        }
    }
}

/// Registers the host, waiting for a server that is not up yet (started before it, or
/// restarting): 1 s, 2 s, … up to 30 s between tries. A refused token ends the worker.
fn register(
    client: &Client,
    name: &str,
    kind: &str,
    phones: &[String],
    server: &str,
) -> Result<sitar_client::WorkerHost> {
    let mut pause = Duration::from_secs(1);
    loop {
        match client.worker_register(name, kind, phones) {
            Ok(host) => return Ok(host),
            Err(e) if matches!(e.status(), Some(400..=499)) => {
                return Err(anyhow::anyhow!(e))
                    .with_context(|| format!("registering host {name} with {server}"));
            }
            Err(e) => {
                log::warn!("registering host {name} with {server}: {e}; again in {pause:?}");
                std::thread::sleep(pause);
                pause = (pause * 2).min(Duration::from_secs(30));
            }
        }
    }
}

fn present_or(first: &[String], playback: Playback, slots: u32, adb: &AdbPlayback) -> Vec<String> {
    match playback {
        Playback::Sim => first.to_vec(),
        Playback::Adb => phones(playback, slots, adb),
    }
}

/// One heartbeat: aborts the leases the server no longer gives this host; registers again
/// when the server forgot it.
fn beat(host: &Host, name: &str, kind: &str, phones: &[String]) {
    let leases: Vec<String> = host.held().values().map(|(l, _)| l.clone()).collect();
    match host.client.worker_heartbeat(&host.id(), phones, &leases) {
        Ok(answer) => {
            for (phone, (lease, cancel)) in host.held().iter() {
                if answer.abort.contains(lease) {
                    log::warn!("{phone}: lease {lease} is no longer ours: stopping its trial");
                    cancel.store(true, Ordering::SeqCst);
                }
            }
            for phone in &answer.out_of_service {
                log::warn!("{phone}: out of service (failed twice in a row)");
            }
        }
        Err(e) if e.status() == Some(404) => {
            log::warn!("the server forgot this host: registering again");
            match host.client.worker_register(name, kind, phones) {
                Ok(again) => *host.id.lock().unwrap_or_else(|e| e.into_inner()) = again.host,
                Err(e) => log::warn!("registering again: {e}"),
            }
        }
        Err(e) => log::warn!("heartbeat: {e}"),
    }
}
