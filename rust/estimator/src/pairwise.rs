//! The pairwise RPE inputs of a set of trials that may grow, grouped for aggregation by window.
//!
//! Trials have a playback order (a rank each; the order given, for a one-shot estimate); of
//! every pair the earlier trial is the reference, the two are associated as evo does, and an
//! all-pairs RPE with a delta of `delta` frames is computed on the associated poses. Every
//! value is keyed by the reference's start stamp (a *key*: every trial's stamps are keys, so
//! that a trial arriving ahead of earlier ones can later be a reference; keys are sorted and
//! indexed, blocks of [`BLOCK`] keys are aggregated in parallel, and a key no reference has
//! gets no values and no window).
//!
//! Speed: an RPE value only needs the two trials' *relative* poses over the window, so they are
//! computed once per trial (`rel[k] = pose_k⁻¹ pose_{k+delta}`) and reused by every pair whose
//! association keeps the window contiguous; only windows broken by a dropped frame are
//! recomputed from the poses. Trials with identical stamps form a group whose pairs associate
//! one to one; other pairs are associated once per distinct pair of stamp lists.
//!
//! [`PairIndex::extend`] adds trials, in any playback order: only the new pairs (those with a
//! new trial) are associated, and [`PairIndex::fill_block`] yields only their values, so the
//! incremental estimate touches each pair once. When a new trial brings stamps that are not
//! keys yet, the keys are re-indexed and the caller gets the map from old to new key indices.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};

use glam::{DQuat, DVec3};
use rayon::prelude::*;

use crate::metrics::RigidPose;
use crate::sync::associate_named;
use crate::{Error, PoseRelation, Trajectory};

/// Keys per aggregation block (a block's buckets stay cache-sized).
pub(crate) const BLOCK: usize = 128;

/// The options a [`PairIndex`] is built with, checked once.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PairOptions {
    pub(crate) delta: usize,
    pub(crate) t_max_diff_s: f64,
    pub(crate) relation: PoseRelation,
}

impl PairOptions {
    /// Checks `delta ≥ 1` and a finite, non-negative `t_max_diff_s`.
    pub(crate) fn new(
        delta: usize,
        t_max_diff_s: f64,
        relation: PoseRelation,
    ) -> Result<Self, Error> {
        if delta == 0 {
            return Err(Error::InvalidArgument(
                "delta must be at least 1 frame".into(),
            ));
        }
        if !(t_max_diff_s.is_finite() && t_max_diff_s >= 0.0) {
            return Err(Error::InvalidArgument(format!(
                "t_max_diff must be a finite, non-negative number of seconds, got {t_max_diff_s}"
            )));
        }
        Ok(Self {
            delta,
            t_max_diff_s,
            relation,
        })
    }
}

/// Checks a trial for pairing: poses, strictly increasing stamps, a length that indexes in u32.
pub(crate) fn validate_trial(index: usize, trial: &Trajectory) -> Result<(), Error> {
    if trial.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "trial {index} has no poses"
        )));
    }
    if trial.len() >= u32::MAX as usize {
        return Err(Error::InvalidArgument(format!(
            "trial {index} has {} poses (at most {} are supported)",
            trial.len(),
            u32::MAX - 1
        )));
    }
    trial
        .validate()
        .map_err(|e| Error::InvalidArgument(format!("trial {index}: {e}")))
}

/// The pairwise index: keys, per-trial relative poses, groups, matchings and the pairs added
/// by the last [`PairIndex::extend`].
#[derive(Debug, Clone)]
pub(crate) struct PairIndex {
    options: PairOptions,
    /// Trials indexed so far.
    trials: usize,
    /// Playback rank (place) of each trial, indexed in the order trials were added.
    ranks: Vec<u64>,
    /// Sorted, distinct window start stamps (ns): the stamps of every trial.
    keys: Vec<i64>,
    /// End stamp per key, from the earliest trial in playback order that has the key.
    ends: Vec<i64>,
    /// Rank of the trial each end comes from.
    end_ranks: Vec<u64>,
    /// Per trial: the key index of each of its poses.
    key_of: Vec<Vec<u32>>,
    /// Per trial: `[b]` = first pose whose key is in block `b` or later.
    trial_block_starts: Vec<Vec<u32>>,
    /// Per trial: the first trial with identical stamps (its group's name).
    group_of: Vec<usize>,
    /// Hash of a stamp list → the first trials of the groups with that hash.
    groups_by_hash: HashMap<u64, Vec<usize>>,
    /// Groups with at least two members, by first member.
    groups: Vec<Group>,
    /// Per trial: relative poses over `delta` frames.
    relative: Vec<RelativeWindows>,
    matchings: Vec<Matching>,
    /// (group of the reference, group of the estimate) → index into `matchings`.
    matching_index: HashMap<(usize, usize), usize>,
    /// The pairs added by the last extension whose trials' stamps differ.
    pairs: Vec<Pair>,
}

