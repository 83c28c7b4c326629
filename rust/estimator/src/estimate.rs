//! Pairwise uncertainty-based pose error estimation (the paper's section 3).
//!
//! Trials are ordered as given; for every pair `i < j` trial `i` is the reference, the two are
//! associated as evo does, and an all-pairs RPE with a delta of `delta` frames is computed on the
//! associated poses. Every value is keyed by the reference's start stamp; per key a robust
//! statistic over all pairs with that key is the window's error estimate.
//!
//! The pairs are indexed by [`crate::pairwise`] (shared with the incremental estimate) and
//! aggregated block by block in parallel (rayon); each window's statistic is a function of
//! the multiset of its values alone ([`crate::statistics::bits`]).

use rayon::prelude::*;

use crate::pairwise::{BLOCK, PairIndex, PairOptions, Scratch};
use crate::{Error, PoseRelation, Setting, Target, Thresholds, TimeUnit, Trajectory, statistics};

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

impl EstimateOptions {
    /// The pairing part of the options, checked.
    pub(crate) fn pair_options(&self) -> Result<PairOptions, Error> {
        PairOptions::new(self.delta, self.t_max_diff_s, self.pose_relation)
    }
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
    /// Set by [`crate::ApplyCalibration::apply`] and [`crate::estimate_live`]: the
    /// uncalibrated value and the interval; `error_m` is then the calibrated value.
    pub interval: Option<WindowInterval>,
}

/// A calibrated window's uncalibrated value and the interval that holds its true error with
/// the calibration's coverage (same unit as `error_m`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowInterval {
    /// The estimate before calibration (JSON `raw_m`).
    pub raw_m: f64,
    /// Lower bound (JSON `lower_m`).
    pub lower_m: f64,
    /// Upper bound (JSON `upper_m`).
    pub upper_m: f64,
}

