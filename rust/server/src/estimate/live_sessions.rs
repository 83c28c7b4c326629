//! Live sessions: the parsed trials of every session in flight, held in memory with the
//! estimator's state, so that each progressive estimate adds only the new trials' pairs and
//! never re-reads a file (`held_trials.rs`).
//!
//! **Memory.** A trial costs 64 bytes a pose (an `i64` stamp, a `DVec3` position, a `DQuat`
//! orientation) plus about 100 bytes: 2 820 poses are 180 kB, 100 such trials 18 MB. The
//! incremental state (every window's pair values, sums and cursors; the pairwise index and
//! relative poses) comes on top, as `IncrementalEstimate::memory_bytes` reports it: about
//! 155 MB more for 100 × 2 820 poses with 10-frame windows (it grows with the square of the
//! trial count). [`ServerConfig::live_session_bytes`](crate::config::ServerConfig::live_session_bytes)
//! bounds one session (default 256 MiB), [`ServerConfig::live_total_bytes`](crate::config::ServerConfig::live_total_bytes)
//! all of them together (default 1 GiB), trials and state alike. A trial that would pass
//! either is refused before anything of it is stored; state growth is counted after each
//! push (one push adds one trial's pairs), and when it passes a bound the state is dropped
//! and the session goes on with one-shot estimates (whose working memory, under 60 MB for
//! 100 × 2 820 poses, is only held while one runs). A live session is dropped, and its bytes
//! freed, when the session finishes, fails or is deleted; after a restart it is rebuilt
//! from the trial files when the session next needs it (its state with the next estimate).
//!
//! **Estimates.** One estimate of a session runs at a time ([`LiveSession::publish`]); trials
//! that arrive meanwhile wait in an inbox and join the next one together, in playback order.
//!
//! **The walk.** A session whose calibration has a model for one run holds the phone's walk
//! (`walk.txt`, [`LiveSession::set_walk`]) as its live run: counted in the bounds like a
//! trial (it is one: every frame of the recording), counted as one of the results' runs, and
//! enough for results on its own (`held_trials.rs`). Other sessions do not hold it.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use sitar_core::Thresholds;
use sitar_estimator::Trajectory;

use crate::error::Error;
use crate::estimate::calibrations::SessionCalibration;
use crate::estimate::held_trials::{Held, HeldTrials, Purpose, StateBudget, trial_bytes};
use crate::estimate::publishing::Published;
use crate::model::estimate_settings::EstimateSettings;

/// The live sessions of one server, with the memory bound over them all.
pub(crate) struct LiveSessions {
    sessions: Mutex<HashMap<String, Arc<LiveSession>>>,
    budget: Arc<Budget>,
}

/// Bytes held, against the two bounds.
#[derive(Debug)]
struct Budget {
    total: AtomicUsize,
    total_limit: usize,
    session_limit: usize,
}

impl LiveSessions {
    pub fn new(session_limit: usize, total_limit: usize) -> LiveSessions {
        LiveSessions {
            sessions: Mutex::new(HashMap::new()),
            budget: Arc::new(Budget {
                total: AtomicUsize::new(0),
                total_limit,
                session_limit,
            }),
        }
    }

    fn map(&self) -> std::sync::MutexGuard<'_, HashMap<String, Arc<LiveSession>>> {
        self.sessions.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The live session `id`, if it is in memory.
    pub fn get(&self, id: &str) -> Option<Arc<LiveSession>> {
        self.map().get(id).cloned()
    }

    /// The live session `id`, made with `trials` (its stored trials, as (playback index,
    /// storage index, trial)) when it is not in memory. `published` is the trial count of
    /// its latest published results; `calibration` what its estimates are calibrated with.
    /// Another request's session made meanwhile wins.
    pub fn get_or_insert(
        &self,
        id: &str,
        settings: EstimateSettings,
        calibration: SessionCalibration,
        thresholds: Thresholds,
        published: u32,
        trials: impl FnOnce() -> Result<Vec<(u32, u32, Trajectory)>, Error>,
    ) -> Result<Arc<LiveSession>, Error> {
        if let Some(live) = self.get(id) {
            return Ok(live);
        }
        let live = Arc::new(LiveSession {
            id: id.to_string(),
            settings,
            calibration,
            thresholds,
            inbox: Mutex::new(Vec::new()),
            held: Arc::new(tokio::sync::Mutex::new(HeldTrials::new(&settings))),
            bytes: AtomicUsize::new(0),
            budget: self.budget.clone(),
            published: AtomicU32::new(published),
            walk: Mutex::new(None),
            published_walk: AtomicU64::new(0),
            walk_restored: AtomicBool::new(false),
            closed: AtomicBool::new(false),
            worker: AtomicBool::new(false),
        });
        for (play_index, index, trial) in trials()? {
            let reservation = live.reserve(trial_bytes(&trial))?;
            live.add(play_index, index, trial, reservation);
        }
        Ok(self.map().entry(id.to_string()).or_insert(live).clone())
    }

