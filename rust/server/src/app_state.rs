//! What the handlers and jobs share: configuration, storage, live sessions, running jobs,
//! the playback backends and the per-session write locks.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use crate::config::ServerConfig;
use crate::error::Error;
use crate::estimate::live_sessions::LiveSessions;
use crate::model::{NewSession, NewVenue, PlaybackKind, Session, new_venue_id};
use crate::playback::adb::AdbPlayback;
use crate::playback::queue::{PlaybackQueue, QueueLimits};
use crate::playback::remote::{RemoteBoard, RemotePlayback};
use crate::playback::{Playback, PlaybackPlan, SimPlayback, UploadPlayback};
use crate::session::Lifecycle;
use crate::storage::BlobStore;
use crate::storage::{MetadataStore, WorkerStore};

/// What a running job knows that the database does not: timing and the cancel flag.
#[derive(Debug, Clone)]
pub(crate) struct RunningJob {
    pub cancel: Arc<AtomicBool>,
    pub plan: Option<PlaybackPlan>,
    /// When the job started (ms since the epoch: other instances read it,
    /// `jobs::progress_view`).
    pub started_ms: i64,
    /// Trials stored before this run started (resume after restart).
    pub done_before: u32,
    /// Trials this run plays.
    pub needed: u32,
}

/// Everything the routes and jobs share.
pub(crate) struct App {
    pub config: ServerConfig,
    /// Every row the server keeps (the embedded default: SQLite in `DATA/sitar.db`).
    pub db: Arc<dyn MetadataStore>,
    /// Playback hosts, their phones, the trials leased to them, failed trials.
    pub workers: Arc<dyn WorkerStore>,
    /// Where trials uploaded by playback hosts meet their session's job.
    pub board: Arc<RemoteBoard>,
    /// Every byte the server keeps for its sessions (the embedded default: the data
    /// directory's session folders).
    pub blobs: Arc<dyn BlobStore>,
    /// Per-token counters of sessions created and bytes uploaded.
    pub limiter: Arc<crate::auth::UploadLimiter>,
    /// Whether the page cookie carries `Secure` (served over TLS).
    pub secure_cookies: bool,
    /// The TLS certificate's SHA-256 fingerprint (`AB:CD:…`), shown on the overview page.
    pub tls_fingerprint: Option<String>,
    /// Parsed trials of the sessions in flight.
    pub live: LiveSessions,
    /// Sim and adb sessions waiting for, or held by, a playback worker.
    pub queue: PlaybackQueue,
    /// One permit per estimate worker: `upload` sessions' estimates run within it.
    pub estimates: tokio::sync::Semaphore,
    /// One permit per answer built from a session's scene at once (report, `scene.glb`,
    /// `scene.json`, a rebuilt trajectory; `http::helpers::rendering`): as many as estimate
    /// workers, so however many clients ask, a long walk's answers are in memory only that
    /// many times at once (the others wait their turn; the work is CPU-bound anyway).
    pub renders: tokio::sync::Semaphore,
    /// This instance's id (`DATA/instance.id`): which sessions in flight it plays.
    pub instance: String,
    sim: Arc<dyn Playback>,
    adb: Arc<dyn Playback>,
    upload: Arc<dyn Playback>,
    running: Mutex<HashMap<String, RunningJob>>,
    /// Per session: held by a request while it writes into the session's folder (a
    /// recording or its kept prefix, a trial, timestamps) or deletes the session.
    session_locks: Mutex<HashMap<String, Arc<tokio::sync::Mutex<()>>>>,
    /// Set when the server stops: jobs stop without changing their session's
    /// state, so the next start resumes them.
    shutdown: AtomicBool,
}

impl App {
    pub fn open(config: ServerConfig) -> Result<App, Error> {
        config.check_delete_sweep()?;
        let (db, blobs, workers) =
            crate::storage::open::open(&crate::storage::open::StoreSettings {
                data_dir: &config.data_dir,
                database: config.database.as_deref(),
                store: config.store.as_deref(),
                upload_idle_timeout: config.upload_idle_timeout,
                session_disk_quota: config.session_disk_quota,
                disk_quota: config.disk_quota,
            })?;
        let instance = crate::storage::instance::instance_id(&config.data_dir)?;
        let board = Arc::new(RemoteBoard::default());
        let local_sim: Arc<dyn Playback> = Arc::new(SimPlayback::new(config.sim.clone()));
        let local_adb: Arc<dyn Playback> = Arc::new(AdbPlayback::new(config.adb.clone()));
        // `--playback-workers 0`: the phones are on playback hosts, not here.
        let (sim, adb) = if config.playback_workers == 0 {
            let remote = |kind, local: Arc<dyn Playback>| -> Arc<dyn Playback> {
                Arc::new(
                    RemotePlayback::new(
                        kind,
                        local,
                        workers.clone(),
                        db.clone(),
                        board.clone(),
                        config.lease_timeout,
                        config.adb.fallback_duration_s,
                    )
                    .for_instance(config.database.is_some().then(|| instance.clone())),
                )
            };
            (
                remote(PlaybackKind::Sim, local_sim),
                remote(PlaybackKind::Adb, local_adb),
            )
        } else {
            (local_sim, local_adb)
        };
        Ok(App {
            sim,
            adb,
            workers,
            board,
            upload: Arc::new(UploadPlayback),
            limiter: Arc::new(crate::auth::UploadLimiter::new(config.limits)),
            secure_cookies: false,
            tls_fingerprint: None,
            live: LiveSessions::new(config.live_session_bytes, config.live_total_bytes),
            queue: PlaybackQueue::new(QueueLimits {
                per_owner: config.jobs_per_token,
                max_waiting: config.max_queued,
            }),
            estimates: tokio::sync::Semaphore::new(config.estimate_workers.max(1)),
            renders: tokio::sync::Semaphore::new(config.estimate_workers.max(1)),
            instance,
            config,
            db,
            blobs,
            running: Mutex::new(HashMap::new()),
            session_locks: Mutex::new(HashMap::new()),
            shutdown: AtomicBool::new(false),
        })
    }