/// One pair whose trials' stamps differ: its trials, the matching of their stamps, and the
/// values of the windows the matching could not cover with segments.
#[derive(Debug, Clone)]
struct Pair {
    reference: usize,
    estimate: usize,
    /// Index into `PairIndex::matchings`.
    matching: usize,
    /// Values (float bits) of `matchings[matching].irregular`, in the same order.
    irregular_values: Vec<u64>,
}

/// Trials with identical stamps (at least two): their pairs associate one to one, so window
/// values of all their pairs come from the same pose index.
#[derive(Debug, Clone)]
struct Group {
    /// Trial indices, ascending.
    members: Vec<usize>,
    /// Pose index of each key in these trials' stamps (`u32::MAX`: not a stamp of theirs).
    pose_of_key: Vec<u32>,
}

/// How two stamp lists associate, as windows; depends only on the stamps, so trials with
/// identical stamps share it. Segments are runs where both trials advance frame by frame
/// (values computed on the fly from the per-trial relative poses); `irregular` are the
/// windows a dropped or unmatched frame breaks.
#[derive(Debug, Clone, Default)]
struct Matching {
    /// The reference group's first trial (whose keys the irregular windows use).
    reference: usize,
    /// Sorted by `reference_start`.
    segments: Vec<Segment>,
    /// Broken windows as pose indices `[reference from, reference to, estimate from, estimate to]`.
    irregular: Vec<[u32; 4]>,
    irregular_keys: Vec<u32>,
    irregular_block_starts: Vec<u32>,
}

/// Windows `reference_start + t → +delta` against `estimate_start + t → +delta`, `t < len`.
#[derive(Debug, Clone, Copy)]
struct Segment {
    reference_start: u32,
    estimate_start: u32,
    len: u32,
}

/// Per-trial relative poses `pose_k⁻¹ pose_{k+delta}` (struct of arrays).
#[derive(Debug, Clone)]
struct RelativeWindows {
    translation: Vec<DVec3>,
    /// Empty for the translation relation.
    rotation: Vec<DQuat>,
}

impl RelativeWindows {
    fn new(trial: &Trajectory, delta: usize, with_rotation: bool) -> Self {
        let count = trial.len().saturating_sub(delta);
        let relative = |k: usize| RigidPose::relative(trial.pose(k), trial.pose(k + delta));
        let translation = (0..count).map(|k| relative(k).translation).collect();
        let rotation = if with_rotation {
            (0..count).map(|k| relative(k).rotation).collect()
        } else {
            Vec::new()
        };
        Self {
            translation,
            rotation,
        }
    }

    fn heap_bytes(&self) -> usize {
        self.translation.capacity() * size_of::<DVec3>()
            + self.rotation.capacity() * size_of::<DQuat>()
    }
}

/// Reusable per-thread buffers of [`PairIndex::fill_block`].
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch {
    translations: Vec<DVec3>,
    rotations: Vec<DQuat>,
}

/// The RPE value of two relative poses, as float bits (`+ 0.0` turns −0 into +0, so the
/// bit order of these non-negative values is their float order).
#[inline(always)]
fn value_bits(relation: PoseRelation, q: RigidPose, p: RigidPose) -> u64 {
    let value = match relation {
        // ‖Q_rel⁻¹P_rel‖ translation = ‖p_rel.t − q_rel.t‖ (a rotation keeps norms).
        PoseRelation::TranslationPart => (p.translation - q.translation).length(),
        _ => RigidPose::relative(q, p).error(relation),
    };
    (value + 0.0).to_bits()
}

