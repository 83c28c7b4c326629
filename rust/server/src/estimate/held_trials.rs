//! The trials a live session holds, in playback order, and the estimator state kept with
//! them: an [`IncrementalEstimate`], so that a new trial adds only its pairs, whatever its
//! place in playback order (parallel phones finish out of order: each trial joins at its
//! place); plain trials (one-shot estimates) once that state is given up.
//!
//! Both give bitwise the one-shot estimate over the held trials in playback order; the
//! incremental state only saves work. It is given up (its memory freed) for the rest of
//! the live session when a trial cannot join it (invalid, or no stamp shared: the one-shot
//! estimate then reports the same error), or when its memory would pass the session's
//! bounds. A final estimate with no state yet (an `upload` session without progressive
//! estimates, or one rebuilt after a restart) is one one-shot estimate, cheaper than pushing
//! every trial.
//!
//! A calibrated session's estimate is calibrated here, over the same trials in playback
//! order (the calibration looks at the motion of the first trials that have each window):
//! exactly what `ApplyCalibration::apply` gives on the one-shot estimate. The incremental state
//! holds its trials in the order they arrived; when that is not playback order (parallel
//! phones), the trials are copied into playback order for the calibration's look, and the
//! copy freed at once.
//!
//! **From the walk.** With the phone's walk (the live session holds it when the session's
//! calibration has a model for one run), the estimate is the error of the walk as the live
//! run: from its own motion alone before any trial (`"source": "walk"`), then with every held
//! trial as its replays (`"source": "replays"`, `"runs"` = 1 + trials), as
//! `sitar_estimator::estimate_live` gives it. It needs only the RPE between the walk and each
//! replay, not every pair: the incremental state is given up (its memory freed). Replays that
//! share no window with the walk (their stamps do not associate) fall back to the expected
//! error from the replays alone, logged.

use sitar_estimator::ApplyCalibration as _;
use std::borrow::Cow;

use sitar_estimator::{Calibration, Estimate, IncrementalEstimate, Trajectory};

use crate::error::Error;
use crate::model::estimate_settings::EstimateSettings;

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

/// One trial with its place in playback order: (playback index, storage index).
pub(crate) struct Held {
    pub order: (u32, u32),
    pub trial: Trajectory,
}

/// Whether an estimate is progressive (more trials may come) or the session's last.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Purpose {
    Progressive,
    Final,
}

/// The trials of a session in playback order, with what estimates them.
pub(crate) struct HeldTrials {
    /// Places of the trials the estimator holds, ascending.
    order: Vec<(u32, u32)>,
    /// Places of the incremental state's trials in the order they were pushed (its
    /// `trajectories()` order); empty for one-shot estimates, whose trials are in playback
    /// order.
    pushed: Vec<(u32, u32)>,
    estimator: Estimator,
    /// Trials taken from the inbox, not yet given to the estimator, sorted by place.
    waiting: Vec<Held>,
    /// Bytes of the estimator state counted in the session's bounds.
    counted: usize,
}

enum Estimator {
    /// Every trial so far, each at its place; nothing estimated yet when it holds none.
    Incremental(Box<IncrementalEstimate>),
    /// Every estimate from scratch over these trials.
    OneShot(Vec<Trajectory>),
}

/// Memory the estimator state holds beyond its trials, as counted against the session's
/// bounds: the caller reserves growth (`Err` when refused) and releases shrinkage.
pub(crate) trait StateBudget {
    fn grow(&self, bytes: usize) -> Result<(), Error>;
    fn shrink(&self, bytes: usize);
}

impl HeldTrials {
    pub fn new(settings: &EstimateSettings) -> HeldTrials {
        let estimator = match IncrementalEstimate::new(settings.options()) {
            Ok(state) => Estimator::Incremental(Box::new(state)),
            // Options the estimator refuses: the one-shot estimate reports why.
            Err(_) => Estimator::OneShot(Vec::new()),
        };
        HeldTrials {
            order: Vec::new(),
            pushed: Vec::new(),
            estimator,
            waiting: Vec::new(),
            counted: 0,
        }
    }

    /// Takes arrived trials (any order); they join the estimator at the next
    /// [`estimate`](Self::estimate).
    pub fn take(&mut self, arrived: Vec<Held>) {
        self.waiting.extend(arrived);
        self.waiting.sort_by_key(|held| held.order);
    }

    /// Trials held, waiting ones included.
    pub fn count(&self) -> usize {
        self.order.len() + self.waiting.len()
    }

    /// Whether the incremental state is kept.
    #[cfg(test)]
    pub fn incremental(&self) -> bool {
        matches!(self.estimator, Estimator::Incremental(_))
    }

    /// Bytes of the estimator state beyond the trials (0 without incremental state).
    fn state_bytes(&self) -> usize {
        match &self.estimator {
            Estimator::Incremental(state) => {
                let trials: usize = state.trajectories().iter().map(trial_bytes).sum();
                state.memory_bytes().saturating_sub(trials)
            }
            Estimator::OneShot(_) => 0,
        }
    }