/// How an estimate was calibrated: the target its model estimates and whether that model's
/// runs predict the error at all (JSON `target`, `informative`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CalibratedAs {
    /// The error estimated.
    pub target: Target,
    /// `false`: the calibration's runs did not predict the error; the values are a guess.
    pub informative: bool,
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
    /// The RPE delta in frames: every window spans this many frames (JSON `window_frames`).
    pub delta: usize,
    /// Windows, sorted by start.
    pub windows: Vec<WindowEstimate>,
    /// The name of the calibration applied (JSON `calibration`), if any.
    pub calibration: Option<String>,
    /// What the calibration estimated (JSON `target` and `informative`), if applied.
    pub calibrated_as: Option<CalibratedAs>,
    /// Where the estimate comes from (JSON `source`: `walk` or `replays`), where the caller
    /// says (the backend does).
    pub source: Option<&'static str>,
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
    /// "window_frames":delta,"unit":…,"windows":[{"start","end","error_m","pairs","spread_m",
    /// "class"}]}`; `start`/`end` keep the trials' unit, written exactly: integer nanoseconds,
    /// or seconds with 9 decimals. `unit` is the unit of the window values: `m` for
    /// `trans_part`, `deg` for `angle_deg` (keys `error_deg`/`spread_deg`), `rad` for
    /// `angle_rad` (`error_rad`/`spread_rad`), `unit-less` for `full` (`error`/`spread`), as
    /// evo names them. `class` comes from `thresholds`, which are in that unit; it is given for
    /// `trans_part` and `angle_deg` windows (the two the phone colours) and omitted otherwise.
    /// A calibrated estimate names its calibration (`calibration`), the error it estimates
    /// (`target`: `live` or `expected`), whether the calibration's runs predict the error at
    /// all (`informative`) and the number of runs (`runs`); `source` (`walk` or `replays`)
    /// where the caller set it.
    pub fn to_json(&self, thresholds: Thresholds) -> String {
        let (error_key, spread_key, unit) = match self.pose_relation {
            PoseRelation::TranslationPart => ("error_m", "spread_m", "m"),
            PoseRelation::RotationAngleDeg => ("error_deg", "spread_deg", "deg"),
            PoseRelation::RotationAngleRad => ("error_rad", "spread_rad", "rad"),
            _ => ("error", "spread", "unit-less"),
        };
        let interval_keys = match self.pose_relation {
            PoseRelation::TranslationPart => ["raw_m", "lower_m", "upper_m"],
            PoseRelation::RotationAngleDeg => ["raw_deg", "lower_deg", "upper_deg"],
            PoseRelation::RotationAngleRad => ["raw_rad", "lower_rad", "upper_rad"],
            _ => ["raw", "lower", "upper"],
        };
        let classified = matches!(
            self.pose_relation,
            PoseRelation::TranslationPart | PoseRelation::RotationAngleDeg
        );
        let windows: Vec<WindowJson<'_>> = self
            .windows
            .iter()
            .map(|window| WindowJson {
                start: self.time_unit.format_stamp(window.start),
                end: self.time_unit.format_stamp(window.end),
                window,
                keys: (error_key, spread_key, interval_keys),
                class: classified.then(|| thresholds.classify(window.error_m).name()),
            })
            .collect();
        // Serialized as a struct: through a `Value` the raw stamps would become floats again.
        #[derive(serde::Serialize)]
        struct Document<'a> {
            version: u32,
            setting: String,
            trials: usize,
            time_unit: &'static str,
            pose_relation: String,
            window_frames: usize,
            unit: &'static str,
            #[serde(skip_serializing_if = "Option::is_none")]
            calibration: Option<&'a str>,
            #[serde(skip_serializing_if = "Option::is_none")]
            target: Option<&'static str>,
            #[serde(skip_serializing_if = "Option::is_none")]
            informative: Option<bool>,
            #[serde(skip_serializing_if = "Option::is_none")]
            source: Option<&'static str>,
            #[serde(skip_serializing_if = "Option::is_none")]
            runs: Option<usize>,
            windows: Vec<WindowJson<'a>>,
        }
        let document = Document {
            version: 1,
            setting: self.setting.to_string(),
            trials: self.trials,
            time_unit: match self.time_unit {
                TimeUnit::Nanoseconds => "ns",
                TimeUnit::Seconds | TimeUnit::RosStamp => "s",
            },
            pose_relation: self.pose_relation.to_string(),
            window_frames: self.delta,
            unit,
            calibration: self.calibration.as_deref(),
            target: self.calibrated_as.map(|c| c.target.name()),
            informative: self.calibrated_as.map(|c| c.informative),
            source: self.source,
            runs: (self.calibrated_as.is_some() || self.source.is_some()).then_some(self.trials),
            windows,
        };
        serde_json::to_string(&document).expect("plain data serializes")
    }
}