/// `starts[b]` = first index whose key is in block `b` or later, for `b` in `0..=blocks`.
fn block_starts(keys: &[u32], blocks: usize) -> Vec<u32> {
    let mut starts = Vec::with_capacity(blocks + 1);
    let mut index = 0usize;
    for b in 0..=blocks {
        let limit = (b * BLOCK) as u32;
        while index < keys.len() && keys[index] < limit {
            index += 1;
        }
        starts.push(index as u32);
    }
    starts
}

/// The key index of every stamp (each one is a key).
fn key_indices(keys: &[i64], stamps: &[i64]) -> Vec<u32> {
    let mut cursor = 0usize;
    stamps
        .iter()
        .map(|&s| {
            // Stamps increase, so the cursor only moves forward.
            while keys[cursor] < s {
                cursor += 1;
            }
            cursor as u32
        })
        .collect()
}

fn stamps_hash(stamps: &[i64]) -> u64 {
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    stamps.hash(&mut hasher);
    hasher.finish()
}

/// How `reference` and `estimate` associate (without the key indices: see [`index_matching`]).
fn associate_pair(
    trials: &[Trajectory],
    (i, j): (usize, usize),
    identical: bool,
    options: &PairOptions,
) -> Result<Matching, Error> {
    let (reference, estimate) = (&trials[i], &trials[j]);
    let delta = options.delta;
    let mut matching = Matching::default();
    if identical {
        // Identical stamps associate one to one (each stamp is its own nearest).
        let len = reference.len().saturating_sub(delta) as u32;
        matching.segments.push(Segment {
            reference_start: 0,
            estimate_start: 0,
            len,
        });
        return Ok(matching);
    }
    let names = (format!("trial {i}"), format!("trial {j}"));
    let (ids_ref, ids_est) = associate_named(
        reference,
        estimate,
        options.t_max_diff_s,
        0.0,
        (&names.0, &names.1),
    )?;
    let count = ids_ref.len().saturating_sub(delta);
    let regular = |k: usize| {
        ids_ref[k + delta] == ids_ref[k] + delta && ids_est[k + delta] == ids_est[k] + delta
    };
    let mut k = 0;
    while k < count {
        if regular(k) {
            let start = k;
            k += 1;
            while k < count
                && regular(k)
                && ids_ref[k] == ids_ref[k - 1] + 1
                && ids_est[k] == ids_est[k - 1] + 1
            {
                k += 1;
            }
            matching.segments.push(Segment {
                reference_start: ids_ref[start] as u32,
                estimate_start: ids_est[start] as u32,
                len: (k - start) as u32,
            });
        } else {
            let (a0, a1, b0, b1) = (
                ids_ref[k],
                ids_ref[k + delta],
                ids_est[k],
                ids_est[k + delta],
            );
            matching
                .irregular
                .push([a0 as u32, a1 as u32, b0 as u32, b1 as u32]);
            k += 1;
        }
    }
    Ok(matching)
}

/// The key indices of a matching's broken windows (from its reference's keys).
fn index_matching(matching: &mut Matching, key_of: &[Vec<u32>], blocks: usize) {
    let keys = &key_of[matching.reference];
    matching.irregular_keys = matching
        .irregular
        .iter()
        .map(|w| keys[w[0] as usize])
        .collect();
    matching.irregular_block_starts = block_starts(&matching.irregular_keys, blocks);
}

impl PairIndex {
    /// An empty index.
    pub(crate) fn new(options: PairOptions) -> Self {
        Self {
            options,
            trials: 0,
            ranks: Vec::new(),
            keys: Vec::new(),
            ends: Vec::new(),
            end_ranks: Vec::new(),
            key_of: Vec::new(),
            trial_block_starts: Vec::new(),
            group_of: Vec::new(),
            groups_by_hash: HashMap::new(),
            groups: Vec::new(),
            relative: Vec::new(),
            matchings: Vec::new(),
            matching_index: HashMap::new(),
            pairs: Vec::new(),
        }
    }

    /// Trials indexed.
    pub(crate) fn trials(&self) -> usize {
        self.trials
    }

    /// Playback rank of each trial, in the order trials were added.
    pub(crate) fn ranks(&self) -> &[u64] {
        &self.ranks
    }

    /// Number of keys (window starts).
    pub(crate) fn key_count(&self) -> usize {
        self.keys.len()
    }