    /// The estimate over every held trial in playback order (at least 2), calibrated with
    /// `calibration` (and its name) when given, and the first of the trials (the reference
    /// whose frames the phone colours). Growth of the state is counted in `budget`; when it
    /// is refused the state is dropped and this estimate is one-shot.
    ///
    /// With `walk` and a calibration: the walk's own error, alone or with the held trials as
    /// its replays, and the walk as the reference (module docs).
    pub fn estimate<'a>(
        &'a mut self,
        settings: &EstimateSettings,
        purpose: Purpose,
        budget: &dyn StateBudget,
        calibration: Option<(&Calibration, &str)>,
        walk: Option<&'a Trajectory>,
    ) -> Result<(Estimate, &'a Trajectory), Error> {
        if let (Some(walk), Some((calibration, name))) = (walk, calibration) {
            // The walk's estimate pairs it with each replay: no state to keep.
            self.give_up_state();
            self.bring_in(purpose);
            self.settle(budget);
            let replays: &[Trajectory] = match &self.estimator {
                Estimator::OneShot(trials) => trials,
                Estimator::Incremental(_) => unreachable!("given up above"),
            };
            let live = sitar_estimator::estimate_live(
                calibration,
                walk,
                replays,
                &settings.options(),
                name,
            );
            match live {
                Ok(mut estimate) => {
                    estimate.source = Some(if replays.is_empty() {
                        sitar_core::calibration::SOURCE_WALK
                    } else {
                        sitar_core::calibration::SOURCE_REPLAYS
                    });
                    return Ok((estimate, walk));
                }
                Err(e) if replays.len() >= 2 => {
                    log::warn!(
                        "the walk as the live run of {} replays: {e}; the expected error from \
                         the replays alone instead",
                        replays.len()
                    );
                }
                Err(e) => {
                    return Err(Error::Estimate(format!(
                        "the walk with calibration {name}: {e}"
                    )));
                }
            }
        }
        self.bring_in(purpose);
        self.settle(budget);
        let (estimate, first) = match &self.estimator {
            Estimator::Incremental(state) => (state.estimate(), state.first_in_order()),
            Estimator::OneShot(trials) => (
                sitar_estimator::estimate(trials, &settings.options()),
                trials.first(),
            ),
        };
        let mut estimate = estimate.map_err(|e| Error::Estimate(e.to_string()))?;
        let first = first.ok_or_else(|| Error::Estimate("no trials".into()))?;
        if let Some((calibration, name)) = calibration {
            calibration
                .apply(&mut estimate, &self.in_playback_order(), name)
                .map_err(|e| Error::Estimate(format!("calibration {name}: {e}")))?;
            estimate.source = Some(sitar_core::calibration::SOURCE_REPLAYS);
        }
        Ok((estimate, first))
    }

    /// Counts the state's growth in `budget` (dropping the state when refused) and releases
    /// what it shrank by.
    fn settle(&mut self, budget: &dyn StateBudget) {
        let mut now = self.state_bytes();
        if now > self.counted {
            match budget.grow(now - self.counted) {
                Ok(()) => self.counted = now,
                Err(e) => {
                    log::info!("incremental estimate given up: {e}");
                    self.give_up_state();
                    now = 0;
                }
            }
        }
        if now < self.counted {
            budget.shrink(self.counted - now);
            self.counted = now;
        }
    }

    /// The estimator's trials in playback order: its own when they are (one-shot, or pushed
    /// in order), else a copy.
    fn in_playback_order(&self) -> Cow<'_, [Trajectory]> {
        match &self.estimator {
            Estimator::OneShot(trials) => Cow::Borrowed(trials),
            Estimator::Incremental(state) => {
                let trials = state.trajectories();
                if self.pushed.windows(2).all(|w| w[0] <= w[1]) {
                    return Cow::Borrowed(trials);
                }
                let mut at: Vec<usize> = (0..trials.len()).collect();
                at.sort_by_key(|&i| self.pushed[i]);
                Cow::Owned(at.into_iter().map(|i| trials[i].clone()).collect())
            }
        }
    }

    /// Gives the waiting trials to the estimator, each at its place in playback order.
    fn bring_in(&mut self, purpose: Purpose) {
        let waiting = std::mem::take(&mut self.waiting);
        if purpose == Purpose::Final && self.order.is_empty() {
            self.give_up_state();
        }
        for held in waiting {
            let at = self.order.partition_point(|o| *o < held.order);
            self.order.insert(at, held.order);
            match &mut self.estimator {
                Estimator::OneShot(trials) => trials.insert(at, held.trial),
                Estimator::Incremental(state) => {
                    let (play, index) = held.order;
                    let place = (u64::from(play) << 32) | u64::from(index);
                    match state.try_push_ordered(held.trial, place) {
                        Ok(()) => self.pushed.push(held.order),
                        Err(rejected) => {
                            let (e, trial) = *rejected;
                            log::info!("incremental estimate given up: {e}");
                            self.give_up_state();
                            if let Estimator::OneShot(trials) = &mut self.estimator {
                                trials.insert(at, trial);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Drops the incremental state, keeping its trials (its counted bytes are released by
    /// [`estimate`](Self::estimate)).
    fn give_up_state(&mut self) {
        let trials = match std::mem::replace(&mut self.estimator, Estimator::OneShot(Vec::new())) {
            Estimator::Incremental(state) => state.into_trajectories(),
            Estimator::OneShot(trials) => trials,
        };
        self.estimator = Estimator::OneShot(trials);
        self.pushed = Vec::new();
    }
}
