//! How trials are played: the [`Playback`] trait and its backends — the simulator
//! ([`SimPlayback`]), phones over adb (`adb`), trials from outside ([`UploadPlayback`]) and
//! playback hosts (`remote`) — and the bounded queue of sessions waiting for one (`queue`).
//! The jobs that drive them are `jobs::playback` and `jobs::playback_run`.

pub(crate) mod adb;
pub(crate) mod queue;
pub(crate) mod remote;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::config::SimConfig;
use crate::error::Error;

/// How long a backend expects playback to take: one trial lasts
/// `trial_seconds` and `devices` run side by side, so T trials take
/// `trial_seconds · ⌈T / devices⌉`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaybackPlan {
    /// Seconds one trial takes on one device.
    pub trial_seconds: f64,
    /// Devices running in parallel (0: trials come from outside).
    pub devices: u32,
}

impl PlaybackPlan {
    /// Seconds until `remaining` more trials are done: d·⌈T/D⌉.
    pub fn seconds_for(&self, remaining: u32) -> f64 {
        if self.devices == 0 {
            return 0.0;
        }
        self.trial_seconds * remaining.div_ceil(self.devices) as f64
    }
}

/// One playback run a backend is asked for.
#[derive(Debug, Clone)]
pub struct PlaybackJob {
    /// The session the trials belong to.
    pub session: String,
    /// A local file holding the recording (the blob store's).
    pub recording: PathBuf,
    /// A local folder for the job's working files (adb's pulled trials), the blob store's:
    /// it goes with the session.
    pub work_dir: PathBuf,
    /// The playback indices to run, in order (`indices_to_play`): a fresh session's are
    /// 0, 1, …; a resumed one's skip the trials already stored, whatever order they came in.
    pub indices: Vec<u32>,
    /// Set to stop early (adaptive stopping, estimate requested, shutdown).
    pub cancel: Arc<AtomicBool>,
}

/// The first `count` playback indices not in `stored`: a fresh session's are 0, 1, …; a
/// resumed one's skip what its phones already delivered, in whatever order they came (with
/// several phones, trial 3 may be stored before trial 2 when the server stops).
pub(crate) fn indices_to_play(stored: &BTreeSet<u32>, count: u32) -> Vec<u32> {
    (0..)
        .filter(|i| !stored.contains(i))
        .take(count as usize)
        .collect()
}

impl PlaybackJob {
    /// Whether the job should stop.
    pub fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// Sleeps `seconds`, waking early when cancelled; false if cancelled.
    pub fn sleep(&self, seconds: f64) -> bool {
        let deadline = Instant::now() + Duration::from_secs_f64(seconds.max(0.0));
        loop {
            if self.cancelled() {
                return false;
            }
            let now = Instant::now();
            if now >= deadline {
                return true;
            }
            std::thread::sleep((deadline - now).min(Duration::from_millis(20)));
        }
    }
}

/// A finished trial: its pose log as TUM text.
#[derive(Debug, Clone)]
pub struct TrialOutput {
    /// Playback index (deterministic for `sim`).
    pub index: u32,
    /// TUM text, one pose per frame.
    pub tum: String,
    /// Which device made it (e.g. `sim:0`, `adb:SERIAL`).
    pub source: String,
}

/// A playback device as `GET /v1/devices` lists it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct DeviceInfo {
    /// adb serial, or `sim:N`.
    pub serial: String,
    /// `device`, `offline`, `unauthorized`, `lost`, …
    pub state: String,
    /// The backend.
    pub backend: &'static str,
}

/// A way of turning a recording into trials. Blocking: the server runs
/// [`Playback::play`] on a blocking thread and hands every finished trial to
/// the job through `sink` as soon as it exists.
pub trait Playback: Send + Sync {
    /// `adb`, `sim` or `upload`.
    fn name(&self) -> &'static str;
    /// Checks the recording and says how long playback will take.
    fn plan(&self, recording: &Path, trials: u32) -> Result<PlaybackPlan, Error>;
    /// Runs the trials, calling `sink` for each as it finishes. Returns when
    /// all are done or the job is cancelled; an error leaves the trials
    /// already delivered valid.
    fn play(&self, job: &PlaybackJob, sink: &(dyn Fn(TrialOutput) + Sync)) -> Result<(), Error>;
    /// The devices this backend can use now.
    fn devices(&self) -> Vec<DeviceInfo> {
        Vec::new()
    }
}

/// Trials come from an outside SLAM run through `POST /v1/sessions/{id}/trials`.
#[derive(Debug, Default)]
pub struct UploadPlayback;

impl Playback for UploadPlayback {
    fn name(&self) -> &'static str {
        "upload"
    }
    fn plan(&self, _recording: &Path, _trials: u32) -> Result<PlaybackPlan, Error> {
        Ok(PlaybackPlan {
            trial_seconds: 0.0,
            devices: 0,
        })
    }
    fn play(&self, _job: &PlaybackJob, _sink: &(dyn Fn(TrialOutput) + Sync)) -> Result<(), Error> {
        Ok(())
    }
}

/// Replays a `sitar-sim` recording into SLAM-like trials in scaled real time,
/// on `devices` simulated phones.
#[derive(Debug, Clone)]
pub struct SimPlayback {
    config: SimConfig,
}

