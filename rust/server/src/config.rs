use std::path::PathBuf;
use std::time::Duration;

use sitar_core::Thresholds;

use crate::model::PlaybackKind;

/// Settings of the `sim` backend.
#[derive(Debug, Clone)]
pub struct SimConfig {
    /// Replay speed: 1.0 is real time (a 15 s recording takes 15 s per trial), 10.0 ten times faster.
    pub speed: f64,
    /// Number of simulated playback phones running in parallel.
    pub devices: u32,
}

/// Settings of the `adb` backend. The defaults drive the SiTAR playback app
/// (`android/playback`); the contract with any playback app (package, activity,
/// extras, folders, status file) is `docs/playback-contract.md`.
#[derive(Debug, Clone)]
pub struct AdbConfig {
    /// The adb executable (a name looked up on `PATH`, or a path).
    pub adb_path: PathBuf,
    /// Package of the playback app (default [`AdbConfig::DEFAULT_PACKAGE`]).
    pub package: String,
    /// Activity started with `am start -S -W -n package/activity` (default
    /// [`AdbConfig::DEFAULT_ACTIVITY`]; a leading `.` is relative to the package).
    pub activity: String,
    /// Folder on the phone for the recording and the `trajectory_N.txt` files; `None`
    /// (the default) is the package's app-specific external folder, which the app can
    /// write without a storage permission: see [`AdbConfig::remote_dir`].
    pub remote_dir: Option<String>,
    /// How often the phone is asked for new trajectory files.
    pub poll_interval: Duration,
    /// A trial taking longer than `factor × duration + slack` counts as lost.
    pub trial_timeout_factor: f64,
    /// Fixed slack added to every trial's deadline.
    pub trial_timeout_slack: Duration,
    /// Duration to assume when the recording has no readable mp4 header.
    pub fallback_duration_s: f64,
}

impl AdbConfig {
    /// Package of the SiTAR playback app (`android/playback`).
    pub const DEFAULT_PACKAGE: &'static str = "io.github.sitar.playback";
    /// Its activity, relative to the package.
    pub const DEFAULT_ACTIVITY: &'static str = ".PlaybackActivity";

    /// The folder on the phone: [`AdbConfig::remote_dir`] if set, else the package's
    /// app-specific external folder `/sdcard/Android/data/PACKAGE/files` (what
    /// `Context.getExternalFilesDir(null)` and Unity's `Application.persistentDataPath`
    /// are; adb can read and write it, the app needs no storage permission).
    pub fn remote_dir(&self) -> String {
        match &self.remote_dir {
            Some(dir) => dir.trim_end_matches('/').to_owned(),
            None => format!("/sdcard/Android/data/{}/files", self.package),
        }
    }

    /// Checks the names that go into `adb shell` command lines (which the phone's
    /// shell parses): a Java package name, an activity class name, an absolute
    /// folder of plain path characters.
    pub fn check(&self) -> Result<(), crate::error::Error> {
        let java_name = |s: &str| {
            !s.is_empty()
                && s.split('.').all(|part| {
                    part.chars()
                        .next()
                        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
                        && part.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                })
        };
        if !java_name(&self.package) || !self.package.contains('.') {
            return Err(crate::error::Error::Config(format!(
                "adb package {:?} is not an Android package name (like {})",
                self.package,
                Self::DEFAULT_PACKAGE
            )));
        }
        if !java_name(self.activity.strip_prefix('.').unwrap_or(&self.activity)) {
            return Err(crate::error::Error::Config(format!(
                "adb activity {:?} is not an activity class name (like {} or \
                 com.unity3d.player.UnityPlayerActivity)",
                self.activity,
                Self::DEFAULT_ACTIVITY
            )));
        }
        let dir = self.remote_dir();
        let plain = |c: char| c.is_ascii_alphanumeric() || "/._-".contains(c);
        if !dir.starts_with('/') || dir.len() < 2 || !dir.chars().all(plain) || dir.contains("..") {
            return Err(crate::error::Error::Config(format!(
                "adb remote dir {dir:?} is not an absolute folder of letters, digits and /._- \
                 (like /sdcard/Android/data/{}/files)",
                self.package
            )));
        }
        Ok(())
    }
}

