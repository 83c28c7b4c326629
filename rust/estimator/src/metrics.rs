//! APE and RPE as evo's `metrics.py` / `filters.py`.

use std::fmt;
use std::str::FromStr;

use glam::{DQuat, DVec3};

use crate::{Error, Statistics, Trajectory};

/// Which part of the error pose is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum PoseRelation {
    /// Norm of the translation part, metres (evo `trans_part`).
    #[default]
    TranslationPart,
    /// Rotation angle of the error pose, degrees (evo `angle_deg`).
    RotationAngleDeg,
    /// Rotation angle of the error pose, radians (evo `angle_rad`).
    RotationAngleRad,
    /// Frobenius norm of `E − I₄` (evo `full`).
    FullTransformation,
}

impl fmt::Display for PoseRelation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PoseRelation::TranslationPart => "trans_part",
            PoseRelation::RotationAngleDeg => "angle_deg",
            PoseRelation::RotationAngleRad => "angle_rad",
            PoseRelation::FullTransformation => "full",
        })
    }
}

impl FromStr for PoseRelation {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        match s {
            "trans" | "trans_part" => Ok(PoseRelation::TranslationPart),
            "angle_deg" => Ok(PoseRelation::RotationAngleDeg),
            "angle_rad" => Ok(PoseRelation::RotationAngleRad),
            "full" => Ok(PoseRelation::FullTransformation),
            other => Err(Error::InvalidArgument(format!(
                "unknown pose relation '{other}' (expected trans, angle_deg, angle_rad or full)"
            ))),
        }
    }
}

/// A rigid pose as (rotation, translation): `x ↦ rotation·x + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidPose {
    /// Rotation (unit quaternion).
    pub rotation: DQuat,
    /// Translation.
    pub translation: DVec3,
}

impl RigidPose {
    /// `a⁻¹·b` (evo's `relative_se3(a, b)`).
    #[inline]
    pub fn relative(a: RigidPose, b: RigidPose) -> RigidPose {
        let inverse = a.rotation.conjugate();
        RigidPose {
            rotation: inverse * b.rotation,
            translation: inverse * (b.translation - a.translation),
        }
    }

    /// The error value of this error pose under `relation`.
    #[inline]
    pub fn error(&self, relation: PoseRelation) -> f64 {
        match relation {
            PoseRelation::TranslationPart => self.translation.length(),
            PoseRelation::RotationAngleRad => rotation_angle(self.rotation),
            PoseRelation::RotationAngleDeg => rotation_angle(self.rotation).to_degrees(),
            PoseRelation::FullTransformation => {
                // ‖R − I‖²_F = 8·sin²(θ/2) = 8·‖q.xyz‖² for a unit quaternion.
                let v = self.rotation.xyz().length_squared();
                (8.0 * v + self.translation.length_squared()).sqrt()
            }
        }
    }
}

/// The rotation angle in [0, π] of a unit quaternion (as scipy's `as_rotvec` norm).
#[inline]
pub fn rotation_angle(q: DQuat) -> f64 {
    2.0 * q.xyz().length().atan2(q.w.abs())
}

impl Trajectory {
    /// The pose at index `i`.
    #[inline]
    pub fn pose(&self, i: usize) -> RigidPose {
        RigidPose {
            rotation: self.orientations[i],
            translation: self.positions[i],
        }
    }
}

/// Unit of the RPE delta.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum DeltaUnit {
    /// Index distance in frames.
    #[default]
    Frames,
    /// Travelled path length in metres.
    Meters,
}

/// RPE options (evo's defaults except `delta`, which SiTAR uses as 10 frames).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RpeOptions {
    /// Pose relation.
    pub pose_relation: PoseRelation,
    /// Delta between pair poses, in `delta_unit`.
    pub delta: f64,
    /// Unit of `delta`.
    pub delta_unit: DeltaUnit,
    /// Every start index instead of consecutive, non-overlapping pairs.
    pub all_pairs: bool,
    /// Relative tolerance of a metre delta (evo `rel_delta_tol`, 0.1).
    pub rel_delta_tol: f64,
    /// Choose pairs on the reference instead of the estimate (evo `pairs_from_reference`).
    pub pairs_from_reference: bool,
}

