//! Real playback phones over adb: push, start the playback app, pull `trajectory_N.txt`.

use std::collections::{HashSet, VecDeque};
use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::config::AdbConfig;
use crate::error::Error;
use crate::playback::{DeviceInfo, Playback, PlaybackJob, PlaybackPlan, TrialOutput};

/// The contract between the backend and a playback app, written out in
/// `docs/playback-contract.md`: the intent extras of `am start`, the file names in
/// the phone folder ([`AdbConfig::remote_dir`]) and the status file. The Kotlin
/// playback app (`android/playback`) and the Unity `SitarPlaybackLogger` use the same
/// names; a test compares them.
pub mod contract {
    /// Int extra: how many trials to play.
    pub const EXTRA_TRIALS: &str = "trials";
    /// Int extra: the number of the first trial; trial `k` (0-based) of the launch is
    /// written as `trajectory_{first + k}.txt`.
    pub const EXTRA_FIRST: &str = "first";
    /// String extra: the recording (mp4) on the phone.
    pub const EXTRA_RECORDING: &str = "recording";
    /// String extra: the folder to write the trajectories and the status file into.
    pub const EXTRA_OUTPUT: &str = "output";
    /// The recording's name in the phone folder.
    pub const RECORDING_FILE: &str = "recording.mp4";
    /// The output folder's name in the phone folder.
    pub const OUTPUT_DIR: &str = "out";
    /// The app's one-line status in the output folder: `starting`, `playing K/N`,
    /// `done N/N`, or `failed MESSAGE` (the backend fails the phone's share with it).
    pub const STATUS_FILE: &str = "status.txt";
    /// The first word of the status line a playback app writes when it gives up.
    pub const STATUS_FAILED: &str = "failed";

    /// The name of trial `index`'s trajectory (TUM, integer nanoseconds).
    pub fn trajectory_file(index: u32) -> String {
        format!("trajectory_{index}.txt")
    }

    /// `trajectory_K.txt` → K.
    pub fn trajectory_number(name: &str) -> Option<u32> {
        name.trim()
            .strip_prefix("trajectory_")?
            .strip_suffix(".txt")?
            .parse()
            .ok()
    }

    /// The message of a `failed MESSAGE` status (`None` for every other state).
    pub fn failure(status: &str) -> Option<&str> {
        let line = status.lines().next()?.trim();
        let rest = line.strip_prefix(STATUS_FAILED)?;
        (rest.is_empty() || rest.starts_with(char::is_whitespace)).then(|| rest.trim())
    }
}

/// Playback on the phones `adb devices` lists. Each phone gets the recording
/// pushed once to `DIR/recording.mp4` (`DIR` is [`AdbConfig::remote_dir`]) and is
/// started with its share of the trials
/// (`am start -S -W -n PACKAGE/ACTIVITY --ei trials N --ei first F --es recording
/// DIR/recording.mp4 --es output DIR/out`: `-S` stops a run still going, `-W` waits
/// for the launch); the app writes `DIR/out/trajectory_K.txt` (K = F … F+N−1) after
/// each trial and the files are pulled as they appear. A `failed …` line in
/// `DIR/out/status.txt` fails the phone's share with that message. A phone that
/// disappears, fails or misses its deadline hands its unfinished trials back to the
/// others.
#[derive(Debug, Clone)]
pub struct AdbPlayback {
    config: AdbConfig,
    /// The last `adb devices` answer and when it came: see [`AdbPlayback::list`].
    listing: Arc<Mutex<Option<(Instant, Listing)>>>,
    /// Plays on this phone only (a playback host's slot: `sitar worker` leases one trial per
    /// phone); `None`: every ready phone.
    only: Option<String>,
}

/// `adb devices`, parsed, or why it failed.
type Listing = Result<Vec<(String, String)>, String>;

/// How long an `adb devices` answer is reused.
pub const DEVICE_LIST_TTL: Duration = Duration::from_secs(2);

