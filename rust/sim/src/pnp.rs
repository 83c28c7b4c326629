//! Per-frame pose from 2D–3D matches: RANSAC with a fixed iteration budget over P3P
//! hypotheses that agree with the inertial prior, then Gauss–Newton refinement on the
//! inliers until they stop changing.
//!
//! Plain RANSAC (Fischler & Bolles, which the paper names as the source of the trials'
//! randomness) rather than a preemptive variant such as ARRSAC: it keeps the hypothesis
//! with the most inliers over *all* matches, so a larger budget converges on the largest
//! consensus — the behaviour the method relies on and `tests/method_behaviour.rs` checks.

use glam::{DMat3, DVec2, DVec3};
use nalgebra::{Matrix6, Vector6};
use rand_chacha::ChaCha8Rng;

use crate::p3p::{CameraPose, p3p};

/// A 2D–3D match: a map point (the trial's own map, world) and where it was seen.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Match {
    pub world: DVec3,
    /// Normalised image coordinates (computer-vision frame).
    pub normalised: DVec2,
}

impl Match {
    fn bearing(&self) -> DVec3 {
        self.normalised.extend(1.0).normalize()
    }
}

/// Reprojection error of `m` under `pose` in normalised units (∞ behind the camera).
fn reprojection(pose: &CameraPose, m: &Match) -> f64 {
    let p = pose.apply(m.world);
    if p.z <= 1e-6 {
        return f64::INFINITY;
    }
    (DVec2::new(p.x / p.z, p.y / p.z) - m.normalised).length()
}

/// P3P hypotheses, kept only when they reproject their own sample and stay within the gate
/// around the prior.
struct P3pSolver<'a> {
    prior: &'a CameraPose,
    gate: Gate,
    threshold: f64,
}

/// How far a visual pose may be from the inertial prior.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Gate {
    pub distance_m: f64,
    pub angle_rad: f64,
}

impl Gate {
    pub fn admits(&self, prior: &CameraPose, pose: &CameraPose) -> bool {
        let turn = pose.rotation * prior.rotation.transpose();
        let cos = (turn.x_axis.x + turn.y_axis.y + turn.z_axis.z - 1.0) / 2.0;
        pose.centre().distance(prior.centre()) <= self.distance_m && cos >= self.angle_rad.cos()
    }
}

impl P3pSolver<'_> {
    fn hypotheses(&self, sample: [&Match; 3]) -> impl Iterator<Item = CameraPose> {
        let mut models = p3p(sample.map(Match::bearing), sample.map(|m| m.world));
        for slot in &mut models {
            let keep = slot.as_ref().is_some_and(|pose| {
                sample
                    .iter()
                    .all(|m| reprojection(pose, m) < self.threshold * 0.1)
                    && self.gate.admits(self.prior, pose)
            });
            if !keep {
                *slot = None;
            }
        }
        models.into_iter().flatten()
    }
}

/// Settings of [`locate`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct LocateOptions {
    /// RANSAC iterations (random minimal samples): the real-time budget.
    pub hypotheses: usize,
    /// Inlier threshold in normalised units (pixels / focal length).
    pub threshold: f64,
    pub gate: Gate,
}

/// The largest number of matches [`locate`] takes (the feature budget's upper bound): the
/// inlier sets are bit sets of this size.
pub(crate) const MAX_MATCHES: usize = 256;

/// The pose from `matches` and its inlier count, or `None` when no hypothesis within the
/// gate was found.
pub(crate) fn locate(
    matches: &[Match],
    prior: &CameraPose,
    options: &LocateOptions,
    rng: &mut ChaCha8Rng,
) -> Option<(CameraPose, usize)> {
    let matches = &matches[..matches.len().min(MAX_MATCHES)];
    if matches.len() < 3 {
        return None;
    }
    let solver = P3pSolver {
        prior,
        gate: options.gate,
        threshold: options.threshold,
    };
    let (pose, inliers) = best_hypothesis(&solver, matches, options, rng)?;
    let inliers: Vec<Match> = inliers.iter().map(|&i| matches[i]).collect();
    let mut pose = refine(pose, &inliers);
    // Refine on the refined pose's own inliers until they stop changing: the result is then a
    // function of the consensus set alone, not of the hypothesis that found it.
    let mut previous = Vec::new();
    for _ in 0..REFINE_ROUNDS {
        let current: Vec<usize> = (0..matches.len())
            .filter(|&i| reprojection(&pose, &matches[i]) < options.threshold)
            .collect();
        if current.len() < 3 || current == previous {
            break;
        }
        let inliers: Vec<Match> = current.iter().map(|&i| matches[i]).collect();
        pose = refine(pose, &inliers);
        previous = current;
    }
    let count = matches
        .iter()
        .filter(|m| reprojection(&pose, m) < options.threshold)
        .count();
    (options.gate.admits(prior, &pose) && count >= 3).then_some((pose, count))
}

