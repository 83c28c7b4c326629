//! What an upload job is asked to do and what it reports: its options, its state and
//! progress, and the state its handle ([`crate::UploadJob`]) and its worker
//! (`job_run`) share.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::Duration;

use crate::{Error, NewSession, SessionFrame, check_session_id};

/// What an [`crate::UploadJob`] does.
#[derive(Debug, Clone, PartialEq)]
pub struct JobOptions {
    /// The server session to create (trials, statistic, playback, window settings). Ignored
    /// when [`JobOptions::session_id`] is set: that session's own settings hold.
    pub session: NewSession,
    /// An existing server session to continue (e.g. a failed job's
    /// [`crate::UploadJob::server_id`]): no new session is created, its recording upload resumes
    /// from the bytes the server kept, or is skipped once the server has it all.
    pub session_id: Option<String>,
    /// How often the server's status is asked for while it works (at least 10 ms).
    pub poll_interval: Duration,
    /// The phone's session folder (as sitar-core's `Session::save` writes it). Before the
    /// recording, its log (`trajectory.txt`, `subtrajectories.csv`, `anchors.csv`:
    /// [`crate::Client::upload_phone_logs`]) is sent: a file the server refuses fails the job, a
    /// backend without the routes (404/405) is skipped with a warning. After the recording,
    /// its evidence (`evidence.csv`, `thumbnails/`) is sent when it is there: a folder without
    /// evidence, or an evidence upload that fails after its retries, never fails the job.
    pub evidence_dir: Option<PathBuf>,
    /// The phone's convention and the venue the new session joins (sent with the session
    /// request only when set). Ignored with [`JobOptions::session_id`].
    pub frame: SessionFrame,
}

impl JobOptions {
    /// A job that creates `session`, polling every 500 ms.
    pub fn new(session: NewSession) -> Self {
        JobOptions {
            session,
            session_id: None,
            poll_interval: Duration::from_millis(500),
            evidence_dir: None,
            frame: SessionFrame::default(),
        }
    }

    /// Checks what can be checked before anything is sent.
    pub(crate) fn validate(&self) -> Result<(), Error> {
        match &self.session_id {
            Some(id) => check_session_id(id).map(drop).map_err(|_| {
                Error::InvalidArgument(format!(
                    "session_id {id:?} is not a server-made id ([A-Za-z0-9_-], 1 to 64 bytes)"
                ))
            }),
            None if self.session.trials < 2 => Err(Error::InvalidArgument(format!(
                "trials must be at least 2 (an estimate compares pairs of trials), not {}",
                self.session.trials
            ))),
            None => Ok(()),
        }
    }
}

/// Where a job is; the order is the life cycle (`Done`, `Failed` and `Cancelled` are final).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub enum JobState {
    /// Creating (or looking up) the server session.
    #[default]
    Starting,
    /// Sending the recording.
    Uploading,
    /// Playback trials running on the server.
    Playing,
    /// The server computes the final estimate.
    Estimating,
    /// Fetching the final results.
    Downloading,
    /// The final results were delivered.
    Done,
    /// Failed: [`JobProgress::error`] says why.
    Failed,
    /// Cancelled by [`crate::UploadJob::cancel`] (or by dropping the job).
    Cancelled,
}

impl JobState {
    /// Whether the job will not change any more.
    pub fn is_finished(self) -> bool {
        self >= JobState::Done
    }
}

/// What a results sink may fail with (any error: the job keeps it as [`Error::Results`]).
pub type SinkError = Box<dyn std::error::Error + Send + Sync>;

/// A snapshot of a job.
#[derive(Debug, Clone, Default)]
pub struct JobProgress {
    /// Where the job is.
    pub state: JobState,
    /// Overall progress 0 … 1 (sending the recording is the first [`UPLOAD_SHARE`]); it never
    /// goes back, also when a resumed upload restarts below an earlier byte count.
    pub progress: f64,
    /// Seconds until done as the server estimates them, when it does.
    pub eta_s: Option<f64>,
    /// Recording bytes sent so far (a resume restarts at what the server kept).
    pub bytes_sent: u64,
    /// Recording size in bytes.
    pub bytes_total: u64,
    /// Playback trials finished on the server.
    pub trials_done: u32,
    /// Playback trials planned.
    pub trials_total: u32,
    /// How many times results were delivered to the sink (progressive and final).
    pub results_revision: u32,
    /// Trials behind the results delivered last (0 = none yet).
    pub results_trials: u32,
    /// How many files of the phone's log ([`crate::PHONE_LOG_FILES`]) the server took (0
    /// without [`JobOptions::evidence_dir`], or from a backend that predates them).
    pub logs_sent: u32,
    /// Whether the session folder's evidence reached the server (false without
    /// [`JobOptions::evidence_dir`], without evidence in it, or when its upload failed).
    pub evidence_sent: bool,
    /// Why the job failed, once it has: a client error, [`Error::SessionFailed`],
    /// [`Error::Results`] (the sink refused the final results) or [`Error::Panicked`].
    pub error: Option<Arc<Error>>,
}

/// Share of [`JobProgress::progress`] given to sending the recording; the server's work is
/// the rest.
pub const UPLOAD_SHARE: f64 = 0.2;

/// The job's state, shared by the handle and the worker thread.
pub(crate) struct Shared {
    status: Mutex<Status>,
    pub(crate) cancelled: AtomicBool,
}

pub(crate) struct Status {
    pub(crate) progress: JobProgress,
    pub(crate) server_id: Option<String>,
}

impl Shared {
    /// A job not started yet, expecting `trials_total` trials.
    pub(crate) fn new(trials_total: u32) -> Self {
        Shared {
            status: Mutex::new(Status {
                progress: JobProgress {
                    trials_total,
                    ..JobProgress::default()
                },
                server_id: None,
            }),
            cancelled: AtomicBool::new(false),
        }
    }

    pub(crate) fn lock(&self) -> MutexGuard<'_, Status> {
        self.status.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Applies `f` to the progress unless the job already finished (e.g. was cancelled).
    pub(crate) fn update(&self, f: impl FnOnce(&mut JobProgress)) {
        let mut s = self.lock();
        if !s.progress.state.is_finished() {
            f(&mut s.progress);
        }
    }

    pub(crate) fn set_state(&self, state: JobState) {
        self.update(|p| p.state = state);
    }

    pub(crate) fn set_server_id(&self, id: &str) {
        self.lock().server_id = Some(id.to_owned());
    }

    pub(crate) fn is_cancelled(&self) -> bool {
        self.cancelled.load(Ordering::Acquire)
    }

    /// Hands `text` to `sink` unless the job finished; the status lock is held throughout,
    /// so a concurrent cancel either wins entirely (nothing delivered) or comes after.
    /// `done` finishes the job with these results. Returns whether they were delivered.
    pub(crate) fn deliver(
        &self,
        sink: &mut dyn FnMut(&str) -> Result<(), SinkError>,
        text: &str,
        trials: u32,
        done: bool,
    ) -> Result<bool, SinkError> {
        let mut s = self.lock();
        if s.progress.state.is_finished() {
            return Ok(false);
        }
        sink(text)?;
        let p = &mut s.progress;
        p.results_revision += 1;
        p.results_trials = trials;
        if done {
            p.state = JobState::Done;
            p.progress = 1.0;
            p.eta_s = Some(0.0);
        }
        Ok(true)
    }

    pub(crate) fn fail(&self, error: Error) {
        self.update(|p| {
            p.state = JobState::Failed;
            p.error = Some(Arc::new(error));
        });
    }
}
