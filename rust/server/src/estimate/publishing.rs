//! From an estimate to what is published: the results files and the classes adaptive
//! stopping watches. (The estimate itself runs in `live_sessions.rs`, over the trials held in memory.)

use std::collections::{BTreeMap, HashSet};

use sitar_core::{ErrorClass, Thresholds};
use sitar_estimator::{Estimate, Trajectory};

/// One estimate, ready to publish.
#[derive(Debug, Clone)]
pub(crate) struct Published {
    /// Runs of the estimate: its trials, and the walk when it is the live run.
    pub trials: u32,
    pub csv: String,
    pub json: String,
    /// Class of the window of every sub-trajectory (every `window_frames`-th frame of the
    /// reference trial: what the phone colours), keyed by its start time (ns).
    pub classes: BTreeMap<i64, ErrorClass>,
    /// Mean and greatest window error (the results' unit) over the windows with a finite
    /// error (those the JSON writes as numbers), 0 when there are none: the history line.
    pub mean_error: f64,
    pub max_error: f64,
    /// Where the estimate comes from (`walk` or `replays`), when it says.
    pub source: Option<&'static str>,
}

impl Published {
    /// The results of `estimate`, whose first trial is `reference`; windows are classified
    /// with `thresholds` (in the estimate's unit).
    pub fn new(
        estimate: &Estimate,
        reference: &Trajectory,
        window_frames: usize,
        thresholds: Thresholds,
    ) -> Published {
        let sub_starts: HashSet<i64> = reference
            .stamps
            .iter()
            .step_by(window_frames.max(1))
            .copied()
            .collect();
        let classes = estimate
            .windows
            .iter()
            .filter(|w| sub_starts.contains(&w.start))
            .map(|w| (w.start, thresholds.classify(w.error_m)))
            .collect();
        let errors = || {
            estimate
                .windows
                .iter()
                .map(|w| w.error_m)
                .filter(|e| e.is_finite())
        };
        Published {
            mean_error: errors().sum::<f64>() / errors().count().max(1) as f64,
            max_error: errors().fold(0.0, f64::max),
            source: estimate.source,
            trials: estimate.trials as u32,
            csv: estimate.to_legacy_csv(),
            json: estimate.to_json(thresholds),
            classes,
        }
    }
}

/// Adaptive stopping: true when no published estimate over the last `k`
/// finished trials changed a class. `history` holds (trials, classes) per
/// published estimate in order; trials that arrived together during one
/// estimate share one entry, so the check spans from the last estimate made
/// with at most `n − k` trials to the newest (n trials).
pub(crate) fn classes_stable(history: &[(u32, BTreeMap<i64, ErrorClass>)], k: u32) -> bool {
    let Some((n, _)) = history.last() else {
        return false;
    };
    if k == 0 || *n < k {
        return false;
    }
    let Some(base) = history.iter().rposition(|(count, _)| *count <= n - k) else {
        return false;
    };
    history[base..].windows(2).all(|w| w[0].1 == w[1].1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sitar_estimator::{EstimateOptions, PoseRelation, TimeUnit};

    #[test]
    fn sub_trajectory_classes_follow_the_window_length_and_unit() {
        let trial = |turn: f64| {
            let n = 61;
            Trajectory {
                stamps: (0..n as i64).map(|k| 1_000 + k * 33_000_000).collect(),
                positions: (0..n)
                    .map(|k| glam::DVec3::new(k as f64 * 0.01 * (1.0 + turn), 0.0, 0.0))
                    .collect(),
                orientations: (0..n)
                    .map(|k| glam::DQuat::from_rotation_y(k as f64 * turn))
                    .collect(),
                time_unit: TimeUnit::Nanoseconds,
            }
        };
        let trials = [trial(0.0), trial(0.02)];
        for (frames, relation) in [
            (10, PoseRelation::TranslationPart),
            (20, PoseRelation::RotationAngleDeg),
        ] {
            let options = EstimateOptions {
                delta: frames,
                pose_relation: relation,
                ..EstimateOptions::default()
            };
            let estimate = sitar_estimator::estimate(&trials, &options).unwrap();
            let thresholds = Thresholds::new(1.0, 2.0);
            let published = Published::new(&estimate, &trials[0], frames, thresholds);
            // One class per sub-trajectory start that has a window: frames 0, k, 2k, … < 61 − k.
            let starts: Vec<i64> = published.classes.keys().copied().collect();
            let expected: Vec<i64> = (0..61 - frames)
                .step_by(frames)
                .map(|k| 1_000 + k as i64 * 33_000_000)
                .collect();
            assert_eq!(starts, expected, "{frames}");
            for w in estimate
                .windows
                .iter()
                .filter(|w| starts.contains(&w.start))
            {
                assert_eq!(published.classes[&w.start], thresholds.classify(w.error_m));
            }
            assert_eq!(published.trials, 2);
            // The history line's mean and greatest error are those of the windows the JSON
            // writes, to the bit.
            let doc: serde_json::Value = serde_json::from_str(&published.json).unwrap();
            let key = if frames == 10 { "error_m" } else { "error_deg" };
            let errors: Vec<f64> = doc["windows"]
                .as_array()
                .unwrap()
                .iter()
                .filter_map(|w| w[key].as_f64())
                .collect();
            assert!(errors.len() > 1 && errors.iter().any(|e| *e > 0.0));
            let mean = errors.iter().sum::<f64>() / errors.len() as f64;
            let max = errors.iter().copied().fold(0.0, f64::max);
            assert_eq!(published.mean_error.to_bits(), mean.to_bits());
            assert_eq!(published.max_error.to_bits(), max.to_bits());
            assert!(
                published
                    .json
                    .contains(&format!("\"window_frames\":{frames}"))
            );
        }
    }

    fn classes(list: &[(i64, ErrorClass)]) -> BTreeMap<i64, ErrorClass> {
        list.iter().copied().collect()
    }

    fn numbered(
        list: &[(u32, &BTreeMap<i64, ErrorClass>)],
    ) -> Vec<(u32, BTreeMap<i64, ErrorClass>)> {
        list.iter().map(|(n, c)| (*n, (*c).clone())).collect()
    }

    #[test]
    fn stability_needs_k_unchanged_trials() {
        let a = classes(&[(0, ErrorClass::Low), (10, ErrorClass::High)]);
        let b = classes(&[(0, ErrorClass::Low), (10, ErrorClass::Medium)]);
        assert!(!classes_stable(&numbered(&[(2, &a), (3, &a), (4, &a)]), 3));
        assert!(classes_stable(
            &numbered(&[(2, &a), (3, &a), (4, &a), (5, &a)]),
            3
        ));
        assert!(!classes_stable(
            &numbered(&[(2, &a), (3, &b), (4, &a), (5, &a)]),
            3
        ));
        assert!(classes_stable(
            &numbered(&[(2, &b), (3, &a), (4, &a), (5, &a), (6, &a)]),
            3
        ));
        // Trials 4 and 5 arrived together: 3 → 5 → 6 still spans the last 3 trials.
        assert!(classes_stable(
            &numbered(&[(2, &b), (3, &a), (5, &a), (6, &a)]),
            3
        ));
        assert!(!classes_stable(
            &numbered(&[(2, &a), (3, &b), (5, &a), (6, &a)]),
            3
        ));
        // A window that appears or vanishes is a change.
        let c = classes(&[(0, ErrorClass::Low)]);
        assert!(!classes_stable(
            &numbered(&[(2, &a), (3, &a), (4, &a), (5, &c)]),
            3
        ));
        assert!(!classes_stable(&[], 3));
    }
}
