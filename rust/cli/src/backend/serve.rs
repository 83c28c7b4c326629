//! `sitar serve`: the backend the phones talk to.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::ValueEnum;
use sitar_server::{
    AdbConfig, Calibrations, Limits, MAX_CALIBRATIONS, PlaybackKind, Server, ServerConfig,
    TlsConfig,
};

/// Runs the SiTAR backend: HTTP API (versioned and the original app's legacy routes),
/// SQLite storage in DIR, playback on phones over adb (or the simulator), estimation.
#[derive(clap::Args, Debug)]
#[command(after_help = LAN_HELP)]
pub struct Args {
    /// Address to listen on.
    #[arg(long, default_value = "127.0.0.1:8000")]
    addr: SocketAddr,
    /// Data directory (SQLite database and files; created if missing). With --database and
    /// --store: this instance's own files only (admin token, TLS certificate, staged
    /// uploads, bounded local copies of objects).
    #[arg(long, value_name = "DIR", default_value = "sitar-data")]
    data: PathBuf,
    /// Postgres for the metadata several instances share, instead of DIR/sitar.db
    /// (postgres://USER@HOST:PORT/DATABASE; the PG* variables fill in what it leaves out).
    /// Migrations are applied at start. Needs a build with the `cluster` feature.
    #[arg(long, value_name = "URL")]
    database: Option<String>,
    /// An S3-compatible bucket for every session's bytes, instead of DIR/sessions
    /// (s3://BUCKET/PREFIX; endpoint, region and credentials from AWS_ENDPOINT_URL,
    /// AWS_REGION, AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY, AWS_ALLOW_HTTP). Needs a build
    /// with the `cluster` feature.
    #[arg(long, value_name = "URL")]
    store: Option<String>,
    /// With --database: an instance silent this long (no heartbeat in the database) is dead,
    /// and another adopts the sessions it played (within 4/3 of it). Each instance keeps its
    /// id in DIR/instance.id.
    #[arg(long, value_name = "SECS", default_value_t = 30.0)]
    instance_timeout_s: f64,
    /// How trials are played for sessions that do not name a playback (`POST /v1/sessions`
    /// without `playback`), for the legacy `POST /recording` route and `GET /v1/devices`:
    /// adb drives phones over USB, sim plays on simulated phones. Sessions may always ask
    /// for `upload` (the app sends its own trials).
    #[arg(long, value_enum, default_value_t = Playback::Adb)]
    playback: Playback,
    /// The adb executable.
    #[arg(long, default_value = "adb")]
    adb: PathBuf,
    /// Package of the playback app on the phones (the contract: docs/playback-contract.md;
    /// a Unity playback app: its bundle identifier).
    #[arg(long = "adb-package", alias = "package", value_name = "PACKAGE",
          default_value = AdbConfig::DEFAULT_PACKAGE)]
    adb_package: String,
    /// Activity of the playback app (a Unity app: com.unity3d.player.UnityPlayerActivity).
    #[arg(long = "adb-activity", alias = "activity", value_name = "ACTIVITY",
          default_value = AdbConfig::DEFAULT_ACTIVITY)]
    adb_activity: String,
    /// Folder on the phones for the recording and the trajectories
    /// [default: /sdcard/Android/data/PACKAGE/files, the app's own external folder].
    #[arg(long = "adb-remote-dir", value_name = "DIR")]
    adb_remote_dir: Option<String>,
    /// Sim playback speed (1 = real time).
    #[arg(long, default_value_t = 1.0)]
    sim_speed: f64,
    /// Simulated playback phones (as many as `sitar demo` uses).
    #[arg(long, default_value_t = crate::getting_started::demo::DEMO_DEVICES)]
    sim_devices: u32,
    /// Trials of a session that does not ask for a number (`POST /v1/sessions` without
    /// `trials`, the legacy route).
    #[arg(long, default_value_t = 5)]
    trials: u32,
    /// Largest recording accepted, in MiB.
    #[arg(long, default_value_t = 2048)]
    max_recording_mib: u64,
    /// Largest trajectory accepted, in MiB.
    #[arg(long, default_value_t = 64)]
    max_trajectory_mib: u64,
    /// Connections served at once; one more is answered 503 and closed.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..),
          default_value_t = ServerConfig::new("").max_connections as u64)]
    max_connections: u64,
    /// Seconds a client has to send a request's headers whole (slow clients are cut off).
    #[arg(long, value_name = "SECS", value_parser = clap::value_parser!(u64).range(1..), default_value_t = ServerConfig::new("").header_read_timeout.as_secs())]
    header_timeout_s: u64,
    /// Seconds a request body other than an upload may send nothing before it is ended.
    #[arg(long, value_name = "SECS", value_parser = clap::value_parser!(u64).range(1..), default_value_t = ServerConfig::new("").body_idle_timeout.as_secs())]
    body_idle_timeout_s: u64,
    /// Seconds an upload may send nothing before it is taken as broken off (what arrived of
    /// a recording is kept for a resume).
    #[arg(long, value_name = "SECS", value_parser = clap::value_parser!(u64).range(1..), default_value_t = ServerConfig::new("").upload_idle_timeout.as_secs())]
    upload_idle_timeout_s: u64,
    /// MiB one session may keep on disk (413 beyond).
    #[arg(long, value_name = "MIB", default_value_t = ServerConfig::new("").session_disk_quota >> 20)]
    session_quota_mib: u64,
    /// GiB all sessions together may keep on disk (507 beyond).
    #[arg(long, value_name = "GIB", default_value_t = ServerConfig::new("").disk_quota >> 30)]
    disk_quota_gib: u64,
    /// Delete finished (done or failed) sessions, files included, this many days after
    /// they finished, and idle ones (never uploaded, or waiting for trials) this many days
    /// after they were created. Without it everything is kept (DELETE frees one).
    #[arg(long, value_name = "DAYS")]
    keep_days: Option<u32>,
    /// How often this instance looks for deletes a crash cut off (the session gone, some of
    /// its bytes not) and removes what is left, 0.1–20 s; any live instance finishes another's
    /// within three periods.
    #[arg(long, value_name = "SECS", default_value_t = 15.0)]
    delete_sweep_s: f64,
    /// Test hook: a delete waits this long between removing the session's rows and its bytes
    /// (the tests kill the instance then).
    #[arg(long, value_name = "SECS", hide = true)]
    delete_pause_s: Option<f64>,
    /// Log level: error, warn, info, debug or trace [default: RUST_LOG's, else info]. Every
    /// line starts with an RFC 3339 time stamp (UTC).
    #[arg(long, value_name = "LEVEL")]
    log_level: Option<log::LevelFilter>,
    /// Sessions one token may create per hour (429 beyond).
    #[arg(long, value_name = "N", default_value_t = Limits::default().sessions_per_hour)]
    max_sessions_per_hour: u32,
    /// GiB one token may upload per 24 hours (429 beyond).
    #[arg(long, value_name = "GIB", default_value_t = Limits::default().upload_bytes_per_day >> 30)]
    max_upload_gib_per_day: u64,
    /// Uploads one token may send at once (429 beyond).
    #[arg(long, value_name = "N", default_value_t = Limits::default().concurrent_uploads)]
    max_concurrent_uploads: u32,
    /// Playback jobs (sim, adb) running at once; more wait in a queue holding no thread
    /// [default: the machine's cores, 2 … 8]. 0: this server plays nothing itself; playback
    /// hosts (`sitar worker`, worker tokens) lease the trials.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=256))]
    playback_workers: Option<u32>,
    /// With --playback-workers 0: a host's lease on a trial lasts this long past its last
    /// heartbeat; then the trial is played elsewhere and the host's late upload is refused.
    #[arg(long, value_name = "SECS", default_value_t = 60.0)]
    lease_s: f64,
    /// With --playback-workers 0: sessions whose trials are out with the hosts at once (each
    /// holds a thread; more wait in the queue).
    #[arg(long, value_name = "N", default_value_t = 64,
          value_parser = clap::value_parser!(u32).range(1..=4096))]
    remote_sessions: u32,
    /// `upload` sessions' estimates running at once [default: the machine's cores, 2 … 8].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=256))]
    estimate_workers: Option<u32>,
    /// Sessions of one token playing at once (tokens are served round-robin).
    #[arg(long, value_name = "N", default_value_t = 2,
          value_parser = clap::value_parser!(u32).range(1..=256))]
    jobs_per_token: u32,
    /// Sessions waiting for playback, all tokens together (503 beyond).
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    max_queued: usize,
    /// Largest `trials` a session may ask for (422 beyond).
    #[arg(long, value_name = "N", default_value_t = 100,
          value_parser = clap::value_parser!(u32).range(1..=100_000))]
    max_trials: u32,
    /// Let sessions ask for sim playback although --playback is adb (demos, load tests).
    #[arg(long)]
    allow_sim: bool,
    /// No tokens at all: every request is allowed. Refused unless --addr is loopback.
    #[arg(long)]
    insecure_no_auth: bool,
    /// Serve HTTPS (rustls). Without --cert/--key a self-signed certificate is made once into
    /// DIR/tls/; its SHA-256 fingerprint is printed at start and shown on the overview page.
    #[arg(long)]
    tls: bool,
    /// PEM certificate chain for --tls (with --key).
    #[arg(long, value_name = "PEM", requires = "tls", requires = "key")]
    cert: Option<PathBuf>,
    /// PEM private key for --tls (with --cert).
    #[arg(long, value_name = "PEM", requires = "tls", requires = "cert")]
    key: Option<PathBuf>,
    /// A calibration sessions may ask for (`"calibration": NAME` in POST /v1/sessions):
    /// NAME (1–64 of A-Z a-z 0-9 _ . -) and a file made by `sitar calibrate` on runs of one
    /// SLAM system on one playback device model. Repeat it (at most 64); each file is read and
    /// checked at start.
    #[arg(long = "calibration", value_name = "NAME=FILE")]
    calibrations: Vec<String>,
    /// A host name or address the self-signed certificate is made for (repeat it)
    /// [default: localhost, 127.0.0.1, ::1, this machine's LAN address and host name].
    #[arg(long = "tls-name", value_name = "NAME", requires = "tls")]
    tls_names: Vec<String>,
}