    /// Drops session `id`'s trials (it finished, failed or was deleted). An estimate still
    /// running finishes on its own copy of the handle and publishes nothing more.
    pub fn remove(&self, id: &str) {
        if let Some(live) = self.map().remove(id) {
            live.closed.store(true, Ordering::SeqCst);
        }
    }

    /// Bytes held by every live session.
    pub fn held_bytes(&self) -> usize {
        self.budget.total.load(Ordering::SeqCst)
    }
}

/// The trials of one session in flight.
pub(crate) struct LiveSession {
    id: String,
    settings: EstimateSettings,
    /// Every estimate published is calibrated with it (or says that it is missing).
    calibration: SessionCalibration,
    thresholds: Thresholds,
    /// Trials that arrived since an estimate last took them.
    inbox: Mutex<Vec<Held>>,
    /// Every other trial, in playback order, with the estimator state; locked by the one
    /// estimate that runs.
    held: Arc<tokio::sync::Mutex<HeldTrials>>,
    /// Bytes of this session's trials (inbox and held) and estimator state.
    bytes: AtomicUsize,
    budget: Arc<Budget>,
    /// Runs of the latest published estimate (its trials, and the walk when it had one).
    published: AtomicU32,
    /// The phone's walk, when this session uses it, with its version (0: the one stored
    /// before a restart; each [`LiveSession::set_walk`] counts up) and its bytes (counted).
    walk: Mutex<Option<HeldWalk>>,
    /// The walk version of the latest published estimate.
    published_walk: AtomicU64,
    /// Whether the stored walk was looked for (once, when the session is made).
    walk_restored: AtomicBool,
    /// Set when the session no longer needs estimates.
    closed: AtomicBool,
    /// A background worker publishes progressive estimates (`upload` sessions).
    worker: AtomicBool,
}

/// The walk a live session holds.
#[derive(Clone)]
struct HeldWalk {
    version: u64,
    run: Arc<Trajectory>,
    bytes: usize,
}

/// Why a session does not use the phone's walk, if it does not: it needs a calibration with a
/// model for one run, and a walk of at least one window.
pub(crate) fn walk_unused(
    calibration: &SessionCalibration,
    window_frames: usize,
    walk: &Trajectory,
) -> Option<String> {
    match calibration {
        SessionCalibration::None => {
            Some("the session has no calibration: its results come from the replays".into())
        }
        SessionCalibration::Missing(name) => Some(format!(
            "calibration {name} is not on this server: the results come from the replays"
        )),
        SessionCalibration::Apply { name, calibration } => {
            if let Err(e) = calibration.model(sitar_core::calibration::Target::Live, 1) {
                Some(format!("calibration {name}: {e}"))
            } else if walk.len() <= window_frames {
                Some(format!(
                    "the walk has {} poses: a window needs {}",
                    walk.len(),
                    window_frames + 1
                ))
            } else {
                None
            }
        }
    }
}

/// Memory counted for a trial that is about to be stored; given back unless the trial is
/// added.
pub(crate) struct Reservation<'a> {
    live: &'a LiveSession,
    bytes: usize,
}

impl Drop for Reservation<'_> {
    fn drop(&mut self) {
        self.live.release(self.bytes);
    }
}

