//! Small random trials for the estimator's property tests (shared by the unit proptest in
//! `src/estimate.rs` and `tests/incremental.rs`): trial 1 drops the frames in `drops`, trial 2
//! has jittered stamps (some beyond 10 ms; skipped if jitter made two stamps equal), the others
//! share their stamps. `seed` holds 6 · 40 numbers in −1..1 per trial.

use glam::{DQuat, DVec3};

use super::{TimeUnit, Trajectory};

pub fn make_trials(
    seed: &[f64],
    drops: &[usize],
    jitter: &[i64],
    n: usize,
    len: usize,
) -> Vec<Trajectory> {
    let mut trials = Vec::new();
    for t in 0..n {
        let base = &seed[t * 6 * 40..];
        let mut trial = Trajectory {
            stamps: (0..len as i64)
                .map(|k| 5_000_000_000 + k * 33_333_333)
                .collect(),
            positions: (0..len)
                .map(|k| {
                    DVec3::new(
                        k as f64 * 0.02 + base[6 * k],
                        base[6 * k + 1],
                        base[6 * k + 2],
                    ) * 0.5
                })
                .collect(),
            orientations: (0..len)
                .map(|k| {
                    DQuat::from_scaled_axis(
                        DVec3::new(base[6 * k + 3], base[6 * k + 4], base[6 * k + 5]) * 0.3,
                    )
                })
                .collect(),
            time_unit: TimeUnit::Nanoseconds,
        };
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
            if trial.stamps.len() != trial.positions.len() {
                continue;
            }
        }
        trials.push(trial);
    }
    trials
}