/// The end of `sitar serve --help`: how phones on a LAN reach the backend.
const LAN_HELP: &str = "\
For phones on a LAN:
  The default --addr 127.0.0.1:8000 is reachable from this machine only. Listen on every
  interface with --addr 0.0.0.0:8000, let the port through the firewall (e.g.
  `sudo ufw allow 8000/tcp`) and give the app http://LAN-ADDRESS:8000 (`ip -4 addr`
  shows this machine's LAN address; the phone must be on the same network). Give each
  app its own token (`sitar token create --data DIR --role app --name PHONE`, revoked with
  `sitar token revoke`). With --tls the app uses https://: a self-signed certificate is
  made for this machine's LAN address and name, and its SHA-256 fingerprint is printed for
  the app to pin.

Phones on other machines: start the server with --playback-workers 0 and run
`sitar worker --server URL --token-file FILE --playback adb` on each of them, with a token
from `sitar token create --data DIR --role worker --name HOSTS`.

Examples:
  sitar serve --playback sim --data sitar-data
  sitar serve --addr 0.0.0.0:8000 --tls --data sitar-data";

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Playback {
    Adb,
    Sim,
}

/// glibc's malloc gives each thread that allocates while another does an arena of its own
/// (up to 8 per core) and keeps what is freed in each for later: a server whose blocking
/// threads take turns building reports and scenes holds a few dozen MiB more than it uses
/// (1 GiB recording, 8 clients: 146 MiB peak with glibc's default, 104 MiB with two arenas;
/// rust/server/README.md, "Memory whatever the recording's size"). So the `sitar` binary's
/// `serve` runs with `MALLOC_ARENA_MAX=2` unless the environment says otherwise: set, then the same
/// binary (`/proc/self/exe`) started again in this process's place (same PID, arguments
/// and open files) before anything else happens. Where that fails, it goes on as it is.
fn with_two_malloc_arenas() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        use std::os::unix::process::CommandExt;
        const ARENAS: &str = "MALLOC_ARENA_MAX";
        // Only the `sitar` binary re-executes itself: run from the Python package, this
        // process is the interpreter, which must not be started again with sitar's arguments.
        let own_binary = std::env::current_exe()
            .ok()
            .and_then(|p| {
                p.file_name()
                    .map(|n| n.to_string_lossy().starts_with("sitar"))
            })
            .unwrap_or(false);
        if std::env::var_os(ARENAS).is_some() || !own_binary {
            return;
        }
        let mut argv = std::env::args_os();
        let mut again = std::process::Command::new("/proc/self/exe");
        if let Some(name) = argv.next() {
            again.arg0(name);
        }
        // Returns only when the exec failed.
        let failed = again.args(argv).env(ARENAS, "2").exec();
        eprintln!("sitar serve: going on with glibc's default malloc arenas ({failed})");
    }
}