impl Default for AdbConfig {
    fn default() -> AdbConfig {
        AdbConfig {
            adb_path: PathBuf::from("adb"),
            package: Self::DEFAULT_PACKAGE.to_owned(),
            activity: Self::DEFAULT_ACTIVITY.to_owned(),
            remote_dir: None,
            poll_interval: Duration::from_millis(1000),
            trial_timeout_factor: 2.0,
            trial_timeout_slack: Duration::from_secs(30),
            fallback_duration_s: 60.0,
        }
    }
}

/// Everything `sitar serve` can be told.
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// Where the SQLite database and all files live. Nothing is written outside it. With
    /// `database` and `store`, the instance's own files only: admin token, TLS certificate,
    /// staged uploads, local copies.
    pub data_dir: PathBuf,
    /// A Postgres URL (`postgres://…`; `PG*` variables fill in what it leaves out) for the
    /// metadata that several instances share; `None` (the default): SQLite in `data_dir`.
    pub database: Option<String>,
    /// An S3-compatible bucket (`s3://BUCKET/PREFIX`; endpoint, region and credentials from
    /// the `AWS_*` variables) for every session's bytes; `None` (the default): `data_dir`.
    pub store: Option<String>,
    /// Backend for the legacy `POST /recording` route and for sessions that name none.
    pub playback: PlaybackKind,
    /// Largest accepted recording (default 2 GiB).
    pub max_recording_bytes: u64,
    /// Largest accepted trajectory or timestamps file (default 64 MiB).
    pub max_trajectory_bytes: u64,
    /// Connections served at once (default 512); one more is answered 503 `busy` and closed.
    pub max_connections: usize,
    /// A request's headers must arrive whole within this time, else the connection is
    /// closed (default 10 s; slow clients dribbling headers are cut off).
    pub header_read_timeout: std::time::Duration,
    /// A request body other than an upload (recording, trial, evidence) that sends nothing
    /// for this long ends its request (default 10 s); uploads use `upload_idle_timeout`.
    pub body_idle_timeout: std::time::Duration,
    /// Bytes one session may keep on disk: recording, its kept prefix, trials, evidence,
    /// results (default 4 GiB). An upload that would pass it is a 413 `too_large`.
    pub session_disk_quota: u64,
    /// Bytes all sessions together may keep on disk, uploads in progress included
    /// (default 100 GiB). An upload that would pass it is a 507 `insufficient_storage`.
    pub disk_quota: u64,
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
    /// How often every instance looks for deletes a crash cut off (the session's row gone,
    /// some of its bytes not) and finishes them (default 15 s; within
    /// [`DELETE_SWEEP_RANGE`]). A delete's own instance holds the work for twice this, so
    /// what a crash left is removed by a live instance within three periods (45 s).
    pub delete_sweep: Duration,
    /// A test hook: a delete waits this long after the session's row is gone and before its
    /// bytes are removed, so a test can kill the instance mid-delete. `None` (the default):
    /// no wait.
    pub delete_pause: Option<Duration>,
    /// An upload body that sends nothing for this long is taken as broken off: what
    /// arrived is kept for a resume and the request ends (default 60 s).
    pub upload_idle_timeout: Duration,
    /// Turns access control off: every request is allowed (default false). The server
    /// refuses to start with it on an address that is not loopback.
    pub insecure_no_auth: bool,
    /// Tokens registered at start, replacing the hash of a token of the same name (the demo
    /// and the tests; an operator uses `sitar token create`).
    pub preset_tokens: Vec<crate::auth::PresetToken>,
    /// Limits per token (sessions per hour, upload bytes per day, concurrent uploads).
    pub limits: crate::auth::Limits,
    /// HTTPS with rustls (`sitar serve --tls`); `None` (the default): plain HTTP.
    pub tls: Option<TlsConfig>,
    /// Playback jobs (sim, adb) running at once, each on its own thread; more wait in the
    /// queue holding no thread (default: the machine's cores, at least 2, at most 8).
    ///
    /// With 0, the server plays nothing itself: sim and adb sessions are played by
    /// `sitar worker` hosts that lease their trials (`remote_sessions` of them at once).
    pub playback_workers: usize,
    /// `upload` sessions' estimates (progressive and final) running at once (default: the
    /// machine's cores, at least 2, at most 8).
    pub estimate_workers: usize,
    /// Sessions of one token playing at once; the queue serves tokens round-robin, so one
    /// client never starves another (default 2; sessions made without a token share one).
    pub jobs_per_token: usize,
    /// Sessions waiting in the playback queue, all tokens together (default 10 000); a
    /// recording that would start one more is refused with 503 `busy`.
    pub max_queued: usize,
    /// With `playback_workers` 0: sessions whose trials are offered to the playback hosts at
    /// once (default 64; each holds a thread while it plays, more wait in the queue).
    pub remote_sessions: usize,
    /// A playback host's lease on a trial lasts this long past its last heartbeat (default
    /// 60 s); then the trial is offered to another phone and the host's late upload is
    /// refused.
    pub lease_timeout: Duration,
    /// With `database` set (several instances on one database): an instance whose heartbeat
    /// is older than this is dead, and the sessions it played are adopted by another
    /// (default 30 s).
    pub instance_timeout: Duration,
    /// Largest `trials` a session may ask for (default 100); more is a 422 naming the cap.
    pub max_trials: u32,
    /// Whether sessions may ask for `sim` playback on a server whose `playback` is another
    /// (default false): simulated playback costs CPU and is for demos and tests.
    pub allow_sim: bool,
    /// Calibrations sessions may name (`"calibration"` in `POST /v1/sessions`), read and
    /// checked at start (`sitar serve --calibration NAME=FILE`; at most
    /// [`MAX_CALIBRATIONS`](crate::MAX_CALIBRATIONS)); none by default.
    pub calibrations: crate::estimate::calibrations::Calibrations,
}

