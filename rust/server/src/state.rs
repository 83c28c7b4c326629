use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use crate::Error;
use crate::adb::AdbPlayback;
use crate::config::ServerConfig;
use crate::db::Db;
use crate::files::Files;
use crate::playback::{Playback, PlaybackPlan, SimPlayback, UploadPlayback};

/// What a running job knows that the database does not: timing and the cancel flag.
#[derive(Debug, Clone)]
pub(crate) struct Live {
    pub cancel: Arc<AtomicBool>,
    pub plan: Option<PlaybackPlan>,
    pub started: Instant,
    /// Trials stored before this run started (resume after restart).
    pub done_before: u32,
    /// Trials this run plays.
    pub needed: u32,
}

/// Everything the routes and jobs share.
pub(crate) struct Shared {
    pub config: ServerConfig,
    pub db: Db,
    pub files: Files,
    sim: Arc<dyn Playback>,
    adb: Arc<dyn Playback>,
    upload: Arc<dyn Playback>,
    pub live: Mutex<HashMap<String, Live>>,
    /// Per session: held by a request while it writes into the session's folder (a
    /// recording or its kept prefix, a trial, timestamps) or deletes the session.
    session_locks: Mutex<HashMap<String, Arc<tokio::sync::Mutex<()>>>>,
    /// Set when the server stops: jobs stop without changing their session's
    /// state, so the next start resumes them.
    pub shutdown: AtomicBool,
}

impl Shared {
    pub fn open(config: ServerConfig) -> Result<Shared, Error> {
        let files = Files::open(&config.data_dir)?.with_idle_timeout(config.upload_idle_timeout);
        let db = Db::open(&config.data_dir.join("sitar.db"))?;
        Ok(Shared {
            sim: Arc::new(SimPlayback::new(config.sim.clone())),
            adb: Arc::new(AdbPlayback::new(config.adb.clone())),
            upload: Arc::new(UploadPlayback),
            config,
            db,
            files,
            live: Mutex::new(HashMap::new()),
            session_locks: Mutex::new(HashMap::new()),
            shutdown: AtomicBool::new(false),
        })
    }

    pub fn backend(&self, name: &str) -> Result<Arc<dyn Playback>, Error> {
        match name {
            "sim" => Ok(self.sim.clone()),
            "adb" => Ok(self.adb.clone()),
            "upload" => Ok(self.upload.clone()),
            other => Err(Error::BadRequest(format!(
                "unknown playback {other:?}: expected adb, sim or upload"
            ))),
        }
    }

    pub fn live(&self, id: &str) -> Option<Live> {
        self.live.lock().ok().and_then(|m| m.get(id).cloned())
    }

    pub fn set_live(&self, id: &str, live: Option<Live>) {
        if let Ok(mut m) = self.live.lock() {
            match live {
                Some(l) => {
                    m.insert(id.to_string(), l);
                }
                None => {
                    m.remove(id);
                }
            }
        }
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
        if let Ok(m) = self.live.lock() {
            for live in m.values() {
                live.cancel.store(true, Ordering::SeqCst);
            }
        }
    }

    pub fn stopping(&self) -> bool {
        self.shutdown.load(Ordering::SeqCst)
    }
}