/// Runs a command with a deadline; stdout on success, an error naming the command otherwise.
fn run(program: &Path, args: &[&str], timeout: Duration) -> Result<String, Error> {
    let describe = || format!("{} {}", program.display(), args.join(" "));
    let mut child = Command::new(program)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| Error::Playback(format!("cannot run {}: {e}", describe())))?;
    // Read the pipes on threads so a chatty command cannot block on a full pipe.
    let mut stdout = child.stdout.take();
    let mut stderr = child.stderr.take();
    let out = std::thread::spawn(move || {
        let mut s = String::new();
        if let Some(p) = stdout.as_mut() {
            let _ = p.read_to_string(&mut s);
        }
        s
    });
    let err = std::thread::spawn(move || {
        let mut s = String::new();
        if let Some(p) = stderr.as_mut() {
            let _ = p.read_to_string(&mut s);
        }
        s
    });
    let started = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if started.elapsed() > timeout => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(Error::Playback(format!(
                    "{} timed out after {:.0?}",
                    describe(),
                    timeout
                )));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(5)),
            Err(e) => return Err(Error::Playback(format!("{}: {e}", describe()))),
        }
    };
    let out = out.join().unwrap_or_default();
    let err = err.join().unwrap_or_default();
    if !status.success() {
        return Err(Error::Playback(format!(
            "{} failed ({status}): {}",
            describe(),
            err.trim()
        )));
    }
    Ok(out)
}

/// Duration of an mp4 from its header (`mvhd`), without decoding anything.
pub fn mp4_duration_s(path: &Path) -> Result<f64, Error> {
    let file = std::fs::File::open(path).map_err(|e| Error::io("cannot open", path, e))?;
    let size = file
        .metadata()
        .map_err(|e| Error::io("cannot stat", path, e))?
        .len();
    let reader = mp4::Mp4Reader::read_header(std::io::BufReader::new(file), size).map_err(|e| {
        Error::InvalidContent(format!("the recording has no readable mp4 header: {e}"))
    })?;
    Ok(reader.duration().as_secs_f64())
}

impl AdbPlayback {
    /// An adb backend with the given configuration.
    pub fn new(config: AdbConfig) -> AdbPlayback {
        AdbPlayback {
            config,
            listing: Arc::default(),
            only: None,
        }
    }

    /// The same backend playing on phone `serial` only (it shares the `adb devices` answer).
    pub fn on_phone(&self, serial: &str) -> AdbPlayback {
        AdbPlayback {
            only: Some(serial.to_string()),
            ..self.clone()
        }
    }

    fn adb(&self, args: &[&str], timeout: Duration) -> Result<String, Error> {
        run(&self.config.adb_path, args, timeout)
    }

    fn on(&self, serial: &str, args: &[&str], timeout: Duration) -> Result<String, Error> {
        let mut all = vec!["-s", serial];
        all.extend_from_slice(args);
        self.adb(&all, timeout)
    }

    /// `adb devices`, parsed: (serial, state) per attached device. One answer serves every
    /// caller for 2 s (`DEVICE_LIST_TTL`), and callers arriving while it runs wait for it, so
    /// many concurrent `GET /v1/devices` start one `adb` process, not one each.
    pub fn list(&self) -> Result<Vec<(String, String)>, Error> {
        let mut cached = self.listing.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((at, listing)) = cached.as_ref()
            && at.elapsed() < DEVICE_LIST_TTL
        {
            return listing.clone().map_err(Error::Playback);
        }
        let fresh = self.list_now();
        *cached = Some((
            Instant::now(),
            fresh.as_ref().map(Vec::clone).map_err(|e| match e {
                Error::Playback(m) => m.clone(),
                other => other.to_string(),
            }),
        ));
        fresh
    }

    fn list_now(&self) -> Result<Vec<(String, String)>, Error> {
        let out = self.adb(&["devices"], Duration::from_secs(10))?;
        Ok(out
            .lines()
            .skip_while(|l| !l.starts_with("List of devices"))
            .skip(1)
            .filter_map(|l| {
                let mut parts = l.split_whitespace();
                Some((parts.next()?.to_string(), parts.next()?.to_string()))
            })
            .collect())
    }

