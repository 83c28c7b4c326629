//! rpg_trajectory_evaluation's pairing and alignment (Zhang & Scaramuzza, IROS 2018), as its
//! results trees use them: the `eval_cfg.yaml` keys `align_type` (`posyaw`, `se3`, `sim3`,
//! `none`) and `align_num_frames` (−1: all poses), and the greedy timestamp association of
//! TUM's `associate.py` (0.02 s). Definitions only; the code is this crate's own.

use std::fmt;
use std::str::FromStr;

use glam::{DMat3, DVec3};

use crate::{Error, GravityAxis, Similarity, Trajectory, position_yaw, umeyama};

/// rpg's association tolerance: stamps strictly closer than 0.02 s pair.
pub const RPG_MAX_DIFF_NS: i64 = 20_000_000;

/// rpg's `align_type`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum RpgAlignType {
    /// Translation and yaw about z (visual-inertial).
    PosYaw,
    /// Rigid body (stereo).
    Se3,
    /// Similarity (monocular); rpg's default when a folder has no `eval_cfg.yaml`.
    #[default]
    Sim3,
    /// No alignment.
    None,
}

impl RpgAlignType {
    /// The name in `eval_cfg.yaml`.
    pub fn name(self) -> &'static str {
        match self {
            RpgAlignType::PosYaw => "posyaw",
            RpgAlignType::Se3 => "se3",
            RpgAlignType::Sim3 => "sim3",
            RpgAlignType::None => "none",
        }
    }
}

impl fmt::Display for RpgAlignType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for RpgAlignType {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        match s {
            "posyaw" => Ok(RpgAlignType::PosYaw),
            "se3" => Ok(RpgAlignType::Se3),
            "sim3" => Ok(RpgAlignType::Sim3),
            "none" => Ok(RpgAlignType::None),
            other => Err(Error::InvalidArgument(format!(
                "align_type must be posyaw, se3, sim3 or none, got {other:?}"
            ))),
        }
    }
}

/// An `eval_cfg.yaml`: the alignment and how many poses from the start it is fitted on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RpgAlignment {
    /// The transform fitted.
    pub align_type: RpgAlignType,
    /// Poses from the start used for the fit; −1 for all (rpg's `align_num_frames`).
    pub num_frames: i64,
}

impl Default for RpgAlignment {
    /// rpg's default without an `eval_cfg.yaml`: Sim(3) on every pose.
    fn default() -> Self {
        Self {
            align_type: RpgAlignType::Sim3,
            num_frames: -1,
        }
    }
}

/// Pairs estimate and reference poses as rpg does (TUM `associate.py`): every pair of stamps
/// strictly closer than `max_diff_ns`, taken greedily by increasing difference (ties by
/// estimate index, then reference index), each pose used once; returned sorted by estimate
/// index as `(estimate, reference)`. Stamps must be increasing (as [`Trajectory`] keeps them).
pub fn rpg_associate(
    estimate: &Trajectory,
    reference: &Trajectory,
    max_diff_ns: i64,
) -> Vec<(usize, usize)> {
    let (a, b) = (&estimate.stamps, &reference.stamps);
    let mut candidates: Vec<(i64, usize, usize)> = Vec::with_capacity(a.len() * 2);
    let mut lo = 0;
    for (i, &t) in a.iter().enumerate() {
        while lo < b.len() && b[lo] <= t - max_diff_ns {
            lo += 1;
        }
        let mut j = lo;
        while j < b.len() && b[j] < t + max_diff_ns {
            candidates.push(((t - b[j]).abs(), i, j));
            j += 1;
        }
    }
    candidates.sort_unstable();
    let (mut used_a, mut used_b) = (vec![false; a.len()], vec![false; b.len()]);
    let mut pairs = Vec::with_capacity(a.len().min(b.len()));
    for (_, i, j) in candidates {
        if !used_a[i] && !used_b[j] {
            used_a[i] = true;
            used_b[j] = true;
            pairs.push((i, j));
        }
    }
    pairs.sort_unstable();
    pairs
}

