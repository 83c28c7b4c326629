//! Background upload of a recording and download of the results: a worker
//! thread drives `sitar-client`; the app polls a snapshot and may cancel.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use serde::Deserialize;
use sitar_client::{Client, NewSession, SessionState};
use sitar_core::Session;

use crate::error::Error;
use crate::types::{SitarJobProgress, SitarJobState};

/// Share of the overall progress given to sending the recording.
const UPLOAD_SHARE: f64 = 0.2;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct UploadOptions {
    server_url: Option<String>,
    /// An existing server session to continue (e.g. after a failed job): no new session;
    /// its recording upload resumes, or is skipped once the server has it.
    session_id: Option<String>,
    trials: u32,
    setting: String,
    playback: String,
    poll_interval_ms: u64,
}

impl Default for UploadOptions {
    fn default() -> Self {
        UploadOptions {
            server_url: None,
            session_id: None,
            trials: 10,
            setting: sitar_core::DEFAULT_SETTING.to_owned(),
            playback: "adb".to_owned(),
            poll_interval_ms: 500,
        }
    }
}

#[derive(Default)]
struct JobStatus {
    progress: SitarJobProgress,
    message: String,
    server_id: String,
}

impl JobStatus {
    fn finished(&self) -> bool {
        self.progress.state >= SitarJobState::SITAR_JOB_DONE as i32
    }
}

/// State shared by the app-facing handle and the worker thread.
struct Shared {
    status: Mutex<JobStatus>,
    cancelled: AtomicBool,
    session: Arc<Mutex<Session>>,
}

impl Shared {
    /// Applies `f` unless the job already finished (e.g. was cancelled).
    fn update(&self, f: impl FnOnce(&mut JobStatus)) {
        let mut s = self.status.lock().unwrap_or_else(PoisonError::into_inner);
        if !s.finished() {
            f(&mut s);
        }
    }

    fn cancelled(&self) -> bool {
        self.cancelled.load(Ordering::Acquire)
    }

    /// Loads results into the session unless cancelled; the status lock is
    /// held so a concurrent cancel either wins entirely or comes after.
    fn load_results(
        &self,
        text: &str,
        trials: u32,
        final_state: Option<SitarJobState>,
    ) -> Result<(), Error> {
        let mut s = self.status.lock().unwrap_or_else(PoisonError::into_inner);
        if s.finished() {
            return Ok(());
        }
        self.session
            .lock()
            .map_err(|_| Error::Panic("the session was poisoned by an earlier panic".into()))?
            .load_results(text)?;
        s.progress.results_revision += 1;
        s.progress.results_trials = trials;
        if let Some(state) = final_state {
            s.progress.state = state as i32;
            s.progress.progress = 1.0;
            s.progress.eta_s = 0.0;
        }
        Ok(())
    }
}

/// A running (or finished) upload job.
pub(crate) struct UploadJob {
    shared: Arc<Shared>,
}

impl UploadJob {
    pub(crate) fn start(
        session: Arc<Mutex<Session>>,
        recording: &Path,
        options_json: &str,
        default_url: Option<String>,
    ) -> Result<UploadJob, Error> {
        let options: UploadOptions = if options_json.trim().is_empty() {
            UploadOptions::default()
        } else {
            serde_json::from_str(options_json)?
        };
        let url = options.server_url.clone().or(default_url).ok_or_else(|| {
            Error::invalid(
                "options_json",
                "no server_url in the upload options or the session config",
            )
        })?;
        let client = Client::new(&url)?;
        if options.trials < 2 {
            return Err(Error::invalid("options_json", "trials must be at least 2"));
        }
        if let Some(id) = &options.session_id {
            sitar_client::check_session_id(id)
                .map_err(|e| Error::invalid("options_json", format!("session_id: {e}")))?;
        }
        let shared = Arc::new(Shared {
            status: Mutex::new(JobStatus {
                progress: SitarJobProgress {
                    eta_s: -1.0,
                    trials_total: options.trials,
                    ..SitarJobProgress::default()
                },
                ..JobStatus::default()
            }),
            cancelled: AtomicBool::new(false),
            session,
        });
        let worker = Arc::clone(&shared);
        let recording = recording.to_path_buf();
        std::thread::Builder::new()
            .name("sitar-upload".into())
            .spawn(move || {
                let outcome = crate::guard::catch(|| run(&worker, &client, &recording, &options));
                if let Err(e) = outcome {
                    log::warn!("upload failed: {e}");
                    worker.update(|s| {
                        s.progress.state = SitarJobState::SITAR_JOB_FAILED as i32;
                        s.progress.error_code = e.code();
                        s.message = e.to_string();
                    });
                }
            })
            .map_err(|source| Error::Io {
                context: "cannot start the upload thread".into(),
                source,
            })?;
        Ok(UploadJob { shared })
    }

    pub(crate) fn progress(&self) -> SitarJobProgress {
        self.shared
            .status
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .progress
    }

    pub(crate) fn message(&self) -> String {
        self.shared
            .status
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .message
            .clone()
    }

    pub(crate) fn server_id(&self) -> String {
        self.shared
            .status
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .server_id
            .clone()
    }

    pub(crate) fn cancel(&self) {
        self.shared.cancelled.store(true, Ordering::Release);
        self.shared
            .update(|s| s.progress.state = SitarJobState::SITAR_JOB_CANCELLED as i32);
    }
}