    fn ready_devices(&self) -> Result<Vec<String>, Error> {
        Ok(self
            .list()?
            .into_iter()
            .filter(|(serial, s)| {
                s == "device" && self.only.as_ref().is_none_or(|only| only == serial)
            })
            .map(|(serial, _)| serial)
            .collect())
    }

    fn duration_s(&self, recording: &Path) -> f64 {
        match mp4_duration_s(recording) {
            Ok(d) if d > 0.0 => d,
            Ok(_) | Err(_) => self.config.fallback_duration_s,
        }
    }

    /// One phone's loop: take a share of the queue, play it, pull results.
    fn run_device(
        &self,
        serial: &str,
        job: &PlaybackJob,
        queue: &Mutex<VecDeque<u32>>,
        active: &Mutex<usize>,
        trial_s: f64,
        sink: &(dyn Fn(TrialOutput) + Sync),
    ) -> Result<(), Error> {
        let phone = self.push(serial, job)?;
        loop {
            let batch = take_share(queue, active)?;
            if batch.is_empty() || job.cancelled() {
                return Ok(());
            }
            let mut pulled: HashSet<usize> = HashSet::new();
            if let Err(e) = phone.run_batch(job, &batch, trial_s, sink, &mut pulled) {
                give_back(queue, &batch, &pulled);
                return Err(e);
            }
            if job.cancelled() {
                return Ok(());
            }
        }
    }

    /// Step 1 on a phone: its output folder made and the recording pushed.
    fn push<'a>(&'a self, serial: &'a str, job: &PlaybackJob) -> Result<Phone<'a>, Error> {
        let dir = self.config.remote_dir();
        let out_dir = format!("{dir}/{}", contract::OUTPUT_DIR);
        let phone = Phone {
            adb: self,
            serial,
            remote_rec: format!("{dir}/{}", contract::RECORDING_FILE),
            status_file: format!("{out_dir}/{}", contract::STATUS_FILE),
            out_dir,
            pull_dir: job.work_dir.clone(),
            safe_serial: serial
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect(),
        };
        let recording = job.recording.to_string_lossy().into_owned();
        phone.adb(&["shell", "mkdir", "-p", &phone.out_dir], COMMAND_TIMEOUT)?;
        phone.adb(&["push", &recording, &phone.remote_rec], PUSH_TIMEOUT)?;
        std::fs::create_dir_all(&phone.pull_dir)
            .map_err(|e| Error::io("cannot create", &phone.pull_dir, e))?;
        Ok(phone)
    }
}

/// A bounded wait for one adb command, and for the recording's push.
const COMMAND_TIMEOUT: Duration = Duration::from_secs(30);
const PUSH_TIMEOUT: Duration = Duration::from_secs(600);

/// This phone's share of the trials left: ⌈remaining / phones⌉, so D phones finish together.
fn take_share(queue: &Mutex<VecDeque<u32>>, active: &Mutex<usize>) -> Result<Vec<u32>, Error> {
    let mut q = queue
        .lock()
        .map_err(|_| Error::Internal("queue lock".into()))?;
    let phones = (*active.lock().map_err(|_| Error::Internal("lock".into()))?).max(1);
    let share = q.len().div_ceil(phones);
    Ok(q.drain(..share).collect())
}

/// The trials of a failed batch that were not pulled go back to the front of the queue, in
/// order, for another phone.
fn give_back(queue: &Mutex<VecDeque<u32>>, batch: &[u32], pulled: &HashSet<usize>) {
    if let Ok(mut q) = queue.lock() {
        for (k, index) in batch.iter().enumerate().rev() {
            if !pulled.contains(&k) {
                q.push_front(*index);
            }
        }
    }
}

/// One phone with the recording pushed: where the playback app reads and writes on it, and
/// where its trials are pulled to.
struct Phone<'a> {
    adb: &'a AdbPlayback,
    serial: &'a str,
    remote_rec: String,
    out_dir: String,
    status_file: String,
    pull_dir: std::path::PathBuf,
    safe_serial: String,
}