impl Default for RpeOptions {
    fn default() -> Self {
        Self {
            pose_relation: PoseRelation::TranslationPart,
            delta: 10.0,
            delta_unit: DeltaUnit::Frames,
            all_pairs: true,
            rel_delta_tol: 0.1,
            pairs_from_reference: false,
        }
    }
}

/// Per-pair (RPE) or per-pose (APE) errors.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseErrors {
    /// Index pairs `(i, j)` into the associated trajectories (APE: `(i, i)`).
    pub pairs: Vec<(usize, usize)>,
    /// One error per pair.
    pub errors: Vec<f64>,
}

impl PoseErrors {
    /// evo's statistics of the errors.
    pub fn statistics(&self) -> Statistics {
        Statistics::from_errors(&self.errors)
    }
}

/// Index pairs of an RPE as evo's `id_pairs_from_delta` (on `poses`' positions).
pub fn delta_pairs(traj: &Trajectory, opts: &RpeOptions) -> Result<Vec<(usize, usize)>, Error> {
    if !(opts.delta > 0.0 && opts.delta.is_finite()) {
        return Err(Error::InvalidArgument(format!(
            "delta must be positive, got {}",
            opts.delta
        )));
    }
    let n = traj.len();
    let pairs: Vec<(usize, usize)> = match opts.delta_unit {
        DeltaUnit::Frames => {
            if opts.delta.fract() != 0.0 {
                return Err(Error::InvalidArgument(format!(
                    "delta in frames must be an integer, got {}",
                    opts.delta
                )));
            }
            let delta = opts.delta as usize;
            if opts.all_pairs {
                (0..n.saturating_sub(delta))
                    .map(|i| (i, i + delta))
                    .collect()
            } else {
                let ids: Vec<usize> = (0..n).step_by(delta).collect();
                ids.windows(2).map(|w| (w[0], w[1])).collect()
            }
        }
        DeltaUnit::Meters => pairs_by_path(
            &traj.positions,
            opts.delta,
            opts.delta * opts.rel_delta_tol,
            opts.all_pairs,
        ),
    };
    if pairs.is_empty() {
        return Err(Error::NoPairs(format!(
            "delta {} ({}) produced no pairs among {n} poses",
            opts.delta,
            match opts.delta_unit {
                DeltaUnit::Frames => "frames",
                DeltaUnit::Meters => "m",
            }
        )));
    }
    Ok(pairs)
}

/// evo's `filter_pairs_by_path`.
fn pairs_by_path(
    positions: &[DVec3],
    delta: f64,
    tol: f64,
    all_pairs: bool,
) -> Vec<(usize, usize)> {
    if positions.is_empty() {
        return Vec::new();
    }
    if all_pairs {
        let mut distances = Vec::with_capacity(positions.len());
        let mut total = 0.0;
        distances.push(0.0);
        for w in positions.windows(2) {
            total += (w[0] - w[1]).length();
            distances.push(total);
        }
        let n = distances.len();
        let mut pairs = Vec::new();
        for i in 0..n - 1 {
            let from_here = |k: usize| distances[k] - distances[i];
            // First k > i with from_here(k) >= delta; the argmin of |from_here − delta| is k
            // or the first index of the plateau just before it (numpy argmin takes the first).
            let k = i + 1 + distances[i + 1..].partition_point(|&d| d - distances[i] < delta);
            let mut best: Option<(usize, f64)> = None;
            if k - 1 > i {
                let value = from_here(k - 1);
                let first =
                    i + 1 + distances[i + 1..k].partition_point(|&d| d - distances[i] < value);
                best = Some((first, (value - delta).abs()));
            }
            if k < n {
                let diff = (from_here(k) - delta).abs();
                if best.is_none_or(|(_, b)| diff < b) {
                    best = Some((k, diff));
                }
            }
            if let Some((j, diff)) = best
                && diff <= tol
            {
                pairs.push((i, j));
            }
        }
        pairs
    } else {
        let mut ids = vec![0];
        let mut path = 0.0;
        for i in 1..positions.len() {
            path += (positions[i] - positions[i - 1]).length();
            if path >= delta {
                ids.push(i);
                path = 0.0;
            }
        }
        ids.windows(2).map(|w| (w[0], w[1])).collect()
    }
}

