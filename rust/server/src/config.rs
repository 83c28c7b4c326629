use std::path::PathBuf;
use std::time::Duration;

use sitar_core::Thresholds;

/// Where a session's trials come from; the server's default serves sessions that name none
/// (and the legacy routes). Stored typed with every session.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlaybackKind {
    /// Real phones over adb.
    Adb,
    /// The `sitar-sim` replay (demo, tests).
    Sim,
    /// Trials come from outside via `POST /v1/sessions/{id}/trials`.
    Upload,
}

impl PlaybackKind {
    /// The wire name: `adb`, `sim` or `upload`.
    pub fn as_str(self) -> &'static str {
        match self {
            PlaybackKind::Adb => "adb",
            PlaybackKind::Sim => "sim",
            PlaybackKind::Upload => "upload",
        }
    }
}

impl std::str::FromStr for PlaybackKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "adb" => Ok(PlaybackKind::Adb),
            "sim" => Ok(PlaybackKind::Sim),
            "upload" => Ok(PlaybackKind::Upload),
            other => Err(format!(
                "unknown playback {other:?}: expected adb, sim or upload"
            )),
        }
    }
}

/// Settings of the `sim` backend.
#[derive(Debug, Clone)]
pub struct SimConfig {
    /// Replay speed: 1.0 is real time (a 15 s recording takes 15 s per trial), 10.0 ten times faster.
    pub speed: f64,
    /// Number of simulated playback phones running in parallel.
    pub devices: u32,
}

/// Settings of the `adb` backend.
#[derive(Debug, Clone)]
pub struct AdbConfig {
    /// The adb executable (a name looked up on `PATH`, or a path).
    pub adb_path: PathBuf,
    /// Package of the playback app.
    pub package: String,
    /// Activity started with `am start -n package/activity`.
    pub activity: String,
    /// Directory on the phone for the recording and the `trajectory_N.txt` files.
    pub remote_dir: String,
    /// How often the phone is asked for new trajectory files.
    pub poll_interval: Duration,
    /// A trial taking longer than `factor × duration + slack` counts as lost.
    pub trial_timeout_factor: f64,
    /// Fixed slack added to every trial's deadline.
    pub trial_timeout_slack: Duration,
    /// Duration to assume when the recording has no readable mp4 header.
    pub fallback_duration_s: f64,
}

/// Everything `sitar serve` can be told.
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// Where the SQLite database and all files live. Nothing is written outside it.
    pub data_dir: PathBuf,
    /// Backend for the legacy `POST /recording` route and for sessions that name none.
    pub playback: PlaybackKind,
    /// Largest accepted recording (default 2 GiB).
    pub max_recording_bytes: u64,
    /// Largest accepted trajectory or timestamps file (default 64 MiB).
    pub max_trajectory_bytes: u64,
    /// Trials for sessions created by the legacy route or without `trials` (default 5, the
    /// paper's).
    pub default_trials: u32,
    /// Statistic for legacy sessions (default [`sitar_core::DEFAULT_SETTING`], `trim_mean_30`).
    pub default_setting: String,
    /// Adaptive stopping window when a session asks for it without one (default 3).
    pub default_adaptive_k: u32,
    /// Class thresholds of `trans_part` sessions, in metres: medium from, high from (default
    /// 0.05, 0.10: [`Thresholds::DEFAULT_M`]).
    pub thresholds: Thresholds,
    /// Class thresholds of `angle_deg` sessions, in degrees (default 2°, 4°:
    /// [`Thresholds::DEFAULT_DEG`], the metric boundaries seen from 1.5 m).
    pub thresholds_deg: Thresholds,
    /// Memory bound of one live session's parsed trials, in bytes (default 256 MiB: 64 bytes
    /// a pose, so 4.2 million poses, e.g. 1000 trials of 4 190 poses; 100 trials of 2 820
    /// poses take 18 MB). A trial beyond it is refused with 413 (`upload`) or ends the
    /// playback early with a stop reason (sim, adb).
    pub live_session_bytes: usize,
    /// Memory bound of all live sessions' parsed trials together, in bytes (default 1 GiB).
    /// A trial beyond it is refused with 503 `busy` (`upload`) or ends the playback early.
    pub live_total_bytes: usize,
    /// Whether `upload` sessions publish a progressive estimate after every trial from the
    /// 2nd on (default true); without, only `POST …/estimate` estimates.
    pub progressive_uploads: bool,
    /// The `sim` backend.
    pub sim: SimConfig,
    /// The `adb` backend.
    pub adb: AdbConfig,
    /// Finished (done or failed) sessions are deleted this long after they finished, and
    /// idle ones (created, or `upload` sessions waiting for trials) this long after they
    /// were created; `None` (the default) keeps everything.
    pub retention: Option<Duration>,
    /// How often finished sessions are checked against `retention` (default 10 min).
    pub retention_sweep: Duration,
    /// An upload body that sends nothing for this long is taken as broken off: what
    /// arrived is kept for a resume and the request ends (default 60 s).
    pub upload_idle_timeout: Duration,
}

impl ServerConfig {
    /// Defaults with the given data directory.
    pub fn new(data_dir: impl Into<PathBuf>) -> ServerConfig {
        ServerConfig {
            data_dir: data_dir.into(),
            playback: PlaybackKind::Adb,
            max_recording_bytes: 2 << 30,
            max_trajectory_bytes: 64 << 20,
            default_trials: 5,
            default_setting: sitar_core::DEFAULT_SETTING.to_string(),
            default_adaptive_k: 3,
            thresholds: Thresholds::DEFAULT_M,
            thresholds_deg: Thresholds::DEFAULT_DEG,
            live_session_bytes: 256 << 20,
            live_total_bytes: 1 << 30,
            progressive_uploads: true,
            sim: SimConfig {
                speed: 1.0,
                devices: 1,
            },
            adb: AdbConfig {
                adb_path: PathBuf::from("adb"),
                package: "org.sitar.playback".to_string(),
                activity: ".PlaybackActivity".to_string(),
                remote_dir: "/sdcard/sitar".to_string(),
                poll_interval: Duration::from_millis(1000),
                trial_timeout_factor: 2.0,
                trial_timeout_slack: Duration::from_secs(30),
                fallback_duration_s: 60.0,
            },
            retention: None,
            retention_sweep: Duration::from_secs(600),
            upload_idle_timeout: Duration::from_secs(60),
        }
    }
}
