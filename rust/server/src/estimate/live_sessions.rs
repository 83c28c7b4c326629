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

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};
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
            let count = held.count() as u32;
            if count < 2 || count == live.published() {
                return Ok(None);
            }
            let (estimate, reference) = held.estimate(
                &live.settings,
                purpose,
                live.as_ref(),
                live.calibration.applied(),
            )?;
            let mut published = Published::new(
                &estimate,
                reference,
                live.settings.window_frames as usize,
                live.thresholds,
            );
            published.json = live.calibration.mark(std::mem::take(&mut published.json));
            write(&published)?;
            live.published.store(count, Ordering::SeqCst);
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
    use sitar_estimator::ApplyCalibration as _;
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
