//! The one place that calls the estimator: trial files in, published results out.

use std::collections::BTreeMap;
use std::path::PathBuf;

use sitar_core::{ErrorClass, Thresholds};
use sitar_estimator::{EstimateOptions, Setting, Trajectory};

use crate::Error;

/// Frames per sub-trajectory (the phone logs every 5th frame; a sub-trajectory spans 10).
const SUBTRAJECTORY_FRAMES: usize = 10;

/// One estimate, ready to publish.
#[derive(Debug, Clone)]
pub(crate) struct Published {
    pub trials: u32,
    pub csv: String,
    pub json: String,
    /// Class of the window of every sub-trajectory (every 10th frame of the
    /// reference trial: what the phone colours), keyed by its start time (ns).
    pub classes: BTreeMap<i64, ErrorClass>,
}

/// Parses a setting name, naming the accepted ones when it is wrong.
pub(crate) fn check_setting(setting: &str) -> Result<Setting, Error> {
    setting.parse::<Setting>().map_err(|e| {
        Error::BadRequest(format!(
            "setting {setting:?}: {e} (expected mean, median, trim_mean_10|20|30|40 or mean_inliers)"
        ))
    })
}

/// Reads and checks one TUM text; the error names `source` and the line.
pub(crate) fn parse_trial(text: &str, source: &str) -> Result<Trajectory, Error> {
    let traj = sitar_estimator::parse_tum(text, source)
        .map_err(|e| Error::InvalidContent(e.to_string()))?;
    if traj.len() < 2 {
        return Err(Error::InvalidContent(format!(
            "{source}: a trial needs at least 2 poses, found {}",
            traj.len()
        )));
    }
    Ok(traj)
}

/// Runs the pairwise estimate over the stored trial files. Blocking: call it
/// from `spawn_blocking`.
pub(crate) fn estimate_files(
    paths: &[PathBuf],
    setting: &str,
    thresholds: Thresholds,
) -> Result<Published, Error> {
    if paths.len() < 2 {
        return Err(Error::Conflict(format!(
            "an estimate needs at least 2 trials, the session has {}",
            paths.len()
        )));
    }
    let setting = check_setting(setting)?;
    let trials = paths
        .iter()
        .map(|p| sitar_estimator::read_tum(p).map_err(|e| Error::InvalidContent(e.to_string())))
        .collect::<Result<Vec<_>, _>>()?;
    let options = EstimateOptions {
        setting,
        ..EstimateOptions::default()
    };
    let estimate =
        sitar_estimator::estimate(&trials, &options).map_err(|e| Error::Estimate(e.to_string()))?;
    let sub_starts: std::collections::HashSet<i64> = trials[0]
        .stamps
        .iter()
        .step_by(SUBTRAJECTORY_FRAMES)
        .copied()
        .collect();
    let classes = estimate
        .windows
        .iter()
        .filter(|w| sub_starts.contains(&w.start))
        .map(|w| (w.start, thresholds.classify(w.error_m)))
        .collect();
    Ok(Published {
        trials: paths.len() as u32,
        csv: estimate.to_legacy_csv(),
        json: estimate.to_json(thresholds),
        classes,
    })
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
