//! Per-frame pose from 2D–3D matches: ARRSAC (the `arrsac` crate) over P3P hypotheses that
//! agree with the inertial prior, then Gauss–Newton refinement on the inliers.

use arrsac::Arrsac;
use glam::{DMat3, DVec2, DVec3};
use nalgebra::{Matrix6, Vector6};
use rand_chacha::ChaCha8Rng;
use sample_consensus::{Consensus, Estimator, Model};

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

impl Model<&Match> for CameraPose {
    fn residual(&self, data: &&Match) -> f64 {
        reprojection(self, data)
    }
}

/// P3P hypotheses, kept only when they reproject their own sample (so every model has at
/// least three inliers, which `arrsac` needs) and stay within the gate around the prior.
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

impl<'a> Estimator<&'a Match> for P3pSolver<'_> {
    type Model = CameraPose;
    type ModelIter = std::iter::Flatten<std::array::IntoIter<Option<CameraPose>, 4>>;
    const MIN_SAMPLES: usize = 3;

    fn estimate<I>(&self, mut data: I) -> Self::ModelIter
    where
        I: Iterator<Item = &'a Match> + Clone,
    {
        let (Some(a), Some(b), Some(c)) = (data.next(), data.next(), data.next()) else {
            return [None; 4].into_iter().flatten();
        };
        let sample = [a, b, c];
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
    /// Hypotheses per ARRSAC stage (the real-time budget): the initial random ones and as
    /// many again drawn from the best one's inliers.
    pub hypotheses: usize,
    /// Inlier threshold in normalised units (pixels / focal length).
    pub threshold: f64,
    pub gate: Gate,
}

/// The largest number of matches [`locate`] takes: ARRSAC then scores every hypothesis on
/// all of them in its initial blocks (so every kept model has its sample among its inliers).
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
    let budget = options.hypotheses.max(1);
    let mut arrsac = Arrsac::new(options.threshold, rng)
        .initialization_hypotheses(budget)
        .estimations_per_block(budget)
        .block_size(MAX_MATCHES / 4)
        .initialization_blocks(4);
    let (pose, inliers) = arrsac.model_inliers(&solver, matches.iter())?;
    let mut inliers: Vec<Match> = inliers.iter().map(|&i| matches[i]).collect();
    let mut pose = refine(pose, &inliers);
    // One more round: the refined pose's own inliers.
    inliers = matches
        .iter()
        .filter(|m| reprojection(&pose, m) < options.threshold)
        .copied()
        .collect();
    if inliers.len() >= 3 {
        pose = refine(pose, &inliers);
    }
    let count = matches
        .iter()
        .filter(|m| reprojection(&pose, m) < options.threshold)
        .count();
    (options.gate.admits(prior, &pose) && count >= 3).then_some((pose, count))
}

/// Gauss–Newton on the reprojection error over `inliers`, with left-multiplied updates.
pub(crate) fn refine(mut pose: CameraPose, inliers: &[Match]) -> CameraPose {
    for _ in 0..4 {
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
        if step.norm() < 1e-10 {
            break;
        }
    }
    pose
}