impl LiveSession {
    /// Counts `bytes` against this session's bound and the server's; refused (nothing
    /// counted) when either would be passed.
    pub fn reserve(&self, bytes: usize) -> Result<Reservation<'_>, Error> {
        let limit = self.budget.session_limit;
        let mine = self.bytes.fetch_add(bytes, Ordering::SeqCst) + bytes;
        if mine > limit {
            self.bytes.fetch_sub(bytes, Ordering::SeqCst);
            return Err(Error::TooLarge {
                what: "the session's trials in memory",
                limit: limit as u64,
            });
        }
        let limit = self.budget.total_limit;
        let all = self.budget.total.fetch_add(bytes, Ordering::SeqCst) + bytes;
        if all > limit {
            self.budget.total.fetch_sub(bytes, Ordering::SeqCst);
            self.bytes.fetch_sub(bytes, Ordering::SeqCst);
            return Err(Error::Busy(format!(
                "the live sessions' trials would take more than the server's {limit} bytes \
                 of memory; try again when sessions have finished"
            )));
        }
        Ok(Reservation { live: self, bytes })
    }

    fn release(&self, bytes: usize) {
        self.bytes.fetch_sub(bytes, Ordering::SeqCst);
        self.budget.total.fetch_sub(bytes, Ordering::SeqCst);
    }

    /// Keeps a stored trial for the next estimate.
    pub fn add(
        &self,
        play_index: u32,
        index: u32,
        trial: Trajectory,
        reservation: Reservation<'_>,
    ) {
        // The bytes stay counted until the session is dropped.
        std::mem::forget(reservation);
        let held = Held {
            order: (play_index, index),
            trial,
        };
        self.inbox
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(held);
    }

    /// Whether trials arrived since an estimate last took them.
    pub fn has_new(&self) -> bool {
        !self
            .inbox
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .is_empty()
    }

    /// Runs of the latest published estimate.
    pub fn published(&self) -> u32 {
        self.published.load(Ordering::SeqCst)
    }

    /// Why this session would not use `walk` as its live run (`None`: it would).
    pub fn walk_unused(&self, walk: &Trajectory) -> Option<String> {
        walk_unused(
            &self.calibration,
            self.settings.window_frames as usize,
            walk,
        )
    }

    /// Holds `walk` as the session's live run from the next estimate on, replacing an earlier
    /// one (its bytes given back); `reservation` counts its bytes (see [`Self::reserve`]).
    /// The caller has checked [`Self::walk_unused`].
    pub fn set_walk(&self, walk: Trajectory, reservation: Reservation<'_>) {
        self.walk_restored.store(true, Ordering::SeqCst);
        let bytes = reservation.bytes;
        std::mem::forget(reservation);
        let mut slot = self.walk.lock().unwrap_or_else(|e| e.into_inner());
        let version = slot.as_ref().map_or(0, |w| w.version) + 1;
        if let Some(old) = slot.replace(HeldWalk {
            version,
            run: Arc::new(walk),
            bytes,
        }) {
            self.release(old.bytes);
        }
    }

    /// Once, for a session made from its stored files: holds the walk `load` reads (if any,
    /// and if the session uses it) as the one its published results already have. A walk
    /// over the bounds is left out (logged).
    pub fn restore_walk(&self, load: impl FnOnce() -> Result<Option<Trajectory>, Error>) {
        if self.walk_restored.swap(true, Ordering::SeqCst) {
            return;
        }
        let walk = match load() {
            Ok(Some(walk)) if self.walk_unused(&walk).is_none() => walk,
            Ok(_) => return,
            Err(e) => {
                log::warn!("session {}: its stored walk is not used: {e}", self.id);
                return;
            }
        };
        match self.reserve(trial_bytes(&walk)) {
            Ok(reservation) => {
                let bytes = reservation.bytes;
                std::mem::forget(reservation);
                let mut slot = self.walk.lock().unwrap_or_else(|e| e.into_inner());
                if slot.is_none() {
                    *slot = Some(HeldWalk {
                        version: 0,
                        run: Arc::new(walk),
                        bytes,
                    });
                } else {
                    self.release(bytes);
                }
            }
            Err(e) => log::warn!("session {}: its stored walk is not used: {e}", self.id),
        }
    }

    /// The walk held, if any.
    fn held_walk(&self) -> Option<HeldWalk> {
        self.walk.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// Whether the session holds a walk.
    pub fn has_walk(&self) -> bool {
        self.held_walk().is_some()
    }

    /// Whether an estimate runs or is about to (a delete waits for it to end).
    pub fn estimating(&self) -> bool {
        self.worker.load(Ordering::SeqCst) || self.held.try_lock().is_err()
    }

    /// Claims the session's background worker; false if one runs already.
    pub fn claim_worker(&self) -> bool {
        !self.worker.swap(true, Ordering::SeqCst)
    }

    /// Ends the worker's claim. True when trials arrived meanwhile and the claim was taken
    /// again: the worker goes on, so no trial waits without one.
    pub fn release_worker(&self) -> bool {
        self.worker.store(false, Ordering::SeqCst);
        self.has_new() && !self.closed.load(Ordering::SeqCst) && self.claim_worker()
    }

    /// Estimates over every trial held (and the walk, when held), once no other estimate of
    /// this session runs, and hands the results to `write` (which publishes them) before the
    /// next estimate may start. `None` when there is nothing new to publish (fewer than 2
    /// trials and no walk, no trial nor walk since the last published estimate, or the
    /// session closed).
    ///
    /// This is the one function that calls the estimator: new trials join the session's
    /// incremental state (only their pairs are computed), or a one-shot estimate when there
    /// is none (`held_trials.rs` says when).
    pub async fn publish(
        self: &Arc<Self>,
        purpose: Purpose,
        write: impl FnOnce(&Published) -> Result<(), Error> + Send + 'static,
    ) -> Result<Option<Published>, Error> {
        let mut held = self.held.clone().lock_owned().await;
        let live = self.clone();
        tokio::task::spawn_blocking(move || {
            if live.closed.load(Ordering::SeqCst) {
                return Ok(None);
            }
            let arrived =
                std::mem::take(&mut *live.inbox.lock().unwrap_or_else(|e| e.into_inner()));
            held.take(arrived);
            let walk = live.held_walk();
            let version = walk.as_ref().map_or(0, |w| w.version);
            let count = (held.count() + usize::from(walk.is_some())) as u32;
            let least = if walk.is_some() { 1 } else { 2 };
            if count < least
                || (count == live.published()
                    && version == live.published_walk.load(Ordering::SeqCst))
            {
                return Ok(None);
            }
            let trials = held.count();
            let estimated = held.estimate(
                &live.settings,
                purpose,
                live.as_ref(),
                live.calibration.applied(),
                walk.as_ref().map(|w| w.run.as_ref()),
            );
            let (estimate, reference) = match estimated {
                // The walk with one replay that does not pair with it: nothing to publish
                // until a second replay gives the expected error (`held_trials.rs`).
                Err(e) if walk.is_some() && trials == 1 => {
                    log::warn!("session {}: {e}; waiting for a second trial", live.id);
                    return Ok(None);
                }
                other => other?,
            };
            let mut published = Published::new(
                &estimate,
                reference,
                live.settings.window_frames as usize,
                live.thresholds,
            );
            published.json = live.calibration.mark(std::mem::take(&mut published.json));
            write(&published)?;
            live.published.store(count, Ordering::SeqCst);
            live.published_walk.store(version, Ordering::SeqCst);
            drop(held);
            Ok(Some(published))
        })
        .await
        .map_err(|e| Error::Internal(format!("estimate of session {}: {e}", self.id)))?
    }

    /// Whether the session's trials are estimated incrementally (see `held_trials.rs`).
    #[cfg(test)]
    async fn incremental(&self) -> bool {
        self.held.lock().await.incremental()
    }
}