/// Relative pose error of two *associated* trajectories (same length), as evo's `RPE`:
/// `E = (Q_i⁻¹Q_j)⁻¹ (P_i⁻¹P_j)` for each pair `(i, j)`.
pub fn rpe(
    reference: &Trajectory,
    estimate: &Trajectory,
    opts: &RpeOptions,
) -> Result<PoseErrors, Error> {
    check_same_length(reference, estimate)?;
    let pairs = delta_pairs(
        if opts.pairs_from_reference {
            reference
        } else {
            estimate
        },
        opts,
    )?;
    let errors = pairs
        .iter()
        .map(|&(i, j)| {
            let q = RigidPose::relative(reference.pose(i), reference.pose(j));
            let p = RigidPose::relative(estimate.pose(i), estimate.pose(j));
            RigidPose::relative(q, p).error(opts.pose_relation)
        })
        .collect();
    Ok(PoseErrors { pairs, errors })
}

/// Absolute pose error of two *associated* trajectories, as evo's `APE`: `E = P_i⁻¹ Q_i`
/// (translation part: `‖p_i − q_i‖`).
pub fn ape(
    reference: &Trajectory,
    estimate: &Trajectory,
    relation: PoseRelation,
) -> Result<PoseErrors, Error> {
    check_same_length(reference, estimate)?;
    if reference.is_empty() {
        return Err(Error::NoPairs("empty trajectories".into()));
    }
    let errors = (0..reference.len())
        .map(|i| match relation {
            PoseRelation::TranslationPart => {
                (estimate.positions[i] - reference.positions[i]).length()
            }
            _ => RigidPose::relative(estimate.pose(i), reference.pose(i)).error(relation),
        })
        .collect();
    Ok(PoseErrors {
        pairs: (0..reference.len()).map(|i| (i, i)).collect(),
        errors,
    })
}

