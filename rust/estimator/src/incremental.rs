//! [`IncrementalEstimate`]: the pairwise estimate of a growing set of trials, updated by each
//! new trial's pairs only, and bitwise equal to the one-shot [`estimate`](crate::estimate).

use rayon::prelude::*;

use crate::exact::{ExactSquares, ExactSum, add_values, population_std};
use crate::pairwise::{BLOCK, PairIndex, Scratch};
use crate::sorted_runs::{FREEZE_AT, SortedRuns, Target};
use crate::statistics::bits::{
    inlier_range, interpolate, mean_of, median_of, median_ranks, quantile_ranks, trim_cuts,
};
use crate::{Error, Estimate, EstimateOptions, Setting, Trajectory, WindowEstimate};

/// The pairwise estimate of trials that arrive one by one (the backend's progressive
/// results): [`push`](Self::push) adds a trial's pairs with the trials already there,
/// [`estimate`](Self::estimate) reads every window's statistic from the state kept.
///
/// After any sequence of pushes, `estimate()` is bitwise equal to
/// [`estimate`](crate::estimate)`(&trials_so_far, &options)` — every window's start, end, pair
/// count, error and spread — because both compute each statistic from the multiset of pair
/// values alone: order statistics by rank and exact sums rounded once (see the crate docs,
/// "Incremental estimation"). Trials may also arrive out of their playback order (parallel
/// phones finish in any order): [`push_ordered`](Self::push_ordered) gives each its place,
/// and the estimate is then the one-shot estimate of the trials sorted by place.
///
/// ```
/// use sitar_estimator::{estimate, parse_tum, EstimateOptions, IncrementalEstimate};
///
/// let trial = |drift: f64| {
///     let text: String = (0..30)
///         .map(|i: i64| format!("{} {} 0 0 0 0 0 1\n", 1_000_000_000 + i * 50_000_000, i as f64 * (0.02 + drift)))
///         .collect();
///     parse_tum(&text, "trial.txt").unwrap()
/// };
/// let trials = [trial(0.0), trial(0.001), trial(0.003)];
/// let mut incremental = IncrementalEstimate::new(EstimateOptions::default())?;
/// for t in &trials {
///     incremental.push(t.clone())?;
/// }
/// assert_eq!(incremental.trials(), 3);
/// assert_eq!(incremental.estimate()?, estimate(&trials, &EstimateOptions::default())?);
/// # Ok::<(), sitar_estimator::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct IncrementalEstimate {
    options: EstimateOptions,
    /// In the order pushed (their places: `index.ranks()`).
    trials: Vec<Trajectory>,
    index: PairIndex,
    /// Per key of `index`: the window's values, once it has some.
    windows: Vec<Option<Box<WindowState>>>,
    /// Per parallel task of [`IncrementalEstimate::push`]: bucket buffers kept between pushes.
    scratch: Vec<TaskScratch>,
}

/// The buffers of one task of [`IncrementalEstimate::push`]: buckets, pair scratch, merges.
#[derive(Debug, Clone, Default)]
struct TaskScratch {
    buckets: Vec<Vec<u64>>,
    pairs: Scratch,
    merge: Vec<u64>,
}

impl TaskScratch {
    fn heap_bytes(&self) -> usize {
        self.buckets.iter().map(|b| b.capacity() * 8).sum::<usize>() + self.merge.capacity() * 8
    }
}

/// What one window keeps: the count and exact sums of all its values and, for settings with
/// order statistics, the values themselves as sorted runs with the setting's cursors.
#[derive(Debug, Clone)]
struct WindowState {
    count: usize,
    sum: ExactSum,
    squares: ExactSquares,
    /// `None` for [`Setting::Mean`], which needs no order.
    order: Option<SortedRuns>,
    /// `(statistic, spread)` after the last insertion (computed while the state is in cache).
    result: (f64, f64),
}

/// Cursors per setting: median `[lower middle rank]`; trimmed mean `[lowercut, uppercut]`
/// with the sum between them; mean of inliers `[Q1 rank, Q3 rank, lower fence, upper
/// fence]` with the sum between the fences.
fn new_order(setting: Setting) -> Option<SortedRuns> {
    match setting {
        Setting::Mean => None,
        Setting::Median => Some(SortedRuns::new(1, None, FREEZE_AT)),
        Setting::TrimMean(_) => Some(SortedRuns::new(2, Some((0, 1)), FREEZE_AT)),
        Setting::MeanInliers => Some(SortedRuns::new(4, Some((2, 3)), FREEZE_AT)),
    }
}

/// numpy's linear `q`-quantile from a cursor at its lower rank.
fn quantile_at(order: &SortedRuns, cursor: usize, n: usize, q: f64) -> f64 {
    let [below, above] = quantile_ranks(n, q);
    let (at, next) = order.above(cursor);
    let at = f64::from_bits(at.unwrap_or(0));
    let next = if above == below {
        at
    } else {
        f64::from_bits(next.unwrap_or(0))
    };
    interpolate(n, q, at, next)
}

