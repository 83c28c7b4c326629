//! Repeated SLAM-like trials: ground truth plus locally accumulated, surface-dependent drift.

use glam::{DQuat, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, LogNormal, Pareto, StudentT};
use sitar_estimator::Trajectory;

use crate::Recording;
use crate::draws::{uniform_direction, world_frame};
use crate::models::DriftModel;

/// RNG stream of the error all trials share (the recording's own systematic error).
const SHARED_STREAM: u64 = 2;
/// RNG stream of trial `i` is `TRIAL_STREAM_BASE + i`.
const TRIAL_STREAM_BASE: u64 = 1 << 32;

/// Options of one trial beyond the recording.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TrialOptions {
    /// Probability that a frame's pose is missing from the output (never the first or last
    /// frame); 0 by default. Drift still accumulates through dropped frames.
    pub drop_probability: f64,
}

/// A correlated 3-vector noise process (AR(1) with Student-t innovations of unit variance).
struct Ar1 {
    state: DVec3,
    rho: f64,
    innovation_scale: f64,
    t: StudentT<f64>,
    t_std: f64,
}

impl Ar1 {
    fn new(model: &DriftModel) -> Self {
        let dof = model.tail_dof;
        Self {
            state: DVec3::ZERO,
            rho: model.correlation,
            innovation_scale: (1.0 - model.correlation * model.correlation).sqrt(),
            // dof > 2 is validated, so this never fails; fall back to near-Gaussian anyway.
            t: StudentT::new(dof).unwrap_or_else(|_| StudentT::new(1e6).expect("valid dof")),
            t_std: (dof / (dof - 2.0)).sqrt(),
        }
    }

    /// Next value with stationary standard deviation `sigma` per axis.
    fn next(&mut self, sigma: f64, rng: &mut ChaCha8Rng) -> DVec3 {
        let mut draw = || self.t.sample(rng) / self.t_std;
        let innovation = DVec3::new(draw(), draw(), draw());
        self.state = self.state * self.rho + innovation * (self.innovation_scale * sigma);
        self.state
    }
}