/// Sends the recording (resuming what the server kept of an earlier attempt); a cancel
/// stops the transfer itself, not only what comes after it.
fn send_recording(
    shared: &Shared,
    client: &Client,
    id: &str,
    recording: &Path,
) -> Result<(), Error> {
    set_state(shared, SitarJobState::SITAR_JOB_UPLOADING);
    let trace = crate::trace::section("sitar upload recording");
    let sent = client.upload_recording_cancellable(
        id,
        recording,
        &mut |sent, total| {
            shared.update(|s| {
                s.progress.bytes_sent = sent;
                s.progress.bytes_total = total;
                // `bytes_sent` tells the truth (a resumed retry starts at the kept offset,
                // below what was sent before); `progress` only grows, for progress bars.
                let share = if total == 0 {
                    0.0
                } else {
                    UPLOAD_SHARE * sent as f64 / total as f64
                };
                s.progress.progress = s.progress.progress.max(share);
            });
        },
        &shared.cancelled,
    );
    drop(trace);
    match sent {
        Err(sitar_client::Error::Cancelled) => Ok(()),
        other => Ok(other?),
    }
}

fn set_state(shared: &Shared, state: SitarJobState) {
    shared.update(|s| s.progress.state = state as i32);
}

/// The worker: create, upload, estimate, poll (loading progressive results), download.
fn run(shared: &Shared, client: &Client, recording: &Path, o: &UploadOptions) -> Result<(), Error> {
    let (id, playback, upload) = match &o.session_id {
        None => {
            let id = client.create_session(&NewSession {
                trials: o.trials,
                setting: o.setting.clone(),
                playback: o.playback.clone(),
            })?;
            (id, o.playback.clone(), true)
        }
        Some(id) => {
            let st = client.status(id)?;
            let playback = st.playback.unwrap_or_else(|| o.playback.clone());
            shared.update(|s| s.progress.trials_total = st.trials_total);
            (id.clone(), playback, st.state == SessionState::Created)
        }
    };
    log::info!("upload: server session {id}");
    shared.update(|s| s.server_id = id.clone());
    if shared.cancelled() {
        return Ok(());
    }
    if upload {
        send_recording(shared, client, &id, recording)?;
    } else {
        // The server already has the whole recording.
        let size = std::fs::metadata(recording).map(|m| m.len()).unwrap_or(0);
        shared.update(|s| {
            s.progress.bytes_sent = size;
            s.progress.bytes_total = size;
            s.progress.progress = UPLOAD_SHARE;
        });
    }
    if shared.cancelled() {
        return Ok(());
    }
    set_state(shared, SitarJobState::SITAR_JOB_PLAYING);
    // With "adb"/"sim" the server plays and estimates on its own (asking for an
    // estimate would cut playback short). With "upload" the playback devices
    // send their trials; once all are there, this job asks for the estimate.
    let mut estimate_requested = playback != "upload";
    let mut loaded_trials = 0;
    loop {
        if shared.cancelled() {
            return Ok(());
        }
        let st = client.status(&id)?;
        shared.update(|s| {
            s.progress.trials_done = st.trials_done;
            s.progress.trials_total = st.trials_total;
            s.progress.eta_s = st.eta_s.unwrap_or(-1.0);
            s.progress.progress = UPLOAD_SHARE + (1.0 - UPLOAD_SHARE) * st.progress.clamp(0.0, 1.0);
            s.progress.state = match st.state {
                SessionState::Estimating => SitarJobState::SITAR_JOB_ESTIMATING,
                SessionState::Done => SitarJobState::SITAR_JOB_DOWNLOADING,
                _ => SitarJobState::SITAR_JOB_PLAYING,
            } as i32;
        });
        match st.state {
            SessionState::Done => break,
            SessionState::Failed => {
                return Err(Error::InvalidState(format!(
                    "the server failed session {id}: {}",
                    st.error.as_deref().unwrap_or("no reason given")
                )));
            }
            _ => {}
        }
        if !estimate_requested && st.trials_total >= 2 && st.trials_done >= st.trials_total {
            client.start_estimate(&id)?;
            estimate_requested = true;
        }
        if st.results_trials > loaded_trials {
            // Progressive results: a failure here is not fatal, the final fetch decides.
            match client.results_json(&id) {
                Ok(text) => {
                    if shared.load_results(&text, st.results_trials, None).is_ok() {
                        loaded_trials = st.results_trials;
                    }
                }
                Err(e) => log::debug!("progressive results not available yet: {e}"),
            }
        }
        sleep_unless_cancelled(shared, Duration::from_millis(o.poll_interval_ms.max(10)));
    }
    let text = match client.results_json(&id) {
        Ok(text) => text,
        Err(e) => {
            log::warn!("results.json failed ({e}); trying results.csv");
            client.results_csv(&id)?
        }
    };
    let trials = client
        .status(&id)
        .map(|s| s.results_trials.max(s.trials_done))
        .unwrap_or(0);
    shared.load_results(&text, trials, Some(SitarJobState::SITAR_JOB_DONE))?;
    log::info!("upload: results of {id} loaded");
    Ok(())
}

fn sleep_unless_cancelled(shared: &Shared, total: Duration) {
    let step = Duration::from_millis(20);
    let mut slept = Duration::ZERO;
    while slept < total && !shared.cancelled() {
        std::thread::sleep(step.min(total - slept));
        slept += step;
    }
}