    /// Number of aggregation blocks.
    pub(crate) fn blocks(&self) -> usize {
        self.keys.len().div_ceil(BLOCK)
    }

    /// Start and end stamp of key `key`.
    pub(crate) fn window(&self, key: usize) -> (i64, i64) {
        (self.keys[key], self.ends[key])
    }

    /// Indexes `trials[self.trials()..]` (the earlier ones must be the trials indexed before,
    /// unchanged, and are not checked again), whose playback ranks are `new_ranks` (one per
    /// new trial; all ranks distinct), and replaces the stored pairs by the new pairs: every
    /// pair with a new trial, the one of lower rank its reference. Nothing changes on error.
    /// Returns the new index of every old key when new keys were inserted among them, `None`
    /// when the old key indices stand.
    pub(crate) fn extend(
        &mut self,
        trials: &[Trajectory],
        new_ranks: &[u64],
    ) -> Result<Option<Vec<u32>>, Error> {
        let old = self.trials;
        let n = trials.len();
        debug_assert_eq!(new_ranks.len(), n - old);
        let ranks: Vec<u64> = self.ranks.iter().chain(new_ranks).copied().collect();
        for (i, trial) in trials.iter().enumerate().skip(old) {
            validate_trial(i, trial)?;
        }
        // Groups of the new trials (tentative until nothing below can fail).
        let mut group_of = self.group_of.clone();
        let mut groups_by_hash = self.groups_by_hash.clone();
        for (i, trial) in trials.iter().enumerate().skip(old) {
            let list = groups_by_hash
                .entry(stamps_hash(&trial.stamps))
                .or_default();
            let group = match list.iter().find(|&&g| trials[g].stamps == trial.stamps) {
                Some(&g) => g,
                None => {
                    list.push(i);
                    i
                }
            };
            group_of.push(group);
        }
        // New pairs, as (reference, estimate), and the matchings they still need (the
        // fallible part: association).
        let orient = |i: usize, j: usize| if ranks[i] < ranks[j] { (i, j) } else { (j, i) };
        let new_pairs: Vec<(usize, usize)> = (old..n)
            .flat_map(|j| (0..j).map(move |i| orient(i, j)))
            .collect();
        let mut wanted: Vec<(usize, usize)> = Vec::new();
        let mut pending: HashMap<(usize, usize), usize> = HashMap::new();
        for &(i, j) in &new_pairs {
            let groups = (group_of[i], group_of[j]);
            if !self.matching_index.contains_key(&groups) && !pending.contains_key(&groups) {
                pending.insert(groups, self.matchings.len() + wanted.len());
                wanted.push((i, j));
            }
        }
        let options = self.options;
        let new_matchings = wanted
            .par_iter()
            .map(|&(i, j)| {
                let mut matching =
                    associate_pair(trials, (i, j), group_of[i] == group_of[j], &options)?;
                matching.reference = group_of[i];
                Ok(matching)
            })
            .collect::<Result<Vec<_>, Error>>()?;

        // From here on nothing fails.
        let with_rotation = options.relation != PoseRelation::TranslationPart;
        let fresh: Vec<RelativeWindows> = trials[old..]
            .par_iter()
            .map(|t| RelativeWindows::new(t, options.delta, with_rotation))
            .collect();
        self.relative.extend(fresh);
        self.group_of = group_of;
        self.groups_by_hash = groups_by_hash;
        let first_new_matching = self.matchings.len();
        self.matchings.extend(new_matchings);
        self.matching_index.extend(pending);
        self.ranks = ranks;
        let remap = self.add_keys(trials, old, n);
        self.trials = n;
        let blocks = self.blocks();
        if remap.is_some() {
            let key_of = &self.key_of;
            self.matchings
                .par_iter_mut()
                .for_each(|m| index_matching(m, key_of, blocks));
        } else {
            let key_of = &self.key_of;
            self.matchings[first_new_matching..]
                .par_iter_mut()
                .for_each(|m| index_matching(m, key_of, blocks));
        }
        self.update_groups(old, remap.is_some());
        self.pairs = self.irregular_pairs(trials, &new_pairs);
        Ok(remap)
    }