/// One window of the JSON: `start` and `end` as exact number text, then the values in
/// alphabetical key order (`class`, error, `lower`, `pairs`, `raw`, spread, `upper`), written straight from the window
/// (a progressive server writes thousands of them after every trial).
struct WindowJson<'a> {
    start: String,
    end: String,
    window: &'a WindowEstimate,
    /// The error's and the spread's keys in the estimate's unit, and the interval's
    /// (`raw`, `lower`, `upper`).
    keys: (&'static str, &'static str, [&'static str; 3]),
    class: Option<&'static str>,
}

impl serde::Serialize for WindowJson<'_> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        /// A number that is not finite is `null` (JSON has no NaN).
        fn finite(v: f64) -> Option<f64> {
            v.is_finite().then_some(v)
        }
        /// A plain decimal number is always valid JSON number text.
        fn raw(text: &str) -> Result<&serde_json::value::RawValue, serde_json::Error> {
            serde_json::from_str(text)
        }
        let mut map = serializer.serialize_map(None)?;
        map.serialize_entry(
            "start",
            raw(&self.start).map_err(serde::ser::Error::custom)?,
        )?;
        map.serialize_entry("end", raw(&self.end).map_err(serde::ser::Error::custom)?)?;
        if let Some(class) = self.class {
            map.serialize_entry("class", class)?;
        }
        map.serialize_entry(self.keys.0, &finite(self.window.error_m))?;
        if let Some(interval) = &self.window.interval {
            map.serialize_entry(self.keys.2[1], &finite(interval.lower_m))?;
        }
        map.serialize_entry("pairs", &self.window.pairs)?;
        if let Some(interval) = &self.window.interval {
            map.serialize_entry(self.keys.2[0], &finite(interval.raw_m))?;
        }
        map.serialize_entry(self.keys.1, &finite(self.window.spread_m))?;
        if let Some(interval) = &self.window.interval {
            map.serialize_entry(self.keys.2[2], &finite(interval.upper_m))?;
        }
        map.end()
    }
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
/// does and only the values of their windows broken by a dropped frame are stored.
#[derive(Debug, Clone)]
pub struct PairwiseValues {
    time_unit: TimeUnit,
    pose_relation: PoseRelation,
    delta: usize,
    index: PairIndex,
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
        let mut index = PairIndex::new(opts.pair_options()?);
        // One-shot: the playback order is the order given.
        let ranks: Vec<u64> = (0..trials.len() as u64).collect();
        index.extend(trials, &ranks)?;
        Ok(Self {
            time_unit: trials[0].time_unit,
            pose_relation: opts.pose_relation,
            delta: opts.delta,
            index,
        })
    }

    /// Aggregates the pair values per window with `setting`.
    pub fn estimate(&self, setting: Setting) -> Estimate {
        let index = &self.index;
        // Buckets are reused per worker thread: fresh ones for every block would be page
        // faults all over again.
        let per_block: Vec<Vec<WindowEstimate>> = (0..index.blocks())
            .into_par_iter()
            .map_init(
                || (Vec::new(), Scratch::default()),
                |(buckets, scratch), block| {
                    index.fill_block(block, 0, buckets, scratch);
                    buckets
                        .iter_mut()
                        .enumerate()
                        .filter(|(_, values)| !values.is_empty())
                        .map(|(offset, values)| {
                            let (start, end) = index.window(block * BLOCK + offset);
                            let (error, spread) =
                                statistics::bits::window_statistics(values, setting);
                            WindowEstimate {
                                start,
                                end,
                                error_m: error,
                                pairs: values.len(),
                                spread_m: spread,
                                interval: None,
                            }
                        })
                        .collect::<Vec<_>>()
                },
            )
            .collect();
        Estimate {
            setting,
            trials: index.trials(),
            time_unit: self.time_unit,
            pose_relation: self.pose_relation,
            delta: self.delta,
            windows: per_block.into_iter().flatten().collect(),
            calibration: None,
            calibrated_as: None,
            source: None,
        }
    }

    /// The RPE delta (frames) these values were computed with.
    pub fn delta(&self) -> usize {
        self.delta
    }
}