impl Phone<'_> {
    fn adb(&self, args: &[&str], timeout: Duration) -> Result<String, Error> {
        self.adb.on(self.serial, args, timeout)
    }

    fn stop_app(&self) {
        let _ = self.adb(
            &["shell", "am", "force-stop", &self.adb.config.package],
            COMMAND_TIMEOUT,
        );
    }

    /// Step 2: plays `batch` (the app started once for all of them) and pulls each trial as
    /// it appears, within its deadline; `pulled` holds the batch positions delivered.
    fn run_batch(
        &self,
        job: &PlaybackJob,
        batch: &[u32],
        trial_s: f64,
        sink: &(dyn Fn(TrialOutput) + Sync),
        pulled: &mut HashSet<usize>,
    ) -> Result<(), Error> {
        // Last run's files: a stale trajectory or failure must not count for this one.
        let stale = format!("{}/trajectory_*.txt", self.out_dir);
        self.adb(
            &["shell", "rm", "-f", &stale, &self.status_file],
            COMMAND_TIMEOUT,
        )?;
        self.start_app(batch)?;
        let config = &self.adb.config;
        let started = Instant::now();
        while pulled.len() < batch.len() {
            if job.cancelled() {
                self.stop_app();
                return Ok(());
            }
            // Trial k is due by (k+1)·d·factor + slack.
            let due = trial_s * config.trial_timeout_factor * (pulled.len() + 1) as f64
                + config.trial_timeout_slack.as_secs_f64();
            if started.elapsed().as_secs_f64() > due {
                self.stop_app();
                return Err(Error::Playback(format!(
                    "{}: trial {} not done after {due:.0} s",
                    self.serial,
                    pulled.len()
                )));
            }
            std::thread::sleep(config.poll_interval);
            let listing = self.adb(&["shell", "ls", &self.out_dir], COMMAND_TIMEOUT)?;
            self.pull_ready(&listing, batch, sink, pulled)?;
            if pulled.len() < batch.len() {
                self.check_status(&listing)?;
            }
        }
        Ok(())
    }

    /// Starts the playback app for `batch` (docs/playback-contract.md).
    fn start_app(&self, batch: &[u32]) -> Result<(), Error> {
        let config = &self.adb.config;
        let component = format!("{}/{}", config.package, config.activity);
        let count = batch.len().to_string();
        let first = batch[0].to_string();
        let started_app = self.adb(
            &[
                "shell",
                "am",
                "start",
                "-S",
                "-W",
                "-n",
                &component,
                "--ei",
                contract::EXTRA_TRIALS,
                &count,
                "--ei",
                contract::EXTRA_FIRST,
                &first,
                "--es",
                contract::EXTRA_RECORDING,
                &self.remote_rec,
                "--es",
                contract::EXTRA_OUTPUT,
                &self.out_dir,
            ],
            COMMAND_TIMEOUT,
        )?;
        // `am` reports a missing activity on stdout ("Error type 3", "Error: Activity
        // class {…} does not exist.") and still exits 0.
        let errors: Vec<&str> = started_app
            .lines()
            .map(str::trim)
            .filter(|l| l.starts_with("Error"))
            .collect();
        if errors.is_empty() {
            return Ok(());
        }
        Err(Error::Playback(format!(
            "{}: am start -n {component}: {} (is the playback app installed? \
             see docs/playback-contract.md)",
            self.serial,
            errors.join("; ")
        )))
    }

    /// Step 3: pulls every trial of `batch` the folder `listing` shows and hands it on.
    fn pull_ready(
        &self,
        listing: &str,
        batch: &[u32],
        sink: &(dyn Fn(TrialOutput) + Sync),
        pulled: &mut HashSet<usize>,
    ) -> Result<(), Error> {
        let first = batch[0];
        let mut ready: Vec<usize> = listing
            .split_whitespace()
            .filter_map(contract::trajectory_number)
            .filter_map(|n| n.checked_sub(first).map(|k| k as usize))
            .filter(|k| *k < batch.len() && !pulled.contains(k))
            .collect();
        ready.sort_unstable();
        for k in ready {
            let name = contract::trajectory_file(first + k as u32);
            let local = self.pull_dir.join(format!("{}_{k}.txt", self.safe_serial));
            let remote = format!("{}/{name}", self.out_dir);
            self.adb(
                &["pull", &remote, &local.to_string_lossy()],
                COMMAND_TIMEOUT,
            )?;
            let text =
                std::fs::read_to_string(&local).map_err(|e| Error::io("cannot read", &local, e))?;
            let _ = std::fs::remove_file(&local);
            pulled.insert(k);
            sink(TrialOutput {
                index: batch[k],
                tum: text,
                source: format!("adb:{}", self.serial),
            });
        }
        Ok(())
    }

    /// A failure the playback app reported in its status file ends the batch.
    fn check_status(&self, listing: &str) -> Result<(), Error> {
        if !listing
            .split_whitespace()
            .any(|f| f == contract::STATUS_FILE)
        {
            return Ok(());
        }
        let status = self.adb(&["shell", "cat", &self.status_file], COMMAND_TIMEOUT)?;
        let Some(message) = contract::failure(&status) else {
            return Ok(());
        };
        self.stop_app();
        Err(Error::Playback(format!(
            "{}: the playback app failed: {}",
            self.serial,
            if message.is_empty() {
                "(no message)"
            } else {
                message
            }
        )))
    }
}