    /// Makes the stamps of trials `from..to` keys (re-indexing everything when some were not)
    /// and computes their key indices, block starts and the ends of their keys.
    fn add_keys(&mut self, trials: &[Trajectory], from: usize, to: usize) -> Option<Vec<u32>> {
        if from >= to {
            return None;
        }
        let delta = self.options.delta;
        let fresh_stamps = |keys: &[i64], t: &Trajectory| -> Vec<i64> {
            let mut cursor = 0;
            let mut missing = Vec::new();
            for &s in &t.stamps {
                while cursor < keys.len() && keys[cursor] < s {
                    cursor += 1;
                }
                if keys.get(cursor) != Some(&s) {
                    missing.push(s);
                }
            }
            missing
        };
        let mut added: Vec<i64> = Vec::new();
        for (index, t) in trials[from..to].iter().enumerate() {
            // Trials usually share their stamps: skip an identical stamp list.
            if index > 0 && t.stamps == trials[from + index - 1].stamps {
                continue;
            }
            if self.keys.is_empty() {
                added.extend_from_slice(&t.stamps);
            } else {
                added.extend(fresh_stamps(&self.keys, t));
            }
        }
        let reindex = !added.is_empty() && !self.keys.is_empty();
        let remap = if added.is_empty() {
            None
        } else {
            added.par_sort_unstable();
            added.dedup();
            let old_keys = std::mem::take(&mut self.keys);
            let mut keys = Vec::with_capacity(old_keys.len() + added.len());
            let mut remap = Vec::with_capacity(old_keys.len());
            let (mut a, mut b) = (0, 0);
            while a < old_keys.len() || b < added.len() {
                if b == added.len() || (a < old_keys.len() && old_keys[a] < added[b]) {
                    remap.push(keys.len() as u32);
                    keys.push(old_keys[a]);
                    a += 1;
                } else {
                    keys.push(added[b]);
                    b += 1;
                }
            }
            self.keys = keys;
            reindex.then_some(remap)
        };
        let keys = &self.keys;
        let first = if remap.is_some() || self.key_of.is_empty() {
            0
        } else {
            from
        };
        let fresh: Vec<Vec<u32>> = trials[first..to]
            .par_iter()
            .map(|t| key_indices(keys, &t.stamps))
            .collect();
        self.key_of.truncate(first);
        self.key_of.extend(fresh);
        if first == 0 || remap.is_some() {
            self.ends = vec![i64::MIN; self.keys.len()];
            self.end_ranks = vec![u64::MAX; self.keys.len()];
        }
        for (index, (t, ids)) in trials[first..to]
            .iter()
            .zip(&self.key_of[first..])
            .enumerate()
        {
            let rank = self.ranks[first + index];
            for (k, &key) in ids.iter().enumerate() {
                let key = key as usize;
                if rank < self.end_ranks[key] {
                    self.end_ranks[key] = rank;
                    self.ends[key] = t.stamps[k.saturating_add(delta).min(t.len() - 1)];
                }
            }
        }
        let blocks = self.blocks();
        let fresh: Vec<Vec<u32>> = self.key_of[first..]
            .par_iter()
            .map(|k| block_starts(k, blocks))
            .collect();
        self.trial_block_starts.truncate(first);
        self.trial_block_starts.extend(fresh);
        remap
    }

    /// Adds trials `old..` to their groups; (re)builds the key lookup of groups that just got
    /// their second member, or of all of them after a re-index.
    fn update_groups(&mut self, old: usize, reindexed: bool) {
        let key_count = self.keys.len();
        let pose_of_key = |key_of: &[u32]| {
            let mut pose_of_key = vec![u32::MAX; key_count];
            for (pose, &key) in key_of.iter().enumerate() {
                pose_of_key[key as usize] = pose as u32;
            }
            pose_of_key
        };
        for trial in old..self.trials {
            let first = self.group_of[trial];
            if first == trial {
                continue;
            }
            match self.groups.iter_mut().find(|g| g.members[0] == first) {
                Some(group) => group.members.push(trial),
                None => {
                    self.groups.push(Group {
                        members: vec![first, trial],
                        pose_of_key: pose_of_key(&self.key_of[first]),
                    });
                }
            }
        }
        self.groups.sort_by_key(|g| g.members[0]);
        if reindexed {
            let key_of = &self.key_of;
            self.groups
                .par_iter_mut()
                .for_each(|g| g.pose_of_key = pose_of_key(&key_of[g.members[0]]));
        }
    }