/// How long an instance may be silent (no heartbeat in the database) before the others
/// count it dead and adopt the sessions it played: 30 s, six missed heartbeats.
pub const INSTANCE_TIMEOUT: Duration = Duration::from_secs(30);

/// Periods `delete_sweep` may take: at most 20 s, so that a crash's leftovers go within a
/// minute (three periods); at least 0.1 s, so that the sweeps stay cheap.
pub const DELETE_SWEEP_RANGE: std::ops::RangeInclusive<Duration> =
    Duration::from_millis(100)..=Duration::from_secs(20);

impl ServerConfig {
    /// Refuses a `delete_sweep` outside [`DELETE_SWEEP_RANGE`], naming it.
    pub fn check_delete_sweep(&self) -> Result<(), crate::error::Error> {
        if DELETE_SWEEP_RANGE.contains(&self.delete_sweep) {
            Ok(())
        } else {
            Err(crate::error::Error::Config(format!(
                "delete sweep every {:?}: must be from 0.1 s to 20 s",
                self.delete_sweep
            )))
        }
    }

    /// Defaults with the given data directory.
    pub fn new(data_dir: impl Into<PathBuf>) -> ServerConfig {
        ServerConfig {
            data_dir: data_dir.into(),
            database: None,
            store: None,
            playback: PlaybackKind::Adb,
            max_recording_bytes: 2 << 30,
            max_trajectory_bytes: 64 << 20,
            max_connections: 512,
            header_read_timeout: Duration::from_secs(10),
            body_idle_timeout: Duration::from_secs(10),
            session_disk_quota: 4 << 30,
            disk_quota: 100 << 30,
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
            adb: AdbConfig::default(),
            retention: None,
            retention_sweep: Duration::from_secs(600),
            delete_sweep: Duration::from_secs(15),
            delete_pause: None,
            upload_idle_timeout: Duration::from_secs(60),
            insecure_no_auth: false,
            preset_tokens: Vec::new(),
            limits: crate::auth::Limits::default(),
            tls: None,
            playback_workers: std::thread::available_parallelism()
                .map_or(2, |n| n.get())
                .clamp(2, 8),
            estimate_workers: std::thread::available_parallelism()
                .map_or(2, |n| n.get())
                .clamp(2, 8),
            jobs_per_token: 2,
            max_queued: 10_000,
            remote_sessions: 64,
            lease_timeout: Duration::from_secs(60),
            instance_timeout: INSTANCE_TIMEOUT,
            max_trials: 100,
            allow_sim: false,
            calibrations: Default::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_remote_dir_follows_the_package_unless_set() {
        let mut adb = AdbConfig::default();
        assert_eq!(
            adb.remote_dir(),
            "/sdcard/Android/data/io.github.sitar.playback/files"
        );
        adb.package = "com.example.unityplayback".into();
        assert_eq!(
            adb.remote_dir(),
            "/sdcard/Android/data/com.example.unityplayback/files"
        );
        adb.remote_dir = Some("/sdcard/Download/sitar/".into());
        assert_eq!(adb.remote_dir(), "/sdcard/Download/sitar");
        assert!(adb.check().is_ok());
    }

    #[test]
    fn the_delete_sweep_period_is_bounded() {
        let mut config = ServerConfig::new("");
        assert!(config.check_delete_sweep().is_ok(), "the default");
        for (period, ok) in [
            (Duration::from_millis(100), true),
            (Duration::from_secs(20), true),
            (Duration::ZERO, false),
            (Duration::from_millis(99), false),
            (Duration::from_secs(21), false),
        ] {
            config.delete_sweep = period;
            let checked = config.check_delete_sweep();
            assert_eq!(checked.is_ok(), ok, "{period:?}");
            if let Err(e) = checked {
                assert!(e.to_string().contains("0.1 s to 20 s"), "{e}");
            }
        }
    }

    #[test]
    fn names_that_would_reach_the_phone_shell_are_checked() {
        let ok = AdbConfig::default();
        assert!(ok.check().is_ok());
        let unity = AdbConfig {
            package: "com.example.app".into(),
            activity: "com.unity3d.player.UnityPlayerActivity".into(),
            ..AdbConfig::default()
        };
        assert!(unity.check().is_ok());
        for package in [
            "",
            "nodot",
            "a.b;reboot",
            "a..b",
            "1a.b",
            "a.b c",
            "a.b$HOME",
        ] {
            let bad = AdbConfig {
                package: package.into(),
                ..AdbConfig::default()
            };
            let err = bad.check().unwrap_err().to_string();
            assert!(err.contains("adb package"), "{package:?}: {err}");
        }
        // `$` too: the phone's shell would expand `Outer$Inner`.
        for activity in ["", ".", ".Main Activity", "$(id)", "a.Outer$Inner"] {
            let bad = AdbConfig {
                activity: activity.into(),
                ..AdbConfig::default()
            };
            let err = bad.check().unwrap_err().to_string();
            assert!(err.contains("adb activity"), "{activity:?}: {err}");
        }
        for dir in [
            "relative/dir",
            "/",
            "/sdcard/a b",
            "/sdcard/../data",
            "/x;rm",
        ] {
            let bad = AdbConfig {
                remote_dir: Some(dir.into()),
                ..AdbConfig::default()
            };
            let err = bad.check().unwrap_err().to_string();
            assert!(err.contains("adb remote dir"), "{dir:?}: {err}");
        }
    }
}

/// `sitar serve --tls`: where the certificate comes from.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TlsConfig {
    /// PEM certificate chain (`--cert`); with [`TlsConfig::key`]. Without both, a
    /// self-signed certificate is made once into `DATA/tls/`.
    pub cert: Option<PathBuf>,
    /// PEM private key (`--key`).
    pub key: Option<PathBuf>,
    /// Host names and addresses the self-signed certificate is made for (`--tls-name`,
    /// repeatable); empty: `localhost`, `127.0.0.1`, `::1`, this machine's LAN address and
    /// host name. Only used when the certificate is made: delete `DATA/tls/` to make another.
    pub names: Vec<String>,
}