impl SimPlayback {
    /// A sim backend with the given speed and device count.
    pub fn new(config: SimConfig) -> SimPlayback {
        SimPlayback { config }
    }

    fn load(recording: &Path) -> Result<sitar_sim::Recording, Error> {
        crate::ingest::mp4_check::read_sim_recording(recording)
    }

    fn trial_seconds(&self, rec: &sitar_sim::Recording) -> f64 {
        rec.duration_s() / self.config.speed.max(1e-6)
    }
}

impl Playback for SimPlayback {
    fn name(&self) -> &'static str {
        "sim"
    }

    fn plan(&self, recording: &Path, _trials: u32) -> Result<PlaybackPlan, Error> {
        let rec = Self::load(recording)?;
        Ok(PlaybackPlan {
            trial_seconds: self.trial_seconds(&rec),
            devices: self.config.devices.max(1),
        })
    }

    fn play(&self, job: &PlaybackJob, sink: &(dyn Fn(TrialOutput) + Sync)) -> Result<(), Error> {
        let rec = Self::load(&job.recording)?;
        let seconds = self.trial_seconds(&rec);
        let next = AtomicU32::new(0);
        std::thread::scope(|scope| {
            for device in 0..self.config.devices.max(1) {
                let (rec, next) = (&rec, &next);
                scope.spawn(move || {
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed) as usize;
                        let Some(&index) = job.indices.get(i) else {
                            return;
                        };
                        if !job.sleep(seconds) {
                            return;
                        }
                        let trajectory = sitar_sim::play_trial(rec, index);
                        let mut tum = Vec::new();
                        if sitar_estimator::write_tum(&trajectory, &mut tum).is_ok() {
                            sink(TrialOutput {
                                index,
                                tum: String::from_utf8_lossy(&tum).into_owned(),
                                source: format!("sim:{device}"),
                            });
                        }
                    }
                });
            }
        });
        Ok(())
    }

    fn devices(&self) -> Vec<DeviceInfo> {
        (0..self.config.devices.max(1))
            .map(|i| DeviceInfo {
                serial: format!("sim:{i}"),
                state: "device".into(),
                backend: "sim",
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eta_follows_d_times_ceil_t_over_d() {
        let plan = PlaybackPlan {
            trial_seconds: 15.0,
            devices: 2,
        };
        assert_eq!(plan.seconds_for(5), 45.0);
        assert_eq!(plan.seconds_for(4), 30.0);
        assert_eq!(plan.seconds_for(0), 0.0);
        assert_eq!(
            PlaybackPlan {
                trial_seconds: 15.0,
                devices: 0
            }
            .seconds_for(3),
            0.0
        );
    }

    #[test]
    fn a_resumed_session_plays_the_indices_it_lacks() {
        assert_eq!(indices_to_play(&BTreeSet::new(), 3), vec![0, 1, 2]);
        let stored = BTreeSet::from([0, 1, 3]);
        assert_eq!(indices_to_play(&stored, 2), vec![2, 4]);
        assert!(indices_to_play(&stored, 0).is_empty());
    }

    /// The sim phones play exactly the job's indices, each trial the one of its index: a
    /// session resumed with trials 0, 1 and 3 stored gets 2 and 4, not 3 a second time.
    #[test]
    fn sim_phones_play_exactly_the_indices_of_the_job() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("recording.sitarsim");
        let rec = sitar_sim::Recording::demo(2.0, 10.0, 7).unwrap();
        std::fs::write(&path, rec.to_bytes()).unwrap();
        let playback = SimPlayback::new(SimConfig {
            speed: 1e6,
            devices: 2,
        });
        let job = PlaybackJob {
            session: "s".into(),
            recording: path,
            work_dir: dir.path().to_path_buf(),
            indices: indices_to_play(&BTreeSet::from([0, 1, 3]), 2),
            cancel: Arc::new(AtomicBool::new(false)),
        };
        let got = std::sync::Mutex::new(Vec::new());
        playback
            .play(&job, &|trial| got.lock().unwrap().push(trial))
            .unwrap();
        let mut got = got.into_inner().unwrap();
        got.sort_by_key(|t| t.index);
        assert_eq!(got.iter().map(|t| t.index).collect::<Vec<_>>(), vec![2, 4]);
        for trial in &got {
            let mut expected = Vec::new();
            sitar_estimator::write_tum(&sitar_sim::play_trial(&rec, trial.index), &mut expected)
                .unwrap();
            assert_eq!(trial.tum.as_bytes(), expected, "trial {}", trial.index);
        }
    }

    #[test]
    fn a_cancelled_job_stops_sleeping_at_once() {
        let job = PlaybackJob {
            session: "s".into(),
            recording: PathBuf::new(),
            work_dir: PathBuf::new(),
            indices: vec![0],
            cancel: Arc::new(AtomicBool::new(true)),
        };
        let started = Instant::now();
        assert!(!job.sleep(10.0));
        assert!(
            started.elapsed() < Duration::from_secs(2),
            "slept {:?} of 10 s",
            started.elapsed()
        );
    }
}