    /// The new pairs whose trials' stamps differ, with the values of their broken windows.
    fn irregular_pairs(&self, trials: &[Trajectory], new_pairs: &[(usize, usize)]) -> Vec<Pair> {
        let delta = self.options.delta;
        let relation = self.options.relation;
        let with_rotation = relation != PoseRelation::TranslationPart;
        let relative = &self.relative;
        new_pairs
            .par_iter()
            .filter(|&&(i, j)| self.group_of[i] != self.group_of[j])
            .map(|&(i, j)| {
                let matching = self.matching_index[&(self.group_of[i], self.group_of[j])];
                // A broken window is usually broken on one side only: the other side's
                // relative pose is the precomputed one.
                let relative_pose = |t: usize, from: u32, to: u32| {
                    let (from, to) = (from as usize, to as usize);
                    if to == from + delta {
                        let rotation = if with_rotation {
                            relative[t].rotation[from]
                        } else {
                            DQuat::IDENTITY
                        };
                        RigidPose {
                            rotation,
                            translation: relative[t].translation[from],
                        }
                    } else if with_rotation {
                        RigidPose::relative(trials[t].pose(from), trials[t].pose(to))
                    } else {
                        let (a, b) = (trials[t].pose(from), trials[t].pose(to));
                        let translation = a.rotation.conjugate() * (b.translation - a.translation);
                        RigidPose {
                            rotation: DQuat::IDENTITY,
                            translation,
                        }
                    }
                };
                let irregular_values = self.matchings[matching]
                    .irregular
                    .iter()
                    .map(|&[a0, a1, b0, b1]| {
                        value_bits(relation, relative_pose(i, a0, a1), relative_pose(j, b0, b1))
                    })
                    .collect();
                Pair {
                    reference: i,
                    estimate: j,
                    matching,
                    irregular_values,
                }
            })
            .collect()
    }

