//! Live sessions: the parsed trials of every session in flight, held in memory so that each
//! progressive estimate works on them and never re-reads a file.
//!
//! **Memory.** A trial costs 64 bytes a pose (an `i64` stamp, a `DVec3` position, a `DQuat`
//! orientation) plus about 100 bytes: 2 820 poses are 180 kB, 100 such trials 18 MB.
//! [`ServerConfig::live_session_bytes`](crate::ServerConfig::live_session_bytes) bounds one
//! session (default 256 MiB), [`ServerConfig::live_total_bytes`](crate::ServerConfig::live_total_bytes)
//! all of them together (default 1 GiB); a trial that would pass either is refused before
//! anything of it is stored. An estimate's own working memory comes on top while it runs
//! (the estimator's: under 60 MB for 100 × 2 820 poses). A live session is dropped, and its
//! bytes freed, when the session finishes, fails or is deleted; after a restart it is
//! rebuilt from the trial files when the session next needs it.
//!
//! **Estimates.** One estimate of a session runs at a time ([`LiveSession::publish`]); trials
//! that arrive meanwhile wait in an inbox and join the next one together, in playback order.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use sitar_core::Thresholds;
use sitar_estimator::Trajectory;

use crate::Error;
use crate::estimation::Published;
use crate::settings::EstimateSettings;