/// The transform `reference ≈ s·R·estimate + t` rpg fits (`alignTrajectory`) on two associated
/// trajectories: with one frame, `posyaw` takes the yaw of the first orientations and `se3`
/// the whole first pose; otherwise Umeyama on the first `num_frames` positions (yaw only for
/// `posyaw`, scale for `sim3`, which needs two frames at least).
pub fn rpg_align(
    estimate: &Trajectory,
    reference: &Trajectory,
    alignment: RpgAlignment,
) -> Result<Similarity, Error> {
    if estimate.len() != reference.len() {
        return Err(Error::InvalidArgument(format!(
            "trajectories must be associated (same number of poses): {} vs {}",
            reference.len(),
            estimate.len()
        )));
    }
    if estimate.is_empty() {
        return Err(Error::DegenerateAlignment("no poses".into()));
    }
    let n = match alignment.num_frames {
        -1 => estimate.len(),
        k if k >= 1 && k as usize <= estimate.len() => k as usize,
        k => {
            return Err(Error::InvalidArgument(format!(
                "align_num_frames must be -1 or 1..={} (the associated poses), got {k}",
                estimate.len()
            )));
        }
    };
    let (x, y) = (&estimate.positions[..n], &reference.positions[..n]);
    let first = || {
        let r_est = DMat3::from_quat(estimate.orientations[0]);
        let r_ref = DMat3::from_quat(reference.orientations[0]);
        (r_est, r_ref, estimate.positions[0], reference.positions[0])
    };
    let rigid = |rotation: DMat3, p_est: DVec3, p_ref: DVec3| Similarity {
        rotation,
        translation: p_ref - rotation * p_est,
        scale: 1.0,
    };
    match (alignment.align_type, n) {
        (RpgAlignType::None, _) => Ok(Similarity {
            rotation: DMat3::IDENTITY,
            translation: DVec3::ZERO,
            scale: 1.0,
        }),
        (RpgAlignType::PosYaw, 1) => {
            // The yaw θ maximising trace(R_z(θ)·R_est·R_refᵀ): R_z(θ)·R_est closest to R_ref.
            let (r_est, r_ref, p_est, p_ref) = first();
            let c = r_est * r_ref.transpose();
            let (c00, c01, c10, c11) = (c.x_axis.x, c.y_axis.x, c.x_axis.y, c.y_axis.y);
            let yaw = (c01 - c10).atan2(c00 + c11);
            Ok(rigid(DMat3::from_rotation_z(yaw), p_est, p_ref))
        }
        (RpgAlignType::PosYaw, _) => position_yaw(x, y, GravityAxis::Z),
        (RpgAlignType::Se3, 1) => {
            let (r_est, r_ref, p_est, p_ref) = first();
            Ok(rigid(r_ref * r_est.transpose(), p_est, p_ref))
        }
        (RpgAlignType::Se3, _) => umeyama(x, y, false),
        (RpgAlignType::Sim3, 1) => Err(Error::InvalidArgument(
            "sim3 alignment needs align_num_frames -1 or at least 2".into(),
        )),
        (RpgAlignType::Sim3, _) => umeyama(x, y, true),
    }
}

/// rpg's absolute translation errors: `‖p_ref − (s·R·p_est + t)‖` per associated pose, metres.
pub fn absolute_translation_errors(
    estimate: &Trajectory,
    reference: &Trajectory,
    transform: &Similarity,
) -> Vec<f64> {
    estimate
        .positions
        .iter()
        .zip(&reference.positions)
        .map(|(p, q)| (*q - transform.apply(*p)).length())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TimeUnit;
    use glam::DQuat;

    fn traj(stamps: &[i64], positions: &[DVec3], yaw: f64) -> Trajectory {
        let q = DQuat::from_rotation_z(yaw);
        Trajectory::from_poses(
            stamps.to_vec(),
            positions.to_vec(),
            vec![q; stamps.len()],
            TimeUnit::Seconds,
        )
        .unwrap()
    }

    #[test]
    fn association_is_greedy_by_difference_and_unique() {
        // Estimates 0 and 1 are both nearest to reference 0; 1 is closer and takes it, so 0
        // pairs with reference 1 only when that is within the tolerance.
        let p = [DVec3::ZERO; 3];
        let est = traj(&[0, 10, 100], &p, 0.0);
        let gt = traj(&[12, 40, 101], &p, 0.0);
        assert_eq!(rpg_associate(&est, &gt, 45), vec![(0, 1), (1, 0), (2, 2)]);
        assert_eq!(rpg_associate(&est, &gt, 25), vec![(1, 0), (2, 2)]);
        // Strictly closer: a difference equal to the tolerance does not pair.
        assert_eq!(rpg_associate(&est, &gt, 2), vec![(2, 2)]);
        assert_eq!(rpg_associate(&est, &gt, 1), vec![]);
    }

    #[test]
    fn alignments_recover_a_yaw_and_translation() {
        let positions: Vec<DVec3> = (0..20)
            .map(|i| DVec3::new((i as f64 * 0.3).sin(), i as f64 * 0.1, (i as f64).cos()))
            .collect();
        let stamps: Vec<i64> = (0..20).collect();
        let yaw = 0.7;
        let shift = DVec3::new(1.0, -2.0, 0.5);
        let r = DMat3::from_rotation_z(yaw);
        let moved: Vec<DVec3> = positions.iter().map(|p| r * *p + shift).collect();
        let est = traj(&stamps, &positions, 0.1);
        let gt = traj(&stamps, &moved, 0.1 + yaw);
        for kind in [RpgAlignType::PosYaw, RpgAlignType::Se3, RpgAlignType::Sim3] {
            for num_frames in [-1, 1, 5] {
                let alignment = RpgAlignment {
                    align_type: kind,
                    num_frames,
                };
                let Ok(t) = rpg_align(&est, &gt, alignment) else {
                    assert_eq!((kind, num_frames), (RpgAlignType::Sim3, 1));
                    continue;
                };
                let errors = absolute_translation_errors(&est, &gt, &t);
                assert!(
                    errors.iter().all(|e| *e < 1e-9),
                    "{alignment:?}: {errors:?}"
                );
            }
        }
        let too_many = RpgAlignment {
            align_type: RpgAlignType::Se3,
            num_frames: 21,
        };
        assert!(rpg_align(&est, &gt, too_many).is_err());
    }
}
