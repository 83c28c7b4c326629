//! Pairwise uncertainty-based pose error estimation (the paper's section 3).
//!
//! Trials are ordered as given; for every pair `i < j` trial `i` is the reference, the two are
//! associated as evo does, and an all-pairs RPE with a delta of `delta` frames is computed on the
//! associated poses. Every value is keyed by the reference's start stamp; per key a robust
//! statistic over all pairs with that key is the window's error estimate.
//!
//! Speed: an RPE value only needs the two trials' *relative* poses over the window, so they are
//! computed once per trial (`rel[k] = pose_k⁻¹ pose_{k+delta}`) and reused by every pair whose
//! association keeps the window contiguous; only windows broken by a dropped frame are
//! recomputed from the poses. Pairs and windows run in parallel (rayon).

use std::collections::HashMap;

use glam::{DQuat, DVec3};
use rayon::prelude::*;

use crate::metrics::RigidPose;
use crate::sync::associate_named;
use crate::{Error, PoseRelation, Setting, Thresholds, TimeUnit, Trajectory, statistics};

/// Options of [`estimate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimateOptions {
    /// Per-window statistic over the pair values (default `trim_mean_30`).
    pub setting: Setting,
    /// RPE delta in frames (default 10).
    pub delta: usize,
    /// Association tolerance in seconds (default 0.01).
    pub t_max_diff_s: f64,
    /// Pose relation of the RPE (default translation part; `RotationAngleDeg` gives the
    /// rotational estimate, in degrees).
    pub pose_relation: PoseRelation,
}

impl Default for EstimateOptions {
    fn default() -> Self {
        Self {
            setting: Setting::default(),
            delta: 10,
            t_max_diff_s: 0.01,
            pose_relation: PoseRelation::TranslationPart,
        }
    }
}

/// One estimated window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowEstimate {
    /// Start stamp (ns): the reference trials' stamp where the window starts.
    pub start: i64,
    /// End stamp (ns): `delta` frames after `start` in the first trial that has `start`.
    pub end: i64,
    /// The statistic over the pair values (metres; degrees/radians for rotational relations).
    pub error_m: f64,
    /// Number of pair values aggregated.
    pub pairs: usize,
    /// Population standard deviation of the pair values (how much the trials disagree).
    pub spread_m: f64,
}

/// The result of [`estimate`]: windows sorted by start.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The statistic used.
    pub setting: Setting,
    /// Number of trials.
    pub trials: usize,
    /// Time unit of the trials (the first trial's), used for the CSV.
    pub time_unit: TimeUnit,
    /// The pose relation of the RPE.
    pub pose_relation: PoseRelation,
    /// Windows, sorted by start.
    pub windows: Vec<WindowEstimate>,
}

impl Estimate {
    /// Legacy CSV: `start,error` header, one row per window, start in the trials' time unit,
    /// error with full round-trip precision.
    pub fn to_legacy_csv(&self) -> String {
        let mut out = String::with_capacity(32 * (self.windows.len() + 1));
        out.push_str("start,error\n");
        for w in &self.windows {
            out.push_str(&self.time_unit.format_stamp(w.start));
            out.push(',');
            out.push_str(&w.error_m.to_string());
            out.push('\n');
        }
        out
    }