impl Playback for AdbPlayback {
    fn name(&self) -> &'static str {
        "adb"
    }

    fn plan(&self, recording: &Path, _trials: u32) -> Result<PlaybackPlan, Error> {
        let devices = self.ready_devices()?;
        if devices.is_empty() {
            return Err(Error::Playback(
                "no playback phone is connected (adb devices lists none ready)".into(),
            ));
        }
        Ok(PlaybackPlan {
            trial_seconds: self.duration_s(recording),
            devices: devices.len() as u32,
        })
    }

    fn play(&self, job: &PlaybackJob, sink: &(dyn Fn(TrialOutput) + Sync)) -> Result<(), Error> {
        let devices = self.ready_devices()?;
        if devices.is_empty() {
            return Err(Error::Playback("no playback phone is connected".into()));
        }
        let trial_s = self.duration_s(&job.recording);
        let queue = Mutex::new(job.indices.iter().copied().collect::<VecDeque<u32>>());
        let active = Mutex::new(devices.len());
        let failures = Mutex::new(Vec::new());
        std::thread::scope(|scope| {
            for serial in &devices {
                let (queue, active, failures) = (&queue, &active, &failures);
                scope.spawn(move || {
                    if let Err(e) = self.run_device(serial, job, queue, active, trial_s, sink) {
                        log::warn!("adb device {serial} dropped out: {e}");
                        if let Ok(mut a) = active.lock() {
                            *a = a.saturating_sub(1);
                        }
                        if let Ok(mut f) = failures.lock() {
                            f.push(e.to_string());
                        }
                    }
                });
            }
        });
        // Phones that finished before another dropped out pick up its trials.
        loop {
            let left = queue.lock().map(|q| q.len()).unwrap_or(0);
            if left == 0 || job.cancelled() {
                return Ok(());
            }
            let survivors = self.ready_devices().unwrap_or_default();
            let failed_all = survivors.is_empty();
            if failed_all {
                let why = failures.lock().map(|f| f.join("; ")).unwrap_or_default();
                return Err(Error::Playback(format!(
                    "{left} trial(s) unplayed: every phone dropped out ({why})"
                )));
            }
            if let Ok(mut a) = active.lock() {
                *a = survivors.len();
            }
            let progress = std::thread::scope(|scope| {
                let handles: Vec<_> = survivors
                    .iter()
                    .map(|serial| {
                        let (queue, active) = (&queue, &active);
                        scope.spawn(move || {
                            self.run_device(serial, job, queue, active, trial_s, sink)
                        })
                    })
                    .collect();
                let mut progress = false;
                let mut why = Vec::new();
                for h in handles {
                    match h.join() {
                        Ok(Ok(())) => progress = true,
                        Ok(Err(e)) => why.push(e.to_string()),
                        Err(_) => why.push("a phone's thread panicked".to_owned()),
                    }
                }
                (progress, why)
            });
            if !progress.0 {
                let left = queue.lock().map(|q| q.len()).unwrap_or(0);
                return Err(Error::Playback(format!(
                    "{left} trial(s) unplayed: no phone could play them ({})",
                    progress.1.join("; ")
                )));
            }
        }
    }

    fn devices(&self) -> Vec<DeviceInfo> {
        match self.list() {
            Ok(list) => list
                .into_iter()
                .map(|(serial, state)| DeviceInfo {
                    serial,
                    state,
                    backend: "adb",
                })
                .collect(),
            Err(e) => {
                log::warn!("adb devices: {e}");
                Vec::new()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ingest::minimal_mp4::minimal_mp4;

    #[cfg(unix)]
    #[test]
    fn concurrent_device_lists_share_one_adb_run() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let calls = dir.path().join("calls");
        let adb = dir.path().join("adb");
        std::fs::write(
            &adb,
            format!(
                "#!/bin/sh\necho run >> '{}'\nsleep 0.3\n\
                 printf 'List of devices attached\\nR58M device\\n'\n",
                calls.display()
            ),
        )
        .unwrap();
        std::fs::set_permissions(&adb, std::fs::Permissions::from_mode(0o755)).unwrap();
        let playback = AdbPlayback::new(AdbConfig {
            adb_path: adb,
            ..AdbConfig::default()
        });
        let runs = || std::fs::read_to_string(&calls).unwrap().lines().count();
        std::thread::scope(|s| {
            let lists: Vec<_> = (0..16).map(|_| s.spawn(|| playback.list())).collect();
            for list in lists {
                let list = list.join().unwrap().unwrap();
                assert_eq!(list, vec![("R58M".to_owned(), "device".to_owned())]);
            }
        });
        assert_eq!(runs(), 1, "16 concurrent callers, one adb process");
        // Past the interval, the next caller asks adb again.
        std::thread::sleep(DEVICE_LIST_TTL);
        playback.list().unwrap();
        assert_eq!(runs(), 2);
    }

    #[test]
    fn trajectory_names_parse() {
        use contract::{trajectory_file, trajectory_number};
        assert_eq!(trajectory_number("trajectory_0.txt"), Some(0));
        assert_eq!(trajectory_number("trajectory_12.txt\r"), Some(12));
        assert_eq!(trajectory_number(&trajectory_file(7)), Some(7));
        assert_eq!(trajectory_number("trajectory_x.txt"), None);
        assert_eq!(trajectory_number("trajectory_3.txt.part"), None);
        assert_eq!(trajectory_number("recording.mp4"), None);
    }

    #[test]
    fn only_a_failed_status_is_a_failure() {
        use contract::failure;
        assert_eq!(
            failure("failed cannot open /sdcard/x.mp4\n"),
            Some("cannot open /sdcard/x.mp4")
        );
        assert_eq!(failure("failed\n"), Some(""));
        assert_eq!(
            failure("  failed   ARCore: IO_ERROR\r\nmore"),
            Some("ARCore: IO_ERROR")
        );
        for other in [
            "",
            "starting",
            "playing 2/5",
            "done 5/5",
            "failedX",
            "not failed",
        ] {
            assert_eq!(failure(other), None, "{other:?}");
        }
    }

    #[test]
    fn mp4_duration_comes_from_mvhd() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.mp4");
        std::fs::write(&path, minimal_mp4(1000, 2500)).unwrap();
        assert!((mp4_duration_s(&path).unwrap() - 2.5).abs() < 1e-9);
        std::fs::write(&path, b"not an mp4 at all").unwrap();
        assert!(matches!(
            mp4_duration_s(&path),
            Err(Error::InvalidContent(_))
        ));
    }
}