    /// Pushes the value of every pair with a trial added at or after `first_new` (in the order
    /// of adding) — of the stored pairs, and of the groups of identical stamps — into
    /// `buckets[key − block·BLOCK]` for the keys of block `block`. `buckets` is resized to
    /// [`BLOCK`] and cleared first.
    pub(crate) fn fill_block(
        &self,
        block: usize,
        first_new: usize,
        buckets: &mut Vec<Vec<u64>>,
        scratch: &mut Scratch,
    ) {
        let block_start = block * BLOCK;
        let block_len = BLOCK.min(self.keys.len() - block_start);
        let relation = self.options.relation;
        let with_rotation = relation != PoseRelation::TranslationPart;
        buckets.resize_with(BLOCK, Vec::new);
        buckets.iter_mut().for_each(Vec::clear);
        for pair in self
            .pairs
            .iter()
            .filter(|p| p.reference.max(p.estimate) >= first_new)
        {
            let starts = &self.trial_block_starts[pair.reference];
            let (low, high) = (starts[block], starts[block + 1]);
            let keys_of_reference = &self.key_of[pair.reference];
            let (q, p) = (
                &self.relative[pair.reference],
                &self.relative[pair.estimate],
            );
            let matching = &self.matchings[pair.matching];
            let first = matching
                .segments
                .partition_point(|s| s.reference_start + s.len <= low);
            for segment in &matching.segments[first..] {
                if segment.reference_start >= high {
                    break;
                }
                let from = segment.reference_start.max(low) as usize;
                let to = (segment.reference_start + segment.len).min(high) as usize;
                let shift = segment.estimate_start as usize;
                let (est_from, est_to) = (
                    from - segment.reference_start as usize + shift,
                    to - segment.reference_start as usize + shift,
                );
                let keys = &keys_of_reference[from..to];
                if with_rotation {
                    for ((a, b), &key) in (from..to).zip(est_from..est_to).zip(keys) {
                        let rq = RigidPose {
                            rotation: q.rotation[a],
                            translation: q.translation[a],
                        };
                        let rp = RigidPose {
                            rotation: p.rotation[b],
                            translation: p.translation[b],
                        };
                        buckets[key as usize - block_start].push(value_bits(relation, rq, rp));
                    }
                } else {
                    let translations = q.translation[from..to]
                        .iter()
                        .zip(&p.translation[est_from..est_to]);
                    for ((tq, tp), &key) in translations.zip(keys) {
                        let value = (*tp - *tq).length() + 0.0;
                        buckets[key as usize - block_start].push(value.to_bits());
                    }
                }
            }
            let range = matching.irregular_block_starts[block] as usize
                ..matching.irregular_block_starts[block + 1] as usize;
            for (&key, &value) in matching.irregular_keys[range.clone()]
                .iter()
                .zip(&pair.irregular_values[range])
            {
                buckets[key as usize - block_start].push(value);
            }
        }
        // Identity pairs, key by key: the group's poses at that key are gathered once
        // (a few kB, cache-resident) and every new pair inside the group is formed from them.
        let Scratch {
            translations,
            rotations,
        } = scratch;
        let groups: Vec<&Group> = self
            .groups
            .iter()
            .filter(|g| g.members.last().is_some_and(|&m| m >= first_new))
            .collect();
        for (offset, bucket) in buckets[..block_len].iter_mut().enumerate() {
            for group in &groups {
                let pose = group.pose_of_key[block_start + offset] as usize;
                if pose >= self.relative[group.members[0]].translation.len() {
                    continue; // not a stamp of this group, or fewer than delta frames after it
                }
                // Members before `newest` pair only with members from `newest` on.
                let newest = group.members.partition_point(|&m| m < first_new);
                translations.clear();
                translations.extend(
                    group
                        .members
                        .iter()
                        .map(|&t| self.relative[t].translation[pose]),
                );
                if with_rotation {
                    rotations.clear();
                    rotations.extend(
                        group
                            .members
                            .iter()
                            .map(|&t| self.relative[t].rotation[pose]),
                    );
                    let pose = |x: usize| RigidPose {
                        rotation: rotations[x],
                        translation: translations[x],
                    };
                    let ranks = &self.ranks;
                    for y in newest.max(1)..translations.len() {
                        let rank_y = ranks[group.members[y]];
                        for x in 0..y {
                            // The earlier trial in playback order is the reference.
                            let value = if ranks[group.members[x]] < rank_y {
                                value_bits(relation, pose(x), pose(y))
                            } else {
                                value_bits(relation, pose(y), pose(x))
                            };
                            bucket.push(value);
                        }
                    }
                } else {
                    // ‖a − b‖ = ‖b − a‖ to the bit: no orientation needed.
                    for (y, tp) in translations.iter().enumerate().skip(newest.max(1)) {
                        for tq in &translations[..y] {
                            bucket.push(((*tp - *tq).length() + 0.0).to_bits());
                        }
                    }
                }
            }
        }
    }

    /// Bytes held on the heap (capacities), for memory bounds.
    pub(crate) fn heap_bytes(&self) -> usize {
        let u32s = |v: &Vec<Vec<u32>>| {
            v.iter().map(|k| k.capacity() * 4).sum::<usize>() + v.capacity() * size_of::<Vec<u32>>()
        };
        let matchings: usize = self
            .matchings
            .iter()
            .map(|m| {
                m.segments.capacity() * size_of::<Segment>()
                    + m.irregular.capacity() * 16
                    + (m.irregular_keys.capacity() + m.irregular_block_starts.capacity()) * 4
            })
            .sum();
        let pairs: usize = self
            .pairs
            .iter()
            .map(|p| p.irregular_values.capacity() * 8 + size_of::<Pair>())
            .sum();
        let groups: usize = self
            .groups
            .iter()
            .map(|g| (g.members.capacity() * 8) + g.pose_of_key.capacity() * 4)
            .sum();
        (self.keys.capacity() + self.ends.capacity() + self.end_ranks.capacity()) * 8
            + self.ranks.capacity() * 8
            + u32s(&self.key_of)
            + u32s(&self.trial_block_starts)
            + self.group_of.capacity() * 8
            + self
                .relative
                .iter()
                .map(RelativeWindows::heap_bytes)
                .sum::<usize>()
            + matchings
            + self.matchings.capacity() * size_of::<Matching>()
            + self.matching_index.capacity() * 24
            + self.groups_by_hash.capacity() * 40
            + pairs
            + groups
    }
}