fn check_same_length(reference: &Trajectory, estimate: &Trajectory) -> Result<(), Error> {
    reference.validate_poses()?;
    estimate.validate_poses()?;
    if reference.len() != estimate.len() {
        return Err(Error::InvalidArgument(format!(
            "trajectories must be associated (same number of poses): {} vs {}",
            reference.len(),
            estimate.len()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TimeUnit;

    fn line(n: usize, step: f64) -> Trajectory {
        Trajectory {
            stamps: (0..n as i64).collect(),
            positions: (0..n)
                .map(|i| DVec3::new(i as f64 * step, 0.0, 0.0))
                .collect(),
            orientations: vec![DQuat::IDENTITY; n],
            time_unit: TimeUnit::Nanoseconds,
        }
    }

    #[test]
    fn analytic_rpe_and_ape() {
        let reference = line(21, 0.1);
        let estimate = line(21, 0.11);
        let r = rpe(&reference, &estimate, &RpeOptions::default()).unwrap();
        assert_eq!(r.pairs.len(), 11);
        assert!(r.errors.iter().all(|e| (e - 0.1).abs() < 1e-12));
        let a = ape(&reference, &estimate, PoseRelation::TranslationPart).unwrap();
        assert!((a.errors[20] - 0.2).abs() < 1e-12);
        let mut turned = reference.clone();
        turned.orientations[10] = DQuat::from_rotation_y(0.25);
        let a = ape(&reference, &turned, PoseRelation::RotationAngleDeg).unwrap();
        assert!((a.errors[10] - 0.25f64.to_degrees()).abs() < 1e-12);
        let full = ape(&reference, &turned, PoseRelation::FullTransformation).unwrap();
        // ‖R − I‖_F for angle θ: 2√2·sin(θ/2)
        assert!((full.errors[10] - 2.0 * 2f64.sqrt() * (0.125f64).sin()).abs() < 1e-12);
        let consecutive = RpeOptions {
            all_pairs: false,
            ..RpeOptions::default()
        };
        assert_eq!(
            delta_pairs(&reference, &consecutive).unwrap(),
            vec![(0, 10), (10, 20)]
        );
        assert!(rpe(&line(5, 0.1), &line(5, 0.1), &RpeOptions::default()).is_err());
    }

    #[test]
    fn metre_pairs() {
        let t = line(11, 0.25);
        let opts = RpeOptions {
            delta: 0.75,
            delta_unit: DeltaUnit::Meters,
            ..RpeOptions::default()
        };
        let pairs = delta_pairs(&t, &opts).unwrap();
        assert_eq!(pairs.first(), Some(&(0, 3)));
        assert_eq!(pairs.len(), 8);
        // 0.6 m: nearest path length is 0.5 (2 steps), within 10 %? |0.5 − 0.6| = 0.1 > 0.06: none.
        let strict = RpeOptions { delta: 0.6, ..opts };
        assert!(delta_pairs(&t, &strict).is_err());
        let opts = RpeOptions {
            all_pairs: false,
            ..opts
        };
        assert_eq!(
            delta_pairs(&t, &opts).unwrap(),
            vec![(0, 3), (3, 6), (6, 9)]
        );
    }

    fn random_trajectory(seed: &[f64]) -> Trajectory {
        let n = seed.len() / 6;
        Trajectory {
            stamps: (0..n as i64).collect(),
            positions: seed
                .chunks(6)
                .map(|c| DVec3::new(c[0], c[1], c[2]))
                .collect(),
            orientations: seed
                .chunks(6)
                .map(|c| DQuat::from_scaled_axis(DVec3::new(c[3], c[4], c[5])))
                .collect(),
            time_unit: TimeUnit::Nanoseconds,
        }
    }

    proptest::proptest! {
        #[test]
        fn rpe_is_invariant_to_rigid_transforms(
            seed_a in proptest::collection::vec(-3.0f64..3.0, 6 * 25),
            seed_b in proptest::collection::vec(-3.0f64..3.0, 6 * 25),
            rotation in (-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0),
            shift in (-50.0f64..50.0, -50.0f64..50.0, -50.0f64..50.0),
            which in 0usize..2,
            relation in 0usize..4,
        ) {
            let relation = [PoseRelation::TranslationPart, PoseRelation::RotationAngleDeg,
                PoseRelation::RotationAngleRad, PoseRelation::FullTransformation][relation];
            let (reference, estimate) = (random_trajectory(&seed_a), random_trajectory(&seed_b));
            let opts = RpeOptions { pose_relation: relation, delta: 3.0, ..RpeOptions::default() };
            let before = rpe(&reference, &estimate, &opts).unwrap();
            let mut moved = if which == 0 { reference.clone() } else { estimate.clone() };
            moved.transform(DQuat::from_scaled_axis(DVec3::new(rotation.0, rotation.1, rotation.2)),
                            DVec3::new(shift.0, shift.1, shift.2), 1.0);
            let after = if which == 0 { rpe(&moved, &estimate, &opts) } else { rpe(&reference, &moved, &opts) }.unwrap();
            for (a, b) in before.errors.iter().zip(&after.errors) {
                proptest::prop_assert!((a - b).abs() <= 1e-9, "{} vs {}", a, b);
            }
        }
    }
}