impl WindowState {
    fn new(setting: Setting) -> Self {
        Self {
            count: 0,
            sum: ExactSum::new(),
            squares: ExactSquares::new(),
            order: new_order(setting),
            result: (f64::NAN, f64::NAN),
        }
    }

    /// Adds values (float bits, any order; `values` is sorted in place).
    fn insert(&mut self, values: &mut [u64], setting: Setting, merge: &mut Vec<u64>) {
        let bound = if self.order.is_some() {
            values.sort_unstable();
            values.last().copied()
        } else {
            values.iter().copied().max()
        }
        .unwrap_or(0);
        add_values(
            &mut self.sum,
            Some(&mut self.squares),
            values.iter().copied(),
            bound,
        );
        self.count += values.len();
        let n = self.count;
        if let Some(order) = &mut self.order {
            order.insert(values, merge);
            Self::move_cursors(order, setting, n);
        }
        self.result = self.statistics(setting);
    }

    /// Moves the cursors to the setting's ranks and fences for `n` values.
    fn move_cursors(order: &mut SortedRuns, setting: Setting, n: usize) {
        match setting {
            Setting::Mean => {}
            Setting::Median => order.move_to(0, Target::Rank(median_ranks(n)[0])),
            Setting::TrimMean(percent) => {
                let (lowercut, uppercut) = trim_cuts(percent, n);
                order.move_to(0, Target::Rank(lowercut));
                order.move_to(1, Target::Rank(uppercut));
            }
            Setting::MeanInliers => {
                order.move_to(0, Target::Rank(quantile_ranks(n, 0.25)[0]));
                order.move_to(1, Target::Rank(quantile_ranks(n, 0.75)[0]));
                let (low, high) = inlier_range(
                    quantile_at(order, 0, n, 0.25),
                    quantile_at(order, 1, n, 0.75),
                );
                order.move_to(2, Target::Below(low));
                order.move_to(3, Target::Below(high));
            }
        }
    }

    /// `(statistic, spread)`, as [`crate::statistics::bits::window_statistics`] computes them.
    fn statistics(&self, setting: Setting) -> (f64, f64) {
        let n = self.count;
        let spread = population_std(n, &self.sum, &self.squares);
        let value = match (&self.order, setting) {
            (Some(order), Setting::Median) => {
                let (lower, upper) = order.above(0);
                let lower = f64::from_bits(lower.unwrap_or(0));
                let upper = if n % 2 == 1 {
                    lower
                } else {
                    f64::from_bits(upper.unwrap_or(0))
                };
                median_of(n, lower, upper)
            }
            (Some(order), Setting::TrimMean(percent)) => {
                let (lowercut, uppercut) = trim_cuts(percent, n);
                if lowercut >= uppercut {
                    f64::NAN
                } else {
                    mean_of(order.between(), uppercut - lowercut)
                }
            }
            (Some(order), Setting::MeanInliers) => {
                mean_of(order.between(), order.rank(3) - order.rank(2))
            }
            _ => mean_of(&self.sum, n),
        };
        (value, spread)
    }

    fn heap_bytes(&self) -> usize {
        size_of::<Self>() + self.order.as_ref().map_or(0, SortedRuns::heap_bytes)
    }
}

impl IncrementalEstimate {
    /// An estimate with no trials yet; checks the options (`delta ≥ 1`, a finite,
    /// non-negative `t_max_diff_s`).
    pub fn new(options: EstimateOptions) -> Result<Self, Error> {
        Ok(Self {
            options,
            trials: Vec::new(),
            index: PairIndex::new(options.pair_options()?),
            windows: Vec::new(),
            scratch: Vec::new(),
        })
    }

    /// Adds a trial after every trial already there: validates it (poses, increasing
    /// stamps), associates it with every trial already there and adds the values of those
    /// pairs only. On error (an invalid trial, or one that shares no stamp with an earlier
    /// trial) nothing changes.
    pub fn push(&mut self, trial: Trajectory) -> Result<(), Error> {
        self.try_push(trial).map_err(|rejected| rejected.0)
    }

    /// [`push`](Self::push) that gives the trial back with the error, for a caller that
    /// keeps it (a server estimating over every trial it received, valid or not).
    pub fn try_push(&mut self, trial: Trajectory) -> Result<(), Box<(Error, Trajectory)>> {
        let place = self
            .index
            .ranks()
            .iter()
            .max()
            .map_or(0, |last| last.saturating_add(1));
        self.try_push_ordered(trial, place)
    }

    /// Adds a trial at playback place `place` (any order of arrival; places must differ):
    /// as [`push`](Self::push), the trial of the earlier place being the reference of each
    /// new pair. The estimate is the one-shot estimate of the trials sorted by place.
    pub fn push_ordered(&mut self, trial: Trajectory, place: u64) -> Result<(), Error> {
        self.try_push_ordered(trial, place)
            .map_err(|rejected| rejected.0)
    }