fn rng_for(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

fn gaussian3(rng: &mut ChaCha8Rng, sigma: f64) -> DVec3 {
    let normal = rand_distr::StandardNormal;
    let mut g = || -> f64 { normal.sample(rng) };
    DVec3::new(g(), g(), g()) * sigma
}

/// Replays `rec` as one SLAM trial (no dropped frames); see [`play_trial_with`].
pub fn play_trial(rec: &Recording, trial_index: u32) -> Trajectory {
    play_trial_with(rec, trial_index, &TrialOptions::default())
}

/// Replays `rec` as trial `trial_index`: deterministic per (recording seed, trial index).
///
/// The trial integrates the ground-truth frame-to-frame motion with an error in each step
/// (in the camera frame): a correlated translation error and a rotation noise, both scaled by
/// [`DriftModel::gain`] of the smoothed view difficulty, a part of which every trial shares
/// (the recording's own systematic error) and the rest independent and scaled by a per-trial
/// quality factor; plus rare heavy-tailed jumps, likelier on hard and reflective views. So
/// trials drift more, and disagree more, where the camera faces blank walls and glass. The
/// trial starts in its own world frame (random yaw and offset) when
/// [`DriftModel::world_offset`] is set. Timestamps equal the recording's.
pub fn play_trial_with(rec: &Recording, trial_index: u32, options: &TrialOptions) -> Trajectory {
    let trial = match rec.ransac_parts() {
        Some((model, observations)) => {
            crate::ransac_tracker::play(rec, model, observations, trial_index)
        }
        None => play_model_trial(rec, trial_index),
    };
    drop_frames(rec, trial_index, trial, options)
}

/// The error model's trial (see [`play_trial_with`]).
fn play_model_trial(rec: &Recording, trial_index: u32) -> Trajectory {
    let model = rec.drift();
    let gt = &rec.walk().ground_truth;
    let n = gt.len();
    let sigma0 = model.frame_sigma();
    let rot0 = model.rotation_noise_deg.to_radians();
    let shared_w = model.shared_share;
    let own_w = (1.0 - shared_w * shared_w).sqrt();

    let mut shared_rng = rng_for(rec.seed(), SHARED_STREAM);
    let mut rng = rng_for(rec.seed(), TRIAL_STREAM_BASE + u64::from(trial_index));
    let quality = LogNormal::new(0.0, model.trial_quality_sigma)
        .map(|d| d.sample(&mut rng))
        .unwrap_or(1.0);
    let (world_rot, world_offset) = world_frame(model.world_offset, &mut rng);
    let jump_size = Pareto::new(model.jump_scale_m, 2.0).ok();

    let mut shared = Ar1::new(model);
    let mut own = Ar1::new(model);
    let mut positions = Vec::with_capacity(n);
    let mut orientations = Vec::with_capacity(n);
    let (difficulty, reflectivity) = (rec.difficulty(), rec.reflectivity());
    let mut position = world_rot * gt.positions[0] + world_offset;
    let mut rotation = (world_rot * gt.orientations[0]).normalize();
    positions.push(position);
    orientations.push(rotation);
    for f in 1..n {
        let gain = model.gain(difficulty[f]);
        // Both random streams advance identically every frame, whatever the options.
        let shared_t = shared.next(shared_w * sigma0 * gain, &mut shared_rng);
        let shared_r = gaussian3(&mut shared_rng, shared_w * rot0 * gain);
        let mut error_t = shared_t + own.next(own_w * sigma0 * gain * quality, &mut rng);
        let error_r = shared_r + gaussian3(&mut rng, own_w * rot0 * gain * quality);
        let jump_p = model.jump_probability(difficulty[f], reflectivity[f]);
        let jumps: bool = rng.random_bool(jump_p);
        let direction = uniform_direction(&mut rng);
        let size = jump_size.map_or(0.0, |d| d.sample(&mut rng).min(0.5));
        if jumps {
            error_t += direction * size;
        }
        let step_t = gt.orientations[f - 1].inverse() * (gt.positions[f] - gt.positions[f - 1]);
        let step_r = gt.orientations[f - 1].inverse() * gt.orientations[f];
        position += rotation * (step_t + step_r * error_t);
        rotation = (rotation * step_r * DQuat::from_scaled_axis(error_r)).normalize();
        // Keep the quaternion sign continuous (q and −q are the same rotation).
        if rotation.dot(orientations[f - 1]) < 0.0 {
            rotation = -rotation;
        }
        positions.push(position);
        orientations.push(rotation);
    }
    Trajectory {
        stamps: gt.stamps.clone(),
        positions,
        orientations,
        time_unit: gt.time_unit,
    }
}

/// Drops frames of `trial` as `options` ask (never the first or last).
fn drop_frames(
    rec: &Recording,
    trial_index: u32,
    mut trial: Trajectory,
    options: &TrialOptions,
) -> Trajectory {
    let n = trial.len();
    if options.drop_probability > 0.0 && n > 2 {
        let p = options.drop_probability.clamp(0.0, 1.0);
        let mut drop_rng = rng_for(
            rec.seed(),
            TRIAL_STREAM_BASE + u64::from(trial_index) + (1 << 31),
        );
        let keep: Vec<usize> = (0..n)
            .filter(|&i| i == 0 || i == n - 1 || !drop_rng.random_bool(p))
            .collect();
        trial = trial.reduce_to_ids(&keep);
    }
    trial
}

/// Trials `0..n` of `rec` (no dropped frames).
pub fn simulate_trials(rec: &Recording, n: u32) -> Vec<Trajectory> {
    (0..n).map(|i| play_trial(rec, i)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Room, Walk};

    fn recording(seed: u64) -> Recording {
        let room = Room::demo();
        let walk = Walk::handheld(&room, 15.0, 30.0, seed).unwrap();
        Recording::new(room, walk, seed)
    }

    /// Translation RPE of `est` against `reference` over `delta` frames, per start frame
    /// (both with the same stamps, no alignment needed: RPE is frame-invariant).
    fn rpe(reference: &Trajectory, est: &Trajectory, delta: usize) -> Vec<f64> {
        (0..reference.len() - delta)
            .map(|i| {
                let j = i + delta;
                let rel = |t: &Trajectory| {
                    (
                        t.orientations[i].inverse() * (t.positions[j] - t.positions[i]),
                        t.orientations[i].inverse() * t.orientations[j],
                    )
                };
                let (rt, rr) = rel(reference);
                let (et, _) = rel(est);
                // (ref_rel)^-1 * est_rel, translation part.
                (rr.inverse() * (et - rt)).length()
            })
            .collect()
    }

    #[test]
    fn trials_are_deterministic_and_distinct() {
        let rec = recording(3);
        let a = play_trial(&rec, 0);
        assert_eq!(a, play_trial(&rec, 0));
        assert_eq!(a, play_trial(&recording(3), 0));
        assert_ne!(a.positions, play_trial(&rec, 1).positions);
        assert_ne!(a.positions, play_trial(&recording(4), 0).positions);
        assert_eq!(a.stamps, rec.walk().ground_truth.stamps);
        assert!(
            a.orientations.windows(2).all(|w| w[0].dot(w[1]) > 0.0),
            "sign flips"
        );
        assert_eq!(simulate_trials(&rec, 3)[2], play_trial(&rec, 2));
    }

    #[test]
    fn without_noise_a_trial_is_the_ground_truth_in_its_own_frame() {
        let room = Room::demo();
        let walk = Walk::handheld(&room, 5.0, 30.0, 1).unwrap();
        let model = DriftModel {
            window_error_m: 1e-300,
            rotation_noise_deg: 0.0,
            jump_rate: 0.0,
            jump_rate_hard: 0.0,
            jump_rate_reflective: 0.0,
            ..DriftModel::default()
        };
        let rec = Recording::new(room, walk, 1).with_drift(model).unwrap();
        let trial = play_trial(&rec, 5);
        let gt = &rec.walk().ground_truth;
        let e = rpe(gt, &trial, 10);
        assert!(
            e.iter().all(|&x| x < 1e-9),
            "{:?}",
            e.iter().cloned().fold(0.0, f64::max)
        );
        // But in another world frame.
        assert!((trial.positions[0] - gt.positions[0]).length() > 1e-3);
    }

    #[test]
    fn dropped_frames_keep_first_and_last_and_the_rest_of_the_poses() {
        let rec = recording(5);
        let full = play_trial(&rec, 2);
        let dropped = play_trial_with(
            &rec,
            2,
            &TrialOptions {
                drop_probability: 0.1,
            },
        );
        assert!(dropped.len() < full.len() && dropped.len() > full.len() * 8 / 10);
        assert_eq!(dropped.stamps[0], full.stamps[0]);
        assert_eq!(dropped.stamps.last(), full.stamps.last());
        for (t, p) in dropped.stamps.iter().zip(&dropped.positions) {
            let i = full.stamps.iter().position(|s| s == t).unwrap();
            assert_eq!(*p, full.positions[i]);
        }
    }

    #[test]
    fn hard_surfaces_cause_larger_drift_and_spread() {
        // Over several recordings, windows with a hard view versus feature-rich ones.
        let (mut easy_err, mut hard_err, mut easy_spread, mut hard_spread) =
            (vec![], vec![], vec![], vec![]);
        for seed in 0..4 {
            let rec = recording(seed);
            let gt = &rec.walk().ground_truth;
            let trials = simulate_trials(&rec, 8);
            let errors: Vec<Vec<f64>> = trials.iter().map(|t| rpe(gt, t, 10)).collect();
            let pair = rpe(&trials[0], &trials[1], 10);
            for w in 0..errors[0].len() {
                let d = rec.difficulty()[w..w + 10].iter().sum::<f64>() / 10.0;
                let mean = errors.iter().map(|e| e[w]).sum::<f64>() / errors.len() as f64;
                let (err, spread) = if d > 0.6 {
                    (&mut hard_err, &mut hard_spread)
                } else if d < 0.2 {
                    (&mut easy_err, &mut easy_spread)
                } else {
                    continue;
                };
                err.push(mean);
                spread.push(pair[w]);
            }
        }
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        assert!(
            easy_err.len() > 100 && hard_err.len() > 100,
            "{} {}",
            easy_err.len(),
            hard_err.len()
        );
        let (e, h) = (median(&mut easy_err), median(&mut hard_err));
        let (es, hs) = (median(&mut easy_spread), median(&mut hard_spread));
        assert!(h > 4.0 * e, "error: easy {e} hard {h}");
        assert!(hs > 4.0 * es, "spread: easy {es} hard {hs}");
        // Magnitudes as the paper's classes expect: feature-rich low (< 2 cm), hard ≥ 5 cm.
        assert!(e < 0.02 && h > 0.04, "easy {e} hard {h}");
    }

    #[test]
    fn drift_model_validation_names_the_field() {
        let m = DriftModel {
            correlation: 1.5,
            ..DriftModel::default()
        };
        assert_eq!(m.validate().unwrap_err().0, "correlation");
        let m = DriftModel {
            tail_dof: 2.0,
            ..DriftModel::default()
        };
        assert_eq!(m.validate().unwrap_err().0, "tail_dof");
        assert!(DriftModel::default().validate().is_ok());
    }

    #[test]
    fn frame_sigma_gives_the_calibrated_window_error() {
        // Monte Carlo over the AR(1) process alone, Gaussian-free check of the variance sum.
        let model = DriftModel {
            tail_dof: 1e6,
            ..DriftModel::default()
        };
        let mut ar = Ar1::new(&model);
        let mut rng = rng_for(9, 0);
        let sigma = model.frame_sigma();
        for _ in 0..200 {
            ar.next(sigma, &mut rng);
        }
        let values: Vec<DVec3> = (0..200_000).map(|_| ar.next(sigma, &mut rng)).collect();
        let sums: Vec<f64> = values
            .chunks(10)
            .map(|c| c.iter().copied().sum::<DVec3>().length_squared())
            .collect();
        let rms = (sums.iter().sum::<f64>() / sums.len() as f64).sqrt();
        assert!((rms / model.window_error_m - 1.0).abs() < 0.03, "rms {rms}");
    }
}