pub fn run(args: Args) -> Result<()> {
    with_two_malloc_arenas();
    // A cluster flag in a build without the backends: say how to get one, before anything.
    if !sitar_server::CLUSTER {
        for (flag, given) in [
            ("--database", args.database.is_some()),
            ("--store", args.store.is_some()),
        ] {
            if given {
                anyhow::bail!("sitar serve {flag}: {}", sitar_server::NO_CLUSTER);
            }
        }
    }
    crate::backend::logging::init(args.log_level);
    let mut config = ServerConfig::new(&args.data);
    config.database = args.database.clone();
    config.store = args.store.clone();
    config.playback = match args.playback {
        Playback::Adb => PlaybackKind::Adb,
        Playback::Sim => PlaybackKind::Sim,
    };
    config.adb.adb_path = args.adb;
    config.adb.package = args.adb_package;
    config.adb.activity = args.adb_activity;
    config.adb.remote_dir = args.adb_remote_dir;
    config
        .adb
        .check()
        .context("sitar serve --adb-package/--adb-activity/--adb-remote-dir")?;
    config.adb.poll_interval = Duration::from_secs(1);
    config.sim.speed = args.sim_speed;
    config.sim.devices = args.sim_devices;
    config.default_trials = args.trials;
    config.max_recording_bytes = args.max_recording_mib << 20;
    config.max_trajectory_bytes = args.max_trajectory_mib << 20;
    config.max_connections = usize::try_from(args.max_connections).unwrap_or(usize::MAX);
    config.header_read_timeout = Duration::from_secs(args.header_timeout_s);
    config.body_idle_timeout = Duration::from_secs(args.body_idle_timeout_s);
    config.upload_idle_timeout = Duration::from_secs(args.upload_idle_timeout_s);
    config.session_disk_quota = args.session_quota_mib.saturating_mul(1 << 20);
    config.disk_quota = args.disk_quota_gib.saturating_mul(1 << 30);
    config.insecure_no_auth = args.insecure_no_auth;
    if let Some(n) = args.playback_workers {
        config.playback_workers = n as usize;
    }
    if !(args.lease_s.is_finite() && args.lease_s >= 0.1) {
        anyhow::bail!(
            "--lease-s {} is not a number of seconds ≥ 0.1",
            args.lease_s
        );
    }
    config.lease_timeout = Duration::from_secs_f64(args.lease_s);
    if !(args.instance_timeout_s.is_finite() && (1.0..=86_400.0).contains(&args.instance_timeout_s))
    {
        anyhow::bail!(
            "--instance-timeout-s {} is not a number of seconds from 1 to 86400",
            args.instance_timeout_s
        );
    }
    config.instance_timeout = Duration::from_secs_f64(args.instance_timeout_s);
    config.remote_sessions = args.remote_sessions as usize;
    if let Some(n) = args.estimate_workers {
        config.estimate_workers = n as usize;
    }
    config.jobs_per_token = args.jobs_per_token as usize;
    config.max_queued = args.max_queued;
    config.max_trials = args.max_trials;
    config.allow_sim = args.allow_sim;
    config.tls = args.tls.then_some(TlsConfig {
        cert: args.cert,
        key: args.key,
        names: args.tls_names,
    });
    config.limits = Limits {
        sessions_per_hour: args.max_sessions_per_hour,
        upload_bytes_per_day: args.max_upload_gib_per_day.saturating_mul(1 << 30),
        concurrent_uploads: args.max_concurrent_uploads,
    };
    if args.calibrations.len() > MAX_CALIBRATIONS {
        anyhow::bail!(
            "sitar serve --calibration: {} given, a server keeps at most {MAX_CALIBRATIONS}",
            args.calibrations.len()
        );
    }
    for argument in &args.calibrations {
        let (name, file) = Calibrations::parse_argument(argument)?;
        config
            .calibrations
            .read(&name, &file)
            .with_context(|| format!("sitar serve --calibration {argument}"))?;
    }
    let sweep_range = sitar_server::DELETE_SWEEP_RANGE;
    let sweep = Duration::try_from_secs_f64(args.delete_sweep_s).ok();
    config.delete_sweep = sweep.filter(|d| sweep_range.contains(d)).with_context(|| {
        format!(
            "--delete-sweep-s {} is not a number of seconds from {} to {}",
            args.delete_sweep_s,
            sweep_range.start().as_secs_f64(),
            sweep_range.end().as_secs_f64()
        )
    })?;
    config.delete_pause = match args.delete_pause_s {
        Some(s) => Some(Duration::try_from_secs_f64(s).context("--delete-pause-s")?),
        None => None,
    };
    config.retention = args
        .keep_days
        .map(|days| Duration::from_secs(u64::from(days) * 86_400));
    let stores = match (&args.database, &args.store) {
        (None, None) => String::new(),
        (database, store) => format!(
            " (metadata in {}, bytes in {})",
            if database.is_some() {
                "Postgres"
            } else {
                "DIR/sitar.db"
            },
            store.as_deref().unwrap_or("DIR/sessions")
        ),
    };
    if config.playback_workers == 0 {
        eprintln!(
            "sitar serve: sim and adb sessions are played by playback hosts (sitar worker); \
             leases last {} s past a host's last heartbeat",
            args.lease_s
        );
    }
    eprintln!(
        "sitar serve: data {}{stores}, playback {}{}, {} playback and {} estimate workers; \
         Ctrl-C or SIGTERM stops",
        args.data.display(),
        config.playback.as_str(),
        if config.allow_sim {
            " (sim allowed)"
        } else {
            ""
        },
        config.playback_workers,
        config.estimate_workers
    );
    if !config.calibrations.is_empty() {
        let names: Vec<&str> = config.calibrations.names().collect();
        eprintln!("sitar serve: calibrations {}", names.join(", "));
    }
    Server::run(config, args.addr).context("the server stopped")
}