impl StateBudget for LiveSession {
    fn grow(&self, bytes: usize) -> Result<(), Error> {
        // Counted until shrunk or the session is dropped.
        std::mem::forget(self.reserve(bytes)?);
        Ok(())
    }

    fn shrink(&self, bytes: usize) {
        self.release(bytes);
    }
}

impl Drop for LiveSession {
    fn drop(&mut self) {
        self.budget
            .total
            .fetch_sub(self.bytes.load(Ordering::SeqCst), Ordering::SeqCst);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sitar_estimator::{ApplyCalibration as _, PoseRelation, Setting, TimeUnit};

    fn trial(seed: u64) -> Trajectory {
        let n = 40;
        Trajectory {
            stamps: (0..n as i64)
                .map(|k| 1_000_000_000 + k * 33_333_333)
                .collect(),
            positions: (0..n)
                .map(|k| {
                    let wobble = ((k as u64 * 7 + seed * 13) % 11) as f64 * 1e-3;
                    glam::DVec3::new(k as f64 * 0.02 + wobble, wobble, 0.0)
                })
                .collect(),
            orientations: (0..n)
                .map(|k| glam::DQuat::from_rotation_y(k as f64 * 0.01 * (1.0 + seed as f64 * 0.1)))
                .collect(),
            time_unit: TimeUnit::Nanoseconds,
        }
    }

    fn settings() -> EstimateSettings {
        EstimateSettings {
            setting: Setting::Median,
            window_frames: 5,
            pose_relation: PoseRelation::RotationAngleDeg,
        }
    }

    fn live(sessions: &LiveSessions, id: &str) -> Arc<LiveSession> {
        sessions
            .get_or_insert(
                id,
                settings(),
                Default::default(),
                Thresholds::DEFAULT_DEG,
                0,
                || Ok(Vec::new()),
            )
            .unwrap()
    }

    fn add(live: &LiveSession, play: u64, index: u32) {
        let reservation = live.reserve(trial_bytes(&trial(play))).unwrap();
        live.add(play as u32, index, trial(play), reservation);
    }

    /// Adds trials whose storage index is their playback index.
    fn add_in_order(live: &LiveSession, plays: impl IntoIterator<Item = u64>) {
        for play in plays {
            add(live, play, play as u32);
        }
    }

    fn one_shot(plays: &[u64]) -> String {
        let trials: Vec<Trajectory> = plays.iter().map(|&p| trial(p)).collect();
        let estimate = sitar_estimator::estimate(&trials, &settings().options()).unwrap();
        estimate.to_json(Thresholds::DEFAULT_DEG)
    }

    async fn progressive(live: &Arc<LiveSession>) -> Option<Published> {
        live.publish(Purpose::Progressive, |_| Ok(()))
            .await
            .unwrap()
    }

    #[tokio::test]
    async fn an_estimate_takes_the_trials_in_playback_order_and_equals_the_one_shot() {
        let sessions = LiveSessions::new(1 << 24, 1 << 24);
        let live = live(&sessions, "a");
        assert!(progressive(&live).await.is_none(), "no trials");
        // Trials arrive out of playback order (parallel phones), before the first estimate.
        for (play, index) in [(2, 0), (0, 1), (1, 2)] {
            add(&live, play, index);
        }
        assert!(live.has_new());
        let published = progressive(&live).await.unwrap();
        assert!(!live.has_new());
        assert_eq!(published.json, one_shot(&[0, 1, 2]));
        assert_eq!((published.trials, live.published()), (3, 3));
        assert!(live.incremental().await);
        // The state is counted on top of the trials.
        let trials = 3 * trial_bytes(&trial(0));
        assert!(sessions.held_bytes() > trials, "{}", sessions.held_bytes());
        // Nothing new: nothing published; a failed write publishes nothing either.
        assert!(progressive(&live).await.is_none());
        add(&live, 3, 3);
        let err = live
            .publish(Purpose::Progressive, |_| {
                Err(Error::Internal("disk".into()))
            })
            .await
            .unwrap_err();
        assert!(err.to_string().contains("disk"));
        assert_eq!(live.published(), 3);
        add(&live, 4, 4);
        let published = progressive(&live).await.unwrap();
        assert_eq!(published.trials, 5);
        assert_eq!(published.json, one_shot(&[0, 1, 2, 3, 4]));
        assert!(live.incremental().await, "in order: pushed");
        // A removed session publishes nothing more, and its bytes are freed when dropped.
        sessions.remove("a");
        add(&live, 5, 5);
        assert!(progressive(&live).await.is_none());
        drop(live);
        assert_eq!(sessions.held_bytes(), 0);
    }

    #[tokio::test]
    async fn a_calibrated_session_publishes_the_calibrated_one_shot_in_any_arrival_order() {
        use crate::estimate::calibrations::tests::calibration as calibration_json;
        let calibration = sitar_estimator::Calibration::from_json(
            &calibration_json("median", 5, "angle_deg"),
            "test",
        )
        .unwrap();
        let expected = |plays: &[u64]| {
            let trials: Vec<Trajectory> = plays.iter().map(|&p| trial(p)).collect();
            let mut estimate = sitar_estimator::estimate(&trials, &settings().options()).unwrap();
            calibration.apply(&mut estimate, &trials, "lab").unwrap();
            estimate.source = Some("replays");
            estimate.to_json(Thresholds::DEFAULT_DEG)
        };
        let sessions = LiveSessions::new(1 << 24, 1 << 24);
        let applied = SessionCalibration::Apply {
            name: "lab".into(),
            calibration: Arc::new(calibration.clone()),
        };
        let live = sessions
            .get_or_insert("a", settings(), applied, Thresholds::DEFAULT_DEG, 0, || {
                Ok(Vec::new())
            })
            .unwrap();
        for (play, index) in [(2, 0), (0, 1)] {
            add(&live, play, index);
        }
        let published = progressive(&live).await.unwrap();
        assert_eq!(published.json, expected(&[0, 2]));
        assert!(published.json.contains(r#""calibration":"lab""#));
        assert!(
            published.json.contains(r#""lower_deg":"#),
            "{}",
            published.json
        );
        // Trial 1 joins after trial 2: the state holds them out of playback order, the
        // calibration looks at them in order.
        add(&live, 1, 2);
        let published = progressive(&live).await.unwrap();
        assert_eq!(published.json, expected(&[0, 1, 2]));
        assert!(live.incremental().await);
        add(&live, 3, 3);
        let published = live
            .publish(Purpose::Final, |_| Ok(()))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(published.json, expected(&[0, 1, 2, 3]));
        // The legacy CSV carries the calibrated errors, in its own shape.
        let trials: Vec<Trajectory> = (0..4).map(trial).collect();
        let mut estimate = sitar_estimator::estimate(&trials, &settings().options()).unwrap();
        calibration.apply(&mut estimate, &trials, "lab").unwrap();
        assert_eq!(published.csv, estimate.to_legacy_csv());
        assert!(published.csv.starts_with("start,error\n"));

        // Asked for but not on this server: the uncalibrated estimate, saying so.
        let missing = sessions
            .get_or_insert(
                "b",
                settings(),
                SessionCalibration::Missing("gone".into()),
                Thresholds::DEFAULT_DEG,
                0,
                || Ok(Vec::new()),
            )
            .unwrap();
        add_in_order(&missing, 0..2);
        let published = progressive(&missing).await.unwrap();
        let plain = one_shot(&[0, 1]);
        assert_eq!(
            published.json,
            format!(r#"{{"calibration_missing":"gone",{}"#, &plain[1..])
        );
    }

    /// A session with the version-2 test calibration `lab` (see `calibration_v2`).
    fn calibrated(sessions: &LiveSessions, id: &str, published: u32) -> Arc<LiveSession> {
        use crate::estimate::calibrations::tests::calibration_v2;
        let applied = SessionCalibration::Apply {
            name: "lab".into(),
            calibration: Arc::new(calibration_v2("median", 5, "angle_deg", true)),
        };
        sessions
            .get_or_insert(
                id,
                settings(),
                applied,
                Thresholds::DEFAULT_DEG,
                published,
                || Ok(Vec::new()),
            )
            .unwrap()
    }

    /// What the library gives for the walk `trial(0)` as the live run of `replays`, as the
    /// server publishes it.
    fn from_walk(replays: &[u64]) -> String {
        use crate::estimate::calibrations::tests::calibration_v2;
        let calibration = calibration_v2("median", 5, "angle_deg", true);
        let replays: Vec<Trajectory> = replays.iter().map(|&p| trial(p)).collect();
        let mut estimate = sitar_estimator::estimate_live(
            &calibration,
            &trial(0),
            &replays,
            &settings().options(),
            "lab",
        )
        .unwrap();
        estimate.source = Some(if replays.is_empty() {
            "walk"
        } else {
            "replays"
        });
        estimate.to_json(Thresholds::DEFAULT_DEG)
    }

    fn set_walk(live: &LiveSession, walk: Trajectory) {
        assert_eq!(live.walk_unused(&walk), None);
        let reservation = live.reserve(trial_bytes(&walk)).unwrap();
        live.set_walk(walk, reservation);
    }

    #[tokio::test]
    async fn the_walk_is_the_live_run_alone_then_with_the_trials_as_its_replays() {
        let sessions = LiveSessions::new(1 << 24, 1 << 24);
        let live = calibrated(&sessions, "a", 0);
        let walk = trial(0);
        set_walk(&live, walk.clone());
        assert!(live.has_walk());
        assert_eq!(
            sessions.held_bytes(),
            trial_bytes(&walk),
            "counted as a trial"
        );
        // Alone: one run, its own motion.
        let first = progressive(&live).await.unwrap();
        assert_eq!(first.json, from_walk(&[]));
        assert_eq!((first.trials, first.source), (1, Some("walk")));
        for key in [
            r#""source":"walk""#,
            r#""runs":1"#,
            r#""target":"live""#,
            r#""informative":true"#,
        ] {
            assert!(first.json.contains(key), "{key}: {}", first.json);
        }
        // The sub-trajectories are the walk's: every 5th frame of it.
        let starts: Vec<i64> = first.classes.keys().copied().collect();
        assert_eq!(
            starts,
            walk.stamps
                .iter()
                .step_by(5)
                .take(7)
                .copied()
                .collect::<Vec<_>>()
        );
        assert!(progressive(&live).await.is_none(), "nothing new");
        // Trials, out of playback order: the walk's replays, in playback order.
        add(&live, 2, 0);
        add(&live, 1, 1);
        let refined = progressive(&live).await.unwrap();
        assert_eq!(refined.json, from_walk(&[1, 2]));
        assert_eq!((refined.trials, refined.source), (3, Some("replays")));
        assert!(!live.incremental().await, "no pairwise state with a walk");
        assert_eq!(sessions.held_bytes(), 3 * trial_bytes(&walk));
        // The walk sent again: published again, its bytes replaced, not added.
        set_walk(&live, walk.clone());
        assert_eq!(sessions.held_bytes(), 3 * trial_bytes(&walk));
        assert_eq!(progressive(&live).await.unwrap().json, from_walk(&[1, 2]));
        add(&live, 3, 2);
        let last = live
            .publish(Purpose::Final, |_| Ok(()))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(last.json, from_walk(&[1, 2, 3]));
        sessions.remove("a");
        drop(live);
        assert_eq!(sessions.held_bytes(), 0);
    }

    #[tokio::test]
    async fn a_restarted_session_holds_its_stored_walk_as_published() {
        let sessions = LiveSessions::new(1 << 24, 1 << 24);
        // Published before the restart: the walk and two trials.
        let live = calibrated(&sessions, "a", 3);
        add_in_order(&live, 1..3);
        live.restore_walk(|| Ok(Some(trial(0))));
        assert!(live.has_walk());
        assert!(progressive(&live).await.is_none(), "already published");
        add(&live, 3, 3);
        assert_eq!(
            progressive(&live).await.unwrap().json,
            from_walk(&[1, 2, 3])
        );
        // Looked for once: a later restore changes nothing.
        live.restore_walk(|| Err(Error::Internal("read again".into())));
        assert_eq!(sessions.held_bytes(), 4 * trial_bytes(&trial(0)));
    }

    #[tokio::test]
    async fn replays_that_share_no_window_with_the_walk_give_the_expected_error() {
        let sessions = LiveSessions::new(1 << 24, 1 << 24);
        let live = calibrated(&sessions, "a", 0);
        set_walk(&live, trial(0));
        let late = |seed| {
            let mut t = trial(seed);
            t.stamps.iter_mut().for_each(|s| *s += 3_600_000_000_000);
            t
        };
        let r = live.reserve(trial_bytes(&trial(1))).unwrap();
        live.add(0, 0, late(1), r);
        assert!(
            progressive(&live).await.is_none(),
            "one replay that does not pair with the walk: nothing yet, not a failure"
        );
        let r = live.reserve(trial_bytes(&trial(2))).unwrap();
        live.add(1, 1, late(2), r);
        let published = progressive(&live).await.unwrap();
        assert!(
            published.json.contains(r#""target":"expected""#),
            "{}",
            published.json
        );
        assert_eq!(published.source, Some("replays"));
    }

    #[test]
    fn only_a_calibration_with_a_model_for_one_run_uses_the_walk() {
        use crate::estimate::calibrations::tests::calibration as v1;
        let walk = trial(0);
        let why = walk_unused(&SessionCalibration::None, 5, &walk).unwrap();
        assert!(why.contains("no calibration"), "{why}");
        let why = walk_unused(&SessionCalibration::Missing("gone".into()), 5, &walk).unwrap();
        assert!(why.contains("gone"), "{why}");
        let old = SessionCalibration::Apply {
            name: "old".into(),
            calibration: Arc::new(
                sitar_estimator::Calibration::from_json(&v1("median", 5, "angle_deg"), "t")
                    .unwrap(),
            ),
        };
        let why = walk_unused(&old, 5, &walk).unwrap();
        assert!(
            why.contains("calibration old") && why.contains("1 run"),
            "{why}"
        );
        let sessions = LiveSessions::new(1 << 24, 1 << 24);
        let live = calibrated(&sessions, "a", 0);
        assert_eq!(live.walk_unused(&walk), None);
        let mut short = walk.clone();
        short.stamps.truncate(5);
        short.positions.truncate(5);
        short.orientations.truncate(5);
        let why = live.walk_unused(&short).unwrap();
        assert!(why.contains("5 poses") && why.contains('6'), "{why}");
    }

    #[tokio::test]
    async fn a_trial_before_ones_already_estimated_joins_the_incremental_state_at_its_place() {
        let sessions = LiveSessions::new(1 << 24, 1 << 24);
        let live = live(&sessions, "a");
        add_in_order(&live, [1, 3, 4]);
        assert_eq!(progressive(&live).await.unwrap().json, one_shot(&[1, 3, 4]));
        assert!(live.incremental().await);
        // Trial 2 finishes after 3 and 4, trial 0 (the new first) after them all.
        add(&live, 2, 5);
        assert_eq!(
            progressive(&live).await.unwrap().json,
            one_shot(&[1, 2, 3, 4])
        );
        add(&live, 0, 6);
        let published = progressive(&live).await.unwrap();
        assert_eq!(published.json, one_shot(&[0, 1, 2, 3, 4]));
        assert!(live.incremental().await, "kept, each trial at its place");
        assert!(sessions.held_bytes() > 5 * trial_bytes(&trial(0)));
        add(&live, 5, 7);
        assert_eq!(
            progressive(&live).await.unwrap().json,
            one_shot(&[0, 1, 2, 3, 4, 5])
        );
    }

    #[tokio::test]
    async fn a_final_estimate_without_state_is_one_shot_and_a_tight_bound_drops_the_state() {
        let sessions = LiveSessions::new(1 << 24, 1 << 24);
        let finishing = live(&sessions, "a");
        add_in_order(&finishing, 0..4);
        let published = finishing
            .publish(Purpose::Final, |_| Ok(()))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(published.json, one_shot(&[0, 1, 2, 3]));
        assert!(!finishing.incremental().await);
        assert_eq!(sessions.held_bytes(), 4 * trial_bytes(&trial(0)));

        // Room for the trials, not for their pairs' values: estimates stay right, one-shot.
        let one = trial_bytes(&trial(0));
        let tight = LiveSessions::new(4 * one + 64, 1 << 24);
        let bounded = live(&tight, "b");
        add_in_order(&bounded, 0..3);
        let published = progressive(&bounded).await.unwrap();
        assert_eq!(published.json, one_shot(&[0, 1, 2]));
        assert!(!bounded.incremental().await);
        assert_eq!(tight.held_bytes(), 3 * one);
        add(&bounded, 3, 3);
        let published = progressive(&bounded).await.unwrap();
        assert_eq!(published.json, one_shot(&[0, 1, 2, 3]));
    }

    #[tokio::test]
    async fn a_trial_that_cannot_join_fails_the_estimate_as_the_one_shot_does() {
        let sessions = LiveSessions::new(1 << 24, 1 << 24);
        let live = live(&sessions, "a");
        add_in_order(&live, 0..2);
        assert!(progressive(&live).await.is_some());
        // Stamps an hour later: no stamp shared with the trials before.
        let mut late = trial(2);
        late.stamps.iter_mut().for_each(|s| *s += 3_600_000_000_000);
        let trials = [trial(0), trial(1), late.clone()];
        let expected = sitar_estimator::estimate(&trials, &settings().options()).unwrap_err();
        let reservation = live.reserve(trial_bytes(&late)).unwrap();
        live.add(2, 2, late, reservation);
        let err = live
            .publish(Purpose::Progressive, |_| Ok(()))
            .await
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            Error::Estimate(expected.to_string()).to_string()
        );
        assert_eq!(live.published(), 2);
    }

    #[test]
    fn the_memory_bounds_refuse_a_trial_and_count_nothing_for_it() {
        let one = trial_bytes(&trial(0));
        // Room for two trials per session and three in all.
        let sessions = LiveSessions::new(2 * one, 3 * one);
        let (a, b) = (live(&sessions, "a"), live(&sessions, "b"));
        for i in 0..2 {
            let r = a.reserve(one).unwrap();
            a.add(i, i, trial(0), r);
        }
        let err = a.reserve(one).err().unwrap();
        assert!(matches!(err, Error::TooLarge { .. }), "{err}");
        assert_eq!(
            err.status_and_code().0,
            axum::http::StatusCode::PAYLOAD_TOO_LARGE
        );
        let r = b.reserve(one).unwrap();
        b.add(0, 0, trial(0), r);
        let err = b.reserve(one).err().unwrap();
        assert!(matches!(err, Error::Busy(_)), "{err}");
        assert_eq!(
            err.status_and_code().0,
            axum::http::StatusCode::SERVICE_UNAVAILABLE
        );
        assert_eq!(sessions.held_bytes(), 3 * one);
        // A finished session frees room for the others.
        sessions.remove("a");
        drop(a);
        assert_eq!(sessions.held_bytes(), one);
        // A reservation not used (an idempotent retry) gives its bytes back.
        drop(b.reserve(one).unwrap());
        assert_eq!(sessions.held_bytes(), one);
        assert!(b.reserve(one).is_ok());
    }

    #[test]
    fn a_rebuilt_session_starts_from_its_stored_trials_and_published_count() {
        let sessions = LiveSessions::new(1 << 20, 1 << 20);
        let live = sessions
            .get_or_insert(
                "a",
                settings(),
                Default::default(),
                Thresholds::DEFAULT_DEG,
                2,
                || Ok(vec![(0, 0, trial(0)), (1, 1, trial(1))]),
            )
            .unwrap();
        assert_eq!(live.published(), 2);
        assert!(live.has_new());
        assert_eq!(sessions.held_bytes(), 2 * trial_bytes(&trial(0)));
        // In memory now: a second lookup does not read the files again.
        let again = sessions
            .get_or_insert(
                "a",
                settings(),
                Default::default(),
                Thresholds::DEFAULT_DEG,
                0,
                || Err(Error::Internal("read again".into())),
            )
            .unwrap();
        assert!(Arc::ptr_eq(&live, &again));
        // A trial file over the bound: the rebuild fails and holds nothing.
        let tight = LiveSessions::new(10, 1 << 20);
        let err = tight
            .get_or_insert(
                "b",
                settings(),
                Default::default(),
                Thresholds::DEFAULT_DEG,
                0,
                || Ok(vec![(0, 0, trial(0))]),
            )
            .err()
            .unwrap();
        assert!(matches!(err, Error::TooLarge { .. }));
        assert!(tight.get("b").is_none());
        assert_eq!(tight.held_bytes(), 0);
    }
}