    /// [`push_ordered`](Self::push_ordered) that gives the trial back with the error.
    pub fn try_push_ordered(
        &mut self,
        trial: Trajectory,
        place: u64,
    ) -> Result<(), Box<(Error, Trajectory)>> {
        if self.index.ranks().contains(&place) {
            let e = Error::InvalidArgument(format!("a trial at place {place} is already there"));
            return Err(Box::new((e, trial)));
        }
        self.trials.push(trial);
        let remap = match self.index.extend(&self.trials, &[place]) {
            Ok(remap) => remap,
            Err(e) => {
                let trial = self.trials.pop().expect("pushed above");
                return Err(Box::new((e, trial)));
            }
        };
        if let Some(remap) = remap {
            let mut windows: Vec<Option<Box<WindowState>>> = Vec::new();
            windows.resize_with(self.index.key_count(), || None);
            for (old, state) in std::mem::take(&mut self.windows).into_iter().enumerate() {
                windows[remap[old] as usize] = state;
            }
            self.windows = windows;
        }
        self.windows.resize_with(self.index.key_count(), || None);
        let newest = self.trials.len() - 1;
        let (index, setting) = (&self.index, self.options.setting);
        // Contiguous groups of blocks, one per task, each with its own buffers.
        let tasks = 2 * rayon::current_num_threads();
        let blocks_per_task = index.blocks().div_ceil(tasks).max(1);
        self.scratch.resize_with(tasks, Default::default);
        self.windows
            .par_chunks_mut(blocks_per_task * BLOCK)
            .zip(self.scratch.par_iter_mut())
            .enumerate()
            .for_each(|(task, (windows, scratch))| {
                let TaskScratch {
                    buckets,
                    pairs,
                    merge,
                } = scratch;
                for (b, windows) in windows.chunks_mut(BLOCK).enumerate() {
                    index.fill_block(task * blocks_per_task + b, newest, buckets, pairs);
                    for (window, values) in windows.iter_mut().zip(buckets.iter_mut()) {
                        if !values.is_empty() {
                            window
                                .get_or_insert_with(|| Box::new(WindowState::new(setting)))
                                .insert(values, setting, merge);
                        }
                    }
                }
            });
        Ok(())
    }

    /// Number of trials pushed.
    pub fn trials(&self) -> usize {
        self.trials.len()
    }

    /// The trials pushed, in the order pushed.
    pub fn trajectories(&self) -> &[Trajectory] {
        &self.trials
    }

    /// The trial of the earliest place (the reference whose stamps a phone colours), if any.
    pub fn first_in_order(&self) -> Option<&Trajectory> {
        let first = (0..self.trials.len()).min_by_key(|&i| self.index.ranks()[i])?;
        Some(&self.trials[first])
    }

    /// The trials pushed, sorted by place; the rest of the state is dropped.
    pub fn into_trajectories(self) -> Vec<Trajectory> {
        let places = self.index.ranks().to_vec();
        let mut placed: Vec<(u64, Trajectory)> = places.into_iter().zip(self.trials).collect();
        placed.sort_by_key(|(place, _)| *place);
        placed.into_iter().map(|(_, trial)| trial).collect()
    }

    /// The estimate over the trials pushed so far (at least 2).
    pub fn estimate(&self) -> Result<Estimate, Error> {
        if self.trials.len() < 2 {
            return Err(Error::InvalidArgument(format!(
                "need at least 2 trials, got {}",
                self.trials.len()
            )));
        }
        let setting = self.options.setting;
        let windows = self
            .windows
            .par_iter()
            .enumerate()
            .filter_map(|(key, state)| {
                let state = state.as_ref()?;
                let (start, end) = self.index.window(key);
                let (error_m, spread_m) = state.result;
                Some(WindowEstimate {
                    start,
                    end,
                    error_m,
                    pairs: state.count,
                    spread_m,
                    interval: None,
                })
            })
            .collect();
        Ok(Estimate {
            setting,
            trials: self.trials.len(),
            time_unit: self.first_in_order().expect("2 trials or more").time_unit,
            pose_relation: self.options.pose_relation,
            delta: self.options.delta,
            windows,
            calibration: None,
            calibrated_as: None,
            source: None,
        })
    }

    /// Bytes this estimate holds: the trials, the pairwise index and every window's values
    /// and sums (capacities, not just lengths) — what a server bounds per session.
    pub fn memory_bytes(&self) -> usize {
        let trials: usize = self
            .trials
            .iter()
            .map(|t| {
                t.stamps.capacity() * 8
                    + t.positions.capacity() * size_of::<glam::DVec3>()
                    + t.orientations.capacity() * size_of::<glam::DQuat>()
            })
            .sum();
        let windows: usize = self.windows.iter().flatten().map(|w| w.heap_bytes()).sum();
        let scratch: usize = self.scratch.iter().map(TaskScratch::heap_bytes).sum();
        size_of::<Self>()
            + scratch
            + trials
            + self.trials.capacity() * size_of::<Trajectory>()
            + self.index.heap_bytes()
            + self.windows.capacity() * size_of::<Option<Box<WindowState>>>()
            + windows
    }
}