    /// JSON: `{"version":1,"setting":…,"trials":n,"time_unit":"ns"|"s","pose_relation":…,
    /// "windows":[{"start","end","error_m","pairs","spread_m","class"}]}`; `start`/`end` keep
    /// the trials' unit, written exactly: integer nanoseconds, or seconds with 9 decimals.
    /// For rotational relations the error keys are `error_deg`/`error_rad`
    /// (`spread_deg`/`spread_rad`) and `class` is omitted.
    pub fn to_json(&self, thresholds: Thresholds) -> String {
        /// One window: the stamps as exact number text, the rest as values.
        #[derive(serde::Serialize)]
        struct Window {
            start: Box<serde_json::value::RawValue>,
            end: Box<serde_json::value::RawValue>,
            #[serde(flatten)]
            values: serde_json::Map<String, serde_json::Value>,
        }
        let stamp = |t: i64| {
            // A plain decimal number is always valid JSON number text.
            serde_json::value::RawValue::from_string(self.time_unit.format_stamp(t))
                .expect("a formatted stamp is a JSON number")
        };
        let (error_key, spread_key) = match self.pose_relation {
            PoseRelation::TranslationPart => ("error_m", "spread_m"),
            PoseRelation::RotationAngleDeg => ("error_deg", "spread_deg"),
            PoseRelation::RotationAngleRad => ("error_rad", "spread_rad"),
            _ => ("error", "spread"),
        };
        let translation = self.pose_relation == PoseRelation::TranslationPart;
        let windows: Vec<Window> = self
            .windows
            .iter()
            .map(|w| {
                let mut o = serde_json::Map::new();
                o.insert(error_key.into(), json_number(w.error_m));
                o.insert("pairs".into(), w.pairs.into());
                o.insert(spread_key.into(), json_number(w.spread_m));
                if translation {
                    o.insert("class".into(), thresholds.classify(w.error_m).name().into());
                }
                Window {
                    start: stamp(w.start),
                    end: stamp(w.end),
                    values: o,
                }
            })
            .collect();
        // Serialized as a struct: through a `Value` the raw stamps would become floats again.
        #[derive(serde::Serialize)]
        struct Document {
            version: u32,
            setting: String,
            trials: usize,
            time_unit: &'static str,
            pose_relation: String,
            windows: Vec<Window>,
        }
        let document = Document {
            version: 1,
            setting: self.setting.to_string(),
            trials: self.trials,
            time_unit: match self.time_unit {
                TimeUnit::Nanoseconds => "ns",
                TimeUnit::Seconds => "s",
            },
            pose_relation: self.pose_relation.to_string(),
            windows,
        };
        serde_json::to_string(&document).expect("plain data serializes")
    }
}