    /// Both stores, borrowed.
    pub fn stores(&self) -> crate::storage::StoreRefs<'_> {
        crate::storage::StoreRefs {
            db: &*self.db,
            blobs: &*self.blobs,
        }
    }

    /// The transitions of this server's sessions.
    pub fn lifecycle(&self) -> Lifecycle<'_> {
        Lifecycle::new(&*self.db)
    }

    /// Session `id`, or a 404 (an id the server cannot have made is never looked up).
    pub fn session(&self, id: &str) -> Result<Session, Error> {
        if !crate::storage::files::is_server_id(id) {
            return Err(Error::NotFound(format!("no session {id:?}")));
        }
        self.db
            .session(id)?
            .ok_or_else(|| Error::NotFound(format!("no session {id:?}")))
    }

    /// Makes a session's row and folder; with an idempotency key seen before, returns the
    /// earlier session (the bool is false).
    pub fn create_session(&self, new: &NewSession<'_>) -> Result<(String, bool), Error> {
        let (id, created) = self
            .db
            .insert_session(&crate::storage::files::new_id(), new)?;
        self.blobs.create_session(&id)?;
        Ok((id, created))
    }

    /// Makes a venue's row; its id.
    pub fn create_venue(&self, new: &NewVenue<'_>) -> Result<String, Error> {
        let id = new_venue_id(&crate::storage::files::new_id());
        self.db.insert_venue(&id, new)?;
        Ok(id)
    }

    pub fn backend(&self, kind: PlaybackKind) -> Arc<dyn Playback> {
        match kind {
            PlaybackKind::Sim => self.sim.clone(),
            PlaybackKind::Adb => self.adb.clone(),
            PlaybackKind::Upload => self.upload.clone(),
        }
    }

    fn running_jobs(&self) -> std::sync::MutexGuard<'_, HashMap<String, RunningJob>> {
        self.running.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The job running on session `id`, if one does.
    pub fn running(&self, id: &str) -> Option<RunningJob> {
        self.running_jobs().get(id).cloned()
    }

    /// Every job running here, by session id.
    pub fn running_all(&self) -> Vec<(String, RunningJob)> {
        let jobs = self.running_jobs();
        jobs.iter()
            .map(|(id, job)| (id.clone(), job.clone()))
            .collect()
    }

    pub fn set_running(&self, id: &str, job: Option<RunningJob>) {
        let mut jobs = self.running_jobs();
        match job {
            Some(job) => jobs.insert(id.to_string(), job),
            None => jobs.remove(id),
        };
    }

    /// The lock over session `id`'s folder: writers hold it, and a delete waits for them.
    pub fn session_lock(&self, id: &str) -> Arc<tokio::sync::Mutex<()>> {
        let mut locks = self.session_locks.lock().unwrap_or_else(|e| e.into_inner());
        locks.entry(id.to_string()).or_default().clone()
    }

    /// Forgets a deleted session's lock.
    pub fn forget_session_lock(&self, id: &str) {
        let mut locks = self.session_locks.lock().unwrap_or_else(|e| e.into_inner());
        locks.remove(id);
    }

    /// Stops every job; their sessions stay in flight for the next start.
    pub fn stop_all(&self) {
        self.shutdown.store(true, Ordering::SeqCst);
        self.queue.close();
        self.estimates.close();
        for job in self.running_jobs().values() {
            job.cancel.store(true, Ordering::SeqCst);
        }
    }

    /// Whether sim and adb sessions are played by remote hosts (`--playback-workers 0`).
    pub fn remote_playback(&self) -> bool {
        self.config.playback_workers == 0
    }

    pub fn stopping(&self) -> bool {
        self.shutdown.load(Ordering::SeqCst)
    }

    /// Whether other instances may share the database (`--database`): then instances
    /// heartbeat, adopt the sessions of dead ones and pass stop requests through it.
    pub fn clustered(&self) -> bool {
        self.config.database.is_some()
    }

    /// The oldest heartbeat (ms since the epoch) of an instance counted alive now. Alone on
    /// its data directory (the embedded default) no other instance plays anything, so any
    /// other instance counts as dead, as when one process held every session.
    pub fn alive_since_ms(&self) -> i64 {
        if !self.clustered() {
            return i64::MAX;
        }
        let timeout = i64::try_from(self.config.instance_timeout.as_millis()).unwrap_or(i64::MAX);
        crate::storage::now_ms().saturating_sub(timeout)
    }
}