#[cfg(test)]
#[path = "../tests/support/trials.rs"]
mod test_trials;

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DQuat, DVec3};

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
    fn json_text_is_exact_with_keys_in_alphabetical_order_and_null_for_nan() {
        let window = |start: i64, error_m: f64, pairs: usize, spread_m: f64| WindowEstimate {
            start,
            end: start + 1000,
            error_m,
            pairs,
            spread_m,
            interval: None,
        };
        let mut e = Estimate {
            setting: Setting::Median,
            trials: 2,
            time_unit: TimeUnit::Nanoseconds,
            pose_relation: PoseRelation::TranslationPart,
            delta: 10,
            windows: vec![
                window(1000, 0.25, 3, 0.5),
                window(2000, f64::NAN, 1, f64::NAN),
            ],
            calibration: None,
            calibrated_as: None,
            source: None,
        };
        assert_eq!(
            e.to_json(Thresholds::new(0.1, 0.2)),
            r#"{"version":1,"setting":"median","trials":2,"time_unit":"ns","pose_relation":"trans_part","window_frames":10,"unit":"m","windows":[{"start":1000,"end":2000,"class":"high","error_m":0.25,"pairs":3,"spread_m":0.5},{"start":2000,"end":3000,"class":"low","error_m":null,"pairs":1,"spread_m":null}]}"#
        );
        e.pose_relation = PoseRelation::RotationAngleRad;
        e.time_unit = TimeUnit::Seconds;
        e.windows.truncate(1);
        assert_eq!(
            e.to_json(Thresholds::new(0.1, 0.2)),
            r#"{"version":1,"setting":"median","trials":2,"time_unit":"s","pose_relation":"angle_rad","window_frames":10,"unit":"rad","windows":[{"start":0.000001000,"end":0.000002000,"error_rad":0.25,"pairs":3,"spread_rad":0.5}]}"#
        );
        // A calibrated window: the interval's keys in the estimate's unit, alphabetically
        // among the others, and the calibration named.
        e.pose_relation = PoseRelation::TranslationPart;
        e.calibration = Some("euroc".into());
        e.windows[0].interval = Some(WindowInterval {
            raw_m: 0.125,
            lower_m: 0.0625,
            upper_m: 0.5,
        });
        assert_eq!(
            e.to_json(Thresholds::new(0.1, 0.2)),
            r#"{"version":1,"setting":"median","trials":2,"time_unit":"s","pose_relation":"trans_part","window_frames":10,"unit":"m","calibration":"euroc","windows":[{"start":0.000001000,"end":0.000002000,"class":"high","error_m":0.25,"lower_m":0.0625,"pairs":3,"raw_m":0.125,"spread_m":0.5,"upper_m":0.5}]}"#
        );
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
        assert_eq!(json["pose_relation"], "trans_part");
        assert_eq!(json["window_frames"], 10);
        assert_eq!(json["unit"], "m");
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
        // A second trial that also turns its own way, so the angles differ.
        let mut turning = trial(25, 0.4);
        for (i, q) in turning.orientations.iter_mut().enumerate() {
            *q = (*q * DQuat::from_rotation_x((i as f64 * 0.7).sin() * 0.05)).normalize();
        }
        let rotational = estimate(
            &[trial(25, 0.0), turning],
            &EstimateOptions {
                pose_relation: PoseRelation::RotationAngleDeg,
                delta: 7,
                ..EstimateOptions::default()
            },
        )
        .unwrap();
        let degrees = Thresholds::new(
            rotational.windows[3].error_m,
            rotational.windows[3].error_m * 2.0,
        );
        let text = rotational.to_json(degrees);
        // Nanoseconds in, integer nanoseconds out.
        assert!(
            text.contains(r#""start":1000000000,"end":1233333331,"#),
            "{text}"
        );
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(json["time_unit"], "ns");
        assert_eq!(json["pose_relation"], "angle_deg");
        assert_eq!(json["window_frames"], 7);
        assert_eq!(json["unit"], "deg");
        let windows = json["windows"].as_array().unwrap();
        assert_eq!(windows.len(), rotational.windows.len());
        for (doc, w) in windows.iter().zip(&rotational.windows) {
            assert_eq!(doc["error_deg"].as_f64(), Some(w.error_m));
            assert_eq!(doc["spread_deg"].as_f64(), Some(w.spread_m));
            assert!(doc.get("error_m").is_none(), "{doc}");
            // Classes come from the thresholds given, in degrees.
            assert_eq!(doc["class"], degrees.classify(w.error_m).name(), "{doc}");
        }
        assert_eq!(windows[3]["class"], "medium");
        // Radians and the full transformation have no class (the phone colours neither).
        for (relation, key, unit) in [
            (PoseRelation::RotationAngleRad, "error_rad", "rad"),
            (PoseRelation::FullTransformation, "error", "unit-less"),
        ] {
            let e = estimate(
                &[trial(25, 0.0), trial(25, 0.4)],
                &EstimateOptions {
                    pose_relation: relation,
                    ..EstimateOptions::default()
                },
            )
            .unwrap();
            let json: serde_json::Value =
                serde_json::from_str(&e.to_json(Thresholds::default())).unwrap();
            assert_eq!(json["unit"], unit);
            let first = &json["windows"][0];
            assert!(
                first[key].is_number() && first.get("class").is_none(),
                "{first}"
            );
        }
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
            let trials = super::test_trials::make_trials(&seed, &drops, &jitter, n, len);
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