fn json_number(v: f64) -> serde_json::Value {
    serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

/// Estimates the per-window pose error of `trials` (at least 2) without ground truth.
pub fn estimate(trials: &[Trajectory], opts: &EstimateOptions) -> Result<Estimate, Error> {
    Ok(PairwiseValues::compute(trials, opts)?.estimate(opts.setting))
}

/// All pairwise RPE inputs of a set of trials, grouped for aggregation, from which an
/// [`Estimate`] for any [`Setting`] is cheap to derive.
///
/// Pairs whose trials have identical stamps (the usual case: trials replay one recording)
/// associate one to one; their values are computed on the fly during aggregation from the
/// per-trial relative poses, so nothing per pair is stored. Other pairs are associated as evo
/// does and their values stored.
#[derive(Debug, Clone)]
pub struct PairwiseValues {
    trials: usize,
    time_unit: TimeUnit,
    pose_relation: PoseRelation,
    delta: usize,
    /// Sorted, distinct window start stamps (ns).
    keys: Vec<i64>,
    /// End stamp per key.
    ends: Vec<i64>,
    /// Per reference trial (all but the last): the key index of each of its poses.
    key_of: Vec<Vec<u32>>,
    /// Per reference trial: `[b]` = first pose whose key is in block `b` or later.
    trial_block_starts: Vec<Vec<u32>>,
    groups: Vec<Group>,
    /// Per trial: relative poses over `delta` frames.
    relative: Vec<RelativeWindows>,
    matchings: Vec<Matching>,
    pairs: Vec<Pair>,
}

/// Keys per aggregation block (a block's buckets stay cache-sized).
const BLOCK: usize = 128;

/// One pair: its trials, the matching of their stamps, and the values of the windows the
/// matching could not cover with segments.
#[derive(Debug, Clone)]
struct Pair {
    reference: usize,
    estimate: usize,
    /// Index into `PairwiseValues::matchings`.
    matching: usize,
    /// Values (float bits) of `matchings[matching].irregular`, in the same order.
    irregular_values: Vec<u64>,
    /// Both trials have identical stamps: aggregated key by key through `groups` instead.
    identity: bool,
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

impl PairwiseValues {
    /// Prepares all n(n−1)/2 pairwise RPEs (`opts.setting` is not used here).
    pub fn compute(trials: &[Trajectory], opts: &EstimateOptions) -> Result<Self, Error> {
        if trials.len() < 2 {
            return Err(Error::InvalidArgument(format!(
                "need at least 2 trials, got {}",
                trials.len()
            )));
        }
        if opts.delta == 0 {
            return Err(Error::InvalidArgument(
                "delta must be at least 1 frame".into(),
            ));
        }
        if !(opts.t_max_diff_s.is_finite() && opts.t_max_diff_s >= 0.0) {
            return Err(Error::InvalidArgument(format!(
                "t_max_diff must be a finite, non-negative number of seconds, got {}",
                opts.t_max_diff_s
            )));
        }
        if let Some(i) = trials.iter().position(|t| t.is_empty()) {
            return Err(Error::InvalidArgument(format!("trial {i} has no poses")));
        }
        for (i, trial) in trials.iter().enumerate() {
            trial
                .validate()
                .map_err(|e| Error::InvalidArgument(format!("trial {i}: {e}")))?;
        }
        let delta = opts.delta;
        let relation = opts.pose_relation;
        let with_rotation = relation != PoseRelation::TranslationPart;
        let relative: Vec<RelativeWindows> = trials
            .par_iter()
            .map(|t| RelativeWindows::new(t, delta, with_rotation))
            .collect();

        // Keys: the distinct stamps of every trial that is a reference somewhere (all but the last).
        let references = &trials[..trials.len() - 1];
        let mut keys: Vec<i64> = Vec::with_capacity(references.len() * trials[0].len());
        for (index, t) in references.iter().enumerate() {
            // Trials usually share their stamps: skip re-adding an identical stamp list.
            if index == 0 || t.stamps != references[index - 1].stamps {
                keys.extend_from_slice(&t.stamps);
            }
        }
        keys.par_sort_unstable();
        keys.dedup();
        if keys.len() >= u32::MAX as usize {
            return Err(Error::InvalidArgument("too many distinct stamps".into()));
        }
        let key_of: Vec<Vec<u32>> = references
            .par_iter()
            .map(|t| {
                let mut cursor = 0usize;
                t.stamps
                    .iter()
                    .map(|&s| {
                        // Stamps increase, so the cursor only moves forward.
                        while keys[cursor] < s {
                            cursor += 1;
                        }
                        cursor as u32
                    })
                    .collect()
            })
            .collect();
        let mut ends = vec![i64::MIN; keys.len()];
        for (t, ids) in references.iter().zip(&key_of) {
            for (k, &key) in ids.iter().enumerate() {
                let end = &mut ends[key as usize];
                if *end == i64::MIN {
                    *end = t.stamps[k.saturating_add(delta).min(t.len() - 1)];
                }
            }
        }
        let blocks = keys.len().div_ceil(BLOCK);
        let trial_block_starts = key_of.iter().map(|k| block_starts(k, blocks)).collect();

        // Group trials by identical stamp lists: matchings depend only on the stamps.
        let mut group_of_stamps: HashMap<&[i64], usize> = HashMap::new();
        let group: Vec<usize> = trials
            .iter()
            .enumerate()
            .map(|(i, t)| *group_of_stamps.entry(&t.stamps[..]).or_insert(i))
            .collect();
        let n = trials.len();
        let pair_ids: Vec<(usize, usize)> = (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .collect();
        let mut matching_index: HashMap<(usize, usize), usize> = HashMap::new();
        let mut matching_pairs: Vec<(usize, usize)> = Vec::new();
        for &(i, j) in &pair_ids {
            matching_index
                .entry((group[i], group[j]))
                .or_insert_with(|| {
                    matching_pairs.push((i, j));
                    matching_pairs.len() - 1
                });
        }
        let matchings = matching_pairs
            .par_iter()
            .map(|&(i, j)| {
                let (reference, estimate) = (&trials[i], &trials[j]);
                let mut matching = Matching::default();
                if group[i] == group[j] {
                    // Identical stamps associate one to one (each stamp is its own nearest).
                    let len = reference.len().saturating_sub(delta) as u32;
                    matching.segments.push(Segment {
                        reference_start: 0,
                        estimate_start: 0,
                        len,
                    });
                    matching.irregular_block_starts = vec![0; blocks + 1];
                    return Ok(matching);
                }
                let names = (format!("trial {i}"), format!("trial {j}"));
                let (ids_ref, ids_est) = associate_named(
                    reference,
                    estimate,
                    opts.t_max_diff_s,
                    0.0,
                    (&names.0, &names.1),
                )?;
                let count = ids_ref.len().saturating_sub(delta);
                let regular = |k: usize| {
                    ids_ref[k + delta] == ids_ref[k] + delta
                        && ids_est[k + delta] == ids_est[k] + delta
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
                        matching.irregular_keys.push(key_of[i][a0]);
                        k += 1;
                    }
                }
                matching.irregular_block_starts = block_starts(&matching.irregular_keys, blocks);
                Ok(matching)
            })
            .collect::<Result<Vec<_>, Error>>()?;
        let pairs = pair_ids
            .par_iter()
            .map(|&(i, j)| {
                let matching = matching_index[&(group[i], group[j])];
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
                let irregular_values = matchings[matching]
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
                    identity: group[i] == group[j],
                }
            })
            .collect();
        let mut members_of: HashMap<usize, Vec<usize>> = HashMap::new();
        for (trial, &g) in group.iter().enumerate() {
            members_of.entry(g).or_default().push(trial);
        }
        let mut groups: Vec<Group> = members_of
            .into_values()
            .filter(|members| members.len() >= 2)
            .map(|members| {
                // The first member is a reference trial (it has a later partner), so it has keys.
                let mut pose_of_key = vec![u32::MAX; keys.len()];
                for (pose, &key) in key_of[members[0]].iter().enumerate() {
                    pose_of_key[key as usize] = pose as u32;
                }
                Group {
                    members,
                    pose_of_key,
                }
            })
            .collect();
        groups.sort_by_key(|g| g.members[0]);

        Ok(Self {
            trials: n,
            time_unit: trials[0].time_unit,
            pose_relation: relation,
            delta,
            keys,
            ends,
            key_of,
            trial_block_starts,
            groups,
            relative,
            matchings,
            pairs,
        })
    }

    /// Aggregates the pair values per window with `setting`.
    pub fn estimate(&self, setting: Setting) -> Estimate {
        let blocks = self.keys.len().div_ceil(BLOCK);
        let relation = self.pose_relation;
        let with_rotation = relation != PoseRelation::TranslationPart;
        // Buckets are reused per worker thread: fresh ones for every block would be page
        // faults all over again.
        let per_block: Vec<Vec<WindowEstimate>> = (0..blocks)
            .into_par_iter()
            .map_init(
                || {
                    (
                        Vec::<Vec<u64>>::new(),
                        Vec::<DVec3>::new(),
                        Vec::<DQuat>::new(),
                    )
                },
                |(buckets, translations, rotations), block| {
                    let block_start = block * BLOCK;
                    let block_len = BLOCK.min(self.keys.len() - block_start);
                    buckets.resize_with(BLOCK, || Vec::with_capacity(self.pairs.len()));
                    buckets.iter_mut().for_each(Vec::clear);
                    for pair in self.pairs.iter().filter(|p| !p.identity) {
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
                                    buckets[key as usize - block_start]
                                        .push(value_bits(relation, rq, rp));
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
                    // (a few kB, cache-resident) and every pair inside the group is formed from them.
                    for (offset, bucket) in buckets[..block_len].iter_mut().enumerate() {
                        for group in &self.groups {
                            let pose = group.pose_of_key[block_start + offset] as usize;
                            if pose >= self.relative[group.members[0]].translation.len() {
                                continue; // not a stamp of this group, or fewer than delta frames after it
                            }
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
                                for x in 0..translations.len() {
                                    let q = RigidPose {
                                        rotation: rotations[x],
                                        translation: translations[x],
                                    };
                                    for y in x + 1..translations.len() {
                                        let p = RigidPose {
                                            rotation: rotations[y],
                                            translation: translations[y],
                                        };
                                        bucket.push(value_bits(relation, q, p));
                                    }
                                }
                            } else {
                                for (x, tq) in translations.iter().enumerate() {
                                    for tp in &translations[x + 1..] {
                                        bucket.push(((*tp - *tq).length() + 0.0).to_bits());
                                    }
                                }
                            }
                        }
                    }
                    buckets[..block_len]
                        .iter_mut()
                        .enumerate()
                        .filter(|(_, values)| !values.is_empty())
                        .map(|(offset, values)| {
                            let key = block_start + offset;
                            let (error, spread) =
                                statistics::bits::window_statistics(values, setting);
                            WindowEstimate {
                                start: self.keys[key],
                                end: self.ends[key],
                                error_m: error,
                                pairs: values.len(),
                                spread_m: spread,
                            }
                        })
                        .collect::<Vec<_>>()
                },
            )
            .collect();
        let windows = per_block.into_iter().flatten().collect();
        Estimate {
            setting,
            trials: self.trials,
            time_unit: self.time_unit,
            pose_relation: self.pose_relation,
            windows,
        }
    }

    /// The RPE delta (frames) these values were computed with.
    pub fn delta(&self) -> usize {
        self.delta
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trial(n: usize, wobble: f64) -> Trajectory {
        Trajectory {
            stamps: (0..n as i64)
                .map(|i| 1_000_000_000 + i * 33_333_333)
                .collect(),
            positions: (0..n)
                .map(|i| DVec3::new(i as f64 * 0.01, (i as f64 * wobble).sin() * wobble, 0.0))
                .collect(),
            orientations: (0..n)
                .map(|i| DQuat::from_rotation_y(i as f64 * 0.01))
                .collect(),
            time_unit: TimeUnit::Nanoseconds,
        }
    }

    #[test]
    fn identical_trials_have_zero_error() {
        let t = trial(30, 0.0);
        let e = estimate(&[t.clone(), t.clone(), t], &EstimateOptions::default()).unwrap();
        assert_eq!(e.windows.len(), 20);
        assert!(
            e.windows
                .iter()
                .all(|w| w.error_m.abs() < 1e-15 && w.pairs == 3)
        );
        assert_eq!(e.windows[0].end, 1_000_000_000 + 10 * 33_333_333);
        assert!(e.to_legacy_csv().starts_with("start,error\n1000000000,0"));
    }

    #[test]
    fn single_pair_equals_rpe() {
        let (a, b) = (trial(40, 0.0), trial(40, 0.3));
        let e = estimate(&[a.clone(), b.clone()], &EstimateOptions::default()).unwrap();
        let r = crate::rpe(&a, &b, &crate::RpeOptions::default()).unwrap();
        assert_eq!(e.windows.len(), r.errors.len());
        for (w, v) in e.windows.iter().zip(&r.errors) {
            assert!((w.error_m - v).abs() < 1e-12);
        }
    }

    #[test]
    fn csv_and_json_outputs() {
        let (mut a, mut b) = (trial(25, 0.0), trial(25, 0.4));
        a.time_unit = TimeUnit::Seconds;
        b.time_unit = TimeUnit::Seconds;
        let e = estimate(&[a, b], &EstimateOptions::default()).unwrap();
        let csv = e.to_legacy_csv();
        let second_row = csv.lines().nth(2).unwrap();
        assert!(second_row.starts_with("1.033333333,"), "{second_row}");
        assert_eq!(
            second_row
                .split(',')
                .nth(1)
                .unwrap()
                .parse::<f64>()
                .unwrap(),
            e.windows[1].error_m
        );
        let thresholds = Thresholds::new(e.windows[0].error_m, e.windows[0].error_m * 2.0);
        let text = e.to_json(thresholds);
        // Seconds in, seconds out: exact, with 9 decimals (as the CSV).
        assert!(
            text.contains(r#""start":1.000000000,"end":1.333333330,"#),
            "{text}"
        );
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(json["version"], 1);
        assert_eq!(json["setting"], "trim_mean_30");
        assert_eq!(json["trials"], 2);
        assert_eq!(json["time_unit"], "s");
        let first = &json["windows"][0];
        assert_eq!(first["start"].as_f64(), Some(1.0));
        assert_eq!(first["pairs"], 1);
        assert_eq!(first["error_m"].as_f64().unwrap(), e.windows[0].error_m);
        assert_eq!(first["class"], "medium");
        let classes: Vec<&str> = json["windows"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| w["class"].as_str().unwrap())
            .collect();
        let expected: Vec<&str> = e
            .windows
            .iter()
            .map(|w| thresholds.classify(w.error_m).name())
            .collect();
        assert_eq!(classes, expected);
        let rotational = estimate(
            &[trial(25, 0.0), trial(25, 0.4)],
            &EstimateOptions {
                pose_relation: PoseRelation::RotationAngleDeg,
                ..EstimateOptions::default()
            },
        )
        .unwrap();
        let text = rotational.to_json(Thresholds::default());
        // Nanoseconds in, integer nanoseconds out.
        assert!(
            text.contains(r#""start":1000000000,"end":1333333330,"#),
            "{text}"
        );
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(json["time_unit"], "ns");
        assert!(
            json["windows"][0]["error_deg"].is_number()
                && json["windows"][0].get("class").is_none()
        );
    }

    #[test]
    fn huge_delta_gives_no_windows_not_a_panic() {
        let opts = EstimateOptions {
            delta: usize::MAX,
            ..EstimateOptions::default()
        };
        let e = estimate(&[trial(20, 0.0), trial(20, 0.1)], &opts).unwrap();
        assert!(e.windows.is_empty());
    }

    #[test]
    fn rejects_too_few_trials() {
        assert!(estimate(&[trial(20, 0.0)], &EstimateOptions::default()).is_err());
        let mut unsorted = trial(20, 0.0);
        unsorted.stamps.swap(3, 4);
        assert!(matches!(
            estimate(&[trial(20, 0.0), unsorted], &EstimateOptions::default()),
            Err(Error::InvalidArgument(_))
        ));
        let negative = EstimateOptions {
            t_max_diff_s: -1.0,
            ..EstimateOptions::default()
        };
        assert!(estimate(&[trial(20, 0.0), trial(20, 0.0)], &negative).is_err());
        let mut short = trial(20, 0.0);
        short.positions.pop();
        assert!(estimate(&[short, trial(20, 0.0)], &EstimateOptions::default()).is_err());
    }

    /// The definition, written plainly: per pair associate, RPE, bucket by reference stamp.
    fn naive(trials: &[Trajectory], opts: &EstimateOptions) -> Vec<(i64, f64, usize)> {
        let mut buckets: std::collections::BTreeMap<i64, Vec<f64>> = Default::default();
        let rpe_opts = crate::RpeOptions {
            pose_relation: opts.pose_relation,
            delta: opts.delta as f64,
            ..Default::default()
        };
        for i in 0..trials.len() {
            for j in i + 1..trials.len() {
                let (r, e) =
                    crate::associate_trajectories(&trials[i], &trials[j], opts.t_max_diff_s, 0.0)
                        .unwrap();
                if let Ok(result) = crate::rpe(&r, &e, &rpe_opts) {
                    for (&(a, _), v) in result.pairs.iter().zip(result.errors) {
                        buckets.entry(r.stamps[a]).or_default().push(v);
                    }
                }
            }
        }
        buckets
            .into_iter()
            .map(|(k, mut v)| (k, opts.setting.apply(&mut v), v.len()))
            .collect()
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        #[test]
        fn fast_paths_equal_the_plain_definition(
            seed in proptest::collection::vec(-1.0f64..1.0, 6 * 5 * 40),
            drops in proptest::collection::vec(0usize..40, 0..6),
            jitter in proptest::collection::vec(-14_000_000i64..14_000_000, 0..4),
            n in 2usize..6, len in 12usize..40, which in 0usize..7, rotational: bool,
        ) {
            let mut trials = Vec::new();
            for t in 0..n {
                let base = &seed[t * 6 * 40..];
                let mut trial = Trajectory {
                    stamps: (0..len as i64).map(|k| 5_000_000_000 + k * 33_333_333).collect(),
                    positions: (0..len).map(|k| DVec3::new(k as f64 * 0.02 + base[6 * k], base[6 * k + 1], base[6 * k + 2]) * 0.5).collect(),
                    orientations: (0..len).map(|k| DQuat::from_scaled_axis(DVec3::new(base[6 * k + 3], base[6 * k + 4], base[6 * k + 5]) * 0.3)).collect(),
                    time_unit: TimeUnit::Nanoseconds,
                };
                // Trial 1 drops frames, trial 2 has jittered stamps (some beyond 10 ms).
                if t == 1 {
                    let keep: Vec<usize> = (0..len).filter(|k| !drops.contains(k)).collect();
                    trial = trial.reduce_to_ids(&keep);
                }
                if t == 2 {
                    for (k, j) in jitter.iter().enumerate() {
                        trial.stamps[3 + 7 * k % (len - 4)] += j;
                    }
                    let mut order: Vec<usize> = (0..trial.len()).collect();
                    order.sort_by_key(|&k| trial.stamps[k]);
                    trial = trial.reduce_to_ids(&order);
                    trial.stamps.dedup();
                    if trial.stamps.len() != trial.positions.len() { continue; }
                }
                trials.push(trial);
            }
            proptest::prop_assume!(trials.len() >= 2);
            let opts = EstimateOptions {
                setting: Setting::ALL[which],
                delta: 3,
                pose_relation: if rotational { PoseRelation::RotationAngleDeg } else { PoseRelation::TranslationPart },
                ..EstimateOptions::default()
            };
            let fast = estimate(&trials, &opts).unwrap();
            let plain = naive(&trials, &opts);
            proptest::prop_assert_eq!(fast.windows.len(), plain.len());
            for (w, (start, value, pairs)) in fast.windows.iter().zip(&plain) {
                proptest::prop_assert_eq!(w.start, *start);
                proptest::prop_assert_eq!(w.pairs, *pairs);
                proptest::prop_assert!((w.error_m - value).abs() <= 1e-9, "{} vs {}", w.error_m, value);
            }
        }
    }
}