/// Bytes one parsed trial holds in memory.
pub(crate) fn trial_bytes(trial: &Trajectory) -> usize {
    fn heap<T>(v: &Vec<T>) -> usize {
        v.capacity() * std::mem::size_of::<T>()
    }
    std::mem::size_of::<Trajectory>()
        + heap(&trial.stamps)
        + heap(&trial.positions)
        + heap(&trial.orientations)
}

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
    /// its latest published results. Another request's session made meanwhile wins.
    pub fn get_or_insert(
        &self,
        id: &str,
        settings: EstimateSettings,
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
            thresholds,
            inbox: Mutex::new(Vec::new()),
            held: Arc::new(tokio::sync::Mutex::new(Ordered::default())),
            bytes: AtomicUsize::new(0),
            budget: self.budget.clone(),
            published: AtomicU32::new(published),
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

/// One trial in memory, with its place in playback order: (playback index, storage index).
struct Held {
    order: (u32, u32),
    trial: Trajectory,
}

/// Trials in playback order, side by side with their places (the estimator takes a slice).
#[derive(Default)]
struct Ordered {
    order: Vec<(u32, u32)>,
    trials: Vec<Trajectory>,
}

impl Ordered {
    fn insert(&mut self, held: Held) {
        let at = self.order.partition_point(|o| *o < held.order);
        self.order.insert(at, held.order);
        self.trials.insert(at, held.trial);
    }
}

/// The trials of one session in flight.
pub(crate) struct LiveSession {
    id: String,
    settings: EstimateSettings,
    thresholds: Thresholds,
    /// Trials that arrived since an estimate last took them.
    inbox: Mutex<Vec<Held>>,
    /// Every other trial, in playback order; locked by the one estimate that runs.
    held: Arc<tokio::sync::Mutex<Ordered>>,
    /// Bytes of this session's trials (inbox and held).
    bytes: AtomicUsize,
    budget: Arc<Budget>,
    /// Trials of the latest published estimate.
    published: AtomicU32,
    /// Set when the session no longer needs estimates.
    closed: AtomicBool,
    /// A background worker publishes progressive estimates (`upload` sessions).
    worker: AtomicBool,
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

    /// Trials of the latest published estimate.
    pub fn published(&self) -> u32 {
        self.published.load(Ordering::SeqCst)
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

    /// Estimates over every trial held, once no other estimate of this session runs, and
    /// hands the results to `write` (which publishes them) before the next estimate may
    /// start. `None` when there is nothing new to publish (fewer than 2 trials, none since
    /// the last published estimate, or the session closed).
    ///
    /// This is the one function that calls the estimator: today the one-shot
    /// `sitar_estimator::estimate` over the held trials; an incremental estimator would
    /// keep its state next to `held` and push the new trials here.
    pub async fn publish(
        self: &Arc<Self>,
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
            for trial in arrived {
                held.insert(trial);
            }
            let trials = &held.trials;
            let count = trials.len() as u32;
            if count < 2 || count == live.published() {
                return Ok(None);
            }
            let estimate = sitar_estimator::estimate(trials, &live.settings.options())
                .map_err(|e| Error::Estimate(e.to_string()))?;
            let published = Published::new(
                &estimate,
                &trials[0],
                live.settings.window_frames as usize,
                live.thresholds,
            );
            write(&published)?;
            live.published.store(count, Ordering::SeqCst);
            drop(held);
            Ok(Some(published))
        })
        .await
        .map_err(|e| Error::Internal(format!("estimate of session {}: {e}", self.id)))?
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
    use sitar_estimator::{PoseRelation, Setting, TimeUnit};

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
                Thresholds::DEFAULT_DEG,
                0,
                || Ok(Vec::new()),
            )
            .unwrap()
    }

    #[tokio::test]
    async fn an_estimate_takes_the_trials_in_playback_order_and_equals_the_one_shot() {
        let sessions = LiveSessions::new(1 << 20, 1 << 20);
        let live = live(&sessions, "a");
        assert!(
            live.publish(|_| Ok(())).await.unwrap().is_none(),
            "no trials"
        );
        // Trials arrive out of playback order (parallel phones).
        for (play, index) in [(2, 0), (0, 1), (1, 2)] {
            let reservation = live.reserve(trial_bytes(&trial(play))).unwrap();
            live.add(play as u32, index, trial(play), reservation);
        }
        assert!(live.has_new());
        let published = live.publish(|_| Ok(())).await.unwrap().unwrap();
        assert!(!live.has_new());
        let ordered = [trial(0), trial(1), trial(2)];
        let one_shot = sitar_estimator::estimate(&ordered, &settings().options()).unwrap();
        assert_eq!(published.json, one_shot.to_json(Thresholds::DEFAULT_DEG));
        assert_eq!((published.trials, live.published()), (3, 3));
        // Nothing new: nothing published; a failed write publishes nothing either.
        assert!(live.publish(|_| Ok(())).await.unwrap().is_none());
        let reservation = live.reserve(trial_bytes(&trial(3))).unwrap();
        live.add(3, 3, trial(3), reservation);
        let err = live
            .publish(|_| Err(Error::Internal("disk".into())))
            .await
            .unwrap_err();
        assert!(err.to_string().contains("disk"));
        assert_eq!(live.published(), 3);
        assert_eq!(live.publish(|_| Ok(())).await.unwrap().unwrap().trials, 4);
        // A removed session publishes nothing more, and its bytes are freed when dropped.
        let held = sessions.held_bytes();
        assert_eq!(held, 4 * trial_bytes(&trial(0)));
        sessions.remove("a");
        let reservation = live.reserve(10).unwrap();
        live.add(4, 4, trial(4), reservation);
        assert!(live.publish(|_| Ok(())).await.unwrap().is_none());
        drop(live);
        assert_eq!(sessions.held_bytes(), 0);
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
            .get_or_insert("a", settings(), Thresholds::DEFAULT_DEG, 2, || {
                Ok(vec![(0, 0, trial(0)), (1, 1, trial(1))])
            })
            .unwrap();
        assert_eq!(live.published(), 2);
        assert!(live.has_new());
        assert_eq!(sessions.held_bytes(), 2 * trial_bytes(&trial(0)));
        // In memory now: a second lookup does not read the files again.
        let again = sessions
            .get_or_insert("a", settings(), Thresholds::DEFAULT_DEG, 0, || {
                Err(Error::Internal("read again".into()))
            })
            .unwrap();
        assert!(Arc::ptr_eq(&live, &again));
        // A trial file over the bound: the rebuild fails and holds nothing.
        let tight = LiveSessions::new(10, 1 << 20);
        let err = tight
            .get_or_insert("b", settings(), Thresholds::DEFAULT_DEG, 0, || {
                Ok(vec![(0, 0, trial(0))])
            })
            .err()
            .unwrap();
        assert!(matches!(err, Error::TooLarge { .. }));
        assert!(tight.get("b").is_none());
        assert_eq!(tight.held_bytes(), 0);
    }
}