/// RANSAC: `options.hypotheses` random minimal samples, each P3P solution that passes the
/// gate scored by its inliers on every match; the best one (most inliers, ties broken by the
/// inlier set itself, so that the answer depends on the consensus found and not on the order
/// it was found in) and the indices of its inliers.
fn best_hypothesis(
    solver: &P3pSolver<'_>,
    matches: &[Match],
    options: &LocateOptions,
    rng: &mut ChaCha8Rng,
) -> Option<(CameraPose, Vec<usize>)> {
    let mut best: Option<(InlierSet, CameraPose)> = None;
    for _ in 0..options.hypotheses.max(1) {
        let sample = rand::seq::index::sample(rng, matches.len(), 3);
        let sample = [0, 1, 2].map(|k| &matches[sample.index(k)]);
        for pose in solver.hypotheses(sample) {
            let set = InlierSet::of(&pose, matches, options.threshold);
            if best.as_ref().is_none_or(|(b, _)| set.beats(b)) {
                best = Some((set, pose));
            }
        }
    }
    let (set, pose) = best?;
    Some((pose, set.indices()))
}

/// The matches a pose explains, as a bit set over at most [`MAX_MATCHES`] indices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct InlierSet {
    count: u32,
    bits: [u64; MAX_MATCHES / 64],
}

impl InlierSet {
    fn of(pose: &CameraPose, matches: &[Match], threshold: f64) -> Self {
        let mut set = Self {
            count: 0,
            bits: [0; MAX_MATCHES / 64],
        };
        for (i, m) in matches.iter().enumerate() {
            if reprojection(pose, m) < threshold {
                set.bits[i / 64] |= 1 << (i % 64);
                set.count += 1;
            }
        }
        set
    }

    /// More inliers, or as many and the smaller set in bit order: a total order.
    fn beats(&self, other: &Self) -> bool {
        (self.count, std::cmp::Reverse(self.bits)) > (other.count, std::cmp::Reverse(other.bits))
    }

    fn indices(&self) -> Vec<usize> {
        (0..MAX_MATCHES)
            .filter(|&i| self.bits[i / 64] & (1 << (i % 64)) != 0)
            .collect()
    }
}

/// Rounds of re-scoring and refinement after RANSAC.
const REFINE_ROUNDS: usize = 5;

/// Gauss–Newton on the reprojection error over `inliers`, with left-multiplied updates.
pub(crate) fn refine(mut pose: CameraPose, inliers: &[Match]) -> CameraPose {
    for _ in 0..10 {
        let mut h = Matrix6::<f64>::zeros();
        let mut g = Vector6::<f64>::zeros();
        for m in inliers {
            let p = pose.apply(m.world);
            if p.z <= 1e-6 {
                continue;
            }
            let iz = 1.0 / p.z;
            let r = DVec2::new(p.x * iz, p.y * iz) - m.normalised;
            // d(projection)/dP and dP/d(v, ω) = [I | −[P]×].
            let du = DVec3::new(iz, 0.0, -p.x * iz * iz);
            let dv = DVec3::new(0.0, iz, -p.y * iz * iz);
            let row = |d: DVec3| {
                let w = p.cross(d);
                Vector6::new(d.x, d.y, d.z, w.x, w.y, w.z)
            };
            for (j, residual) in [(row(du), r.x), (row(dv), r.y)] {
                h += j * j.transpose();
                g += j * residual;
            }
        }
        let Some(cholesky) = h.cholesky() else {
            break;
        };
        let step = cholesky.solve(&(-g));
        if !step.iter().all(|v| v.is_finite()) {
            break;
        }
        let (v, w) = (
            DVec3::new(step[0], step[1], step[2]),
            DVec3::new(step[3], step[4], step[5]),
        );
        let turn = DMat3::from_quat(glam::DQuat::from_scaled_axis(w));
        pose = CameraPose {
            rotation: turn * pose.rotation,
            translation: turn * pose.translation + v,
        };
        if step.norm() < 1e-13 {
            break;
        }
    }
    pose
}
