//! APE and RPE as evo's `metrics.py` / `filters.py`.

use std::fmt;
use std::str::FromStr;

use glam::{DQuat, DVec3};

use crate::trajectory::rotation_angle;
use crate::{Error, Statistics, Trajectory};

/// Which part of the error pose is measured (evo's `PoseRelation`, `-r`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum PoseRelation {
    /// Norm of the translation part, metres (evo `trans_part`).
    #[default]
    TranslationPart,
    /// Frobenius norm of `R − I₃` of the error pose, unit-less (evo `rot_part`).
    RotationPart,
    /// Rotation angle of the error pose, degrees (evo `angle_deg`).
    RotationAngleDeg,
    /// Rotation angle of the error pose, radians (evo `angle_rad`).
    RotationAngleRad,
    /// Frobenius norm of `E − I₄` (evo `full`).
    FullTransformation,
    /// APE: distance of the positions; RPE: difference of the distances travelled by the
    /// pair's poses on both trajectories, metres (evo `point_distance`).
    PointDistance,
    /// RPE only: the point distance in percent of the reference's distance; pairs whose
    /// reference distance is zero are left out (evo `point_distance_error_ratio`).
    PointDistanceErrorRatio,
}

impl PoseRelation {
    /// Every relation, in evo's order.
    pub const ALL: [PoseRelation; 7] = [
        PoseRelation::FullTransformation,
        PoseRelation::TranslationPart,
        PoseRelation::RotationPart,
        PoseRelation::RotationAngleRad,
        PoseRelation::RotationAngleDeg,
        PoseRelation::PointDistance,
        PoseRelation::PointDistanceErrorRatio,
    ];

    /// evo's description, as its titles print it ("translation part", …).
    pub fn description(self) -> &'static str {
        match self {
            PoseRelation::TranslationPart => "translation part",
            PoseRelation::RotationPart => "rotation part",
            PoseRelation::RotationAngleDeg => "rotation angle in degrees",
            PoseRelation::RotationAngleRad => "rotation angle in radians",
            PoseRelation::FullTransformation => "full transformation",
            PoseRelation::PointDistance => "point distance",
            PoseRelation::PointDistanceErrorRatio => "point distance error ratio",
        }
    }

    /// evo's unit of the values: `m`, `deg`, `rad`, `%` or `unit-less`.
    pub fn unit(self) -> &'static str {
        match self {
            PoseRelation::TranslationPart | PoseRelation::PointDistance => "m",
            PoseRelation::RotationAngleDeg => "deg",
            PoseRelation::RotationAngleRad => "rad",
            PoseRelation::PointDistanceErrorRatio => "%",
            PoseRelation::RotationPart | PoseRelation::FullTransformation => "unit-less",
        }
    }
}

impl fmt::Display for PoseRelation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PoseRelation::TranslationPart => "trans_part",
            PoseRelation::RotationPart => "rot_part",
            PoseRelation::RotationAngleDeg => "angle_deg",
            PoseRelation::RotationAngleRad => "angle_rad",
            PoseRelation::FullTransformation => "full",
            PoseRelation::PointDistance => "point_distance",
            PoseRelation::PointDistanceErrorRatio => "point_distance_error_ratio",
        })
    }
}

impl FromStr for PoseRelation {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        if s == "trans" {
            return Ok(PoseRelation::TranslationPart);
        }
        PoseRelation::ALL
            .into_iter()
            .find(|r| r.to_string() == s)
            .ok_or_else(|| {
                Error::InvalidArgument(format!(
                    "unknown pose relation '{other}' (expected full, trans_part, rot_part, angle_deg, angle_rad, point_distance or point_distance_error_ratio)",
                    other = s
                ))
            })
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

    /// The error value of this error pose under `relation` (the point distance of an error
    /// pose is its translation's length; its error ratio is undefined: NaN).
    #[inline]
    pub fn error(&self, relation: PoseRelation) -> f64 {
        match relation {
            PoseRelation::TranslationPart | PoseRelation::PointDistance => {
                self.translation.length()
            }
            PoseRelation::PointDistanceErrorRatio => f64::NAN,
            // ‖R − I‖_F = √8·sin(θ/2) = √8·‖q.xyz‖ for a unit quaternion.
            PoseRelation::RotationPart => 8f64.sqrt() * self.rotation.xyz().length(),
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

/// Unit of the RPE delta (evo's `-u f|m|d|r`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum DeltaUnit {
    /// Index distance in frames.
    #[default]
    Frames,
    /// Travelled path length in metres.
    Meters,
    /// Rotation in degrees: accumulated along the path for consecutive pairs, the direct
    /// angle between the two poses for all pairs.
    Degrees,
    /// As [`DeltaUnit::Degrees`], in radians.
    Radians,
}

impl DeltaUnit {
    /// evo's name of the unit, as its titles print it.
    pub fn name(self) -> &'static str {
        match self {
            DeltaUnit::Frames => "frames",
            DeltaUnit::Meters => "m",
            DeltaUnit::Degrees => "deg",
            DeltaUnit::Radians => "rad",
        }
    }
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
        DeltaUnit::Degrees | DeltaUnit::Radians => {
            let degrees = opts.delta_unit == DeltaUnit::Degrees;
            let bound = if degrees { 180.0 } else { std::f64::consts::PI };
            if opts.delta > bound {
                return Err(Error::InvalidArgument(format!(
                    "delta angle must be within [0, {bound}] ({})",
                    opts.delta_unit.name()
                )));
            }
            let to_rad = |v: f64| if degrees { v.to_radians() } else { v };
            pairs_by_angle(
                &traj.orientations,
                to_rad(opts.delta),
                to_rad(opts.delta * opts.rel_delta_tol),
                opts.all_pairs,
            )
        }
    };
    if pairs.is_empty() {
        return Err(Error::NoPairs(format!(
            "delta = {} ({}) produced an empty index list among {n} poses - try lower values or a less strict tolerance",
            opts.delta,
            opts.delta_unit.name()
        )));
    }
    Ok(pairs)
}

/// evo's `filter_pairs_by_angle` (radians): consecutive pairs where the angle accumulated
/// pose by pose reaches `delta`; all pairs whose direct angle is within `delta ± tol`.
fn pairs_by_angle(
    orientations: &[DQuat],
    delta: f64,
    tol: f64,
    all_pairs: bool,
) -> Vec<(usize, usize)> {
    let n = orientations.len();
    let angle = |i: usize, j: usize| rotation_angle(orientations[i].conjugate() * orientations[j]);
    if all_pairs {
        use rayon::prelude::*;
        let (low, high) = (delta - tol, delta + tol);
        (0..n.saturating_sub(1))
            .into_par_iter()
            .flat_map_iter(|i| {
                (i + 1..n)
                    .filter(move |&j| (low..=high).contains(&angle(i, j)))
                    .map(move |j| (i, j))
            })
            .collect()
    } else {
        let mut pairs = Vec::new();
        let (mut accumulated, mut start) = (0.0, 0);
        for i in 0..n.saturating_sub(1) {
            accumulated += angle(i, i + 1);
            if accumulated >= delta {
                pairs.push((start, i + 1));
                accumulated = 0.0;
                start = i + 1;
            }
        }
        pairs
    }
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
    if matches!(
        opts.pose_relation,
        PoseRelation::PointDistance | PoseRelation::PointDistanceErrorRatio
    ) {
        let distance =
            |t: &Trajectory, i: usize, j: usize| (t.positions[i] - t.positions[j]).length();
        let mut kept = Vec::with_capacity(pairs.len());
        let mut errors = Vec::with_capacity(pairs.len());
        for (i, j) in pairs {
            let (d_ref, d_est) = (distance(reference, i, j), distance(estimate, i, j));
            let error = (d_ref - d_est).abs();
            if opts.pose_relation == PoseRelation::PointDistance {
                errors.push(error);
            } else if d_ref != 0.0 {
                errors.push(error / d_ref * 100.0);
            } else {
                continue;
            }
            kept.push((i, j));
        }
        if kept.is_empty() {
            return Err(Error::NoPairs(
                "every pair's reference distance is zero: no error ratio".into(),
            ));
        }
        return Ok(PoseErrors {
            pairs: kept,
            errors,
        });
    }
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
    if relation == PoseRelation::PointDistanceErrorRatio {
        return Err(Error::InvalidArgument(
            "point_distance_error_ratio is a relative pose error: use rpe".into(),
        ));
    }
    let errors = (0..reference.len())
        .map(|i| match relation {
            PoseRelation::TranslationPart | PoseRelation::PointDistance => {
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

    #[test]
    fn angle_pairs_point_distances_and_rot_part() {
        // A trajectory turning 10 degrees per pose about z, moving 1 m per pose along x.
        let mut t = line(10, 1.0);
        t.orientations = (0..10)
            .map(|i| DQuat::from_rotation_z((10.0 * i as f64).to_radians()))
            .collect();
        let opts = RpeOptions {
            delta: 25.0,
            delta_unit: DeltaUnit::Degrees,
            all_pairs: false,
            ..RpeOptions::default()
        };
        assert_eq!(
            delta_pairs(&t, &opts).unwrap(),
            vec![(0, 3), (3, 6), (6, 9)]
        );
        let all = RpeOptions {
            delta: 30.0,
            all_pairs: true,
            ..opts
        };
        let pairs = delta_pairs(&t, &all).unwrap();
        // |angle − 30| ≤ 3 degrees: exactly the pairs three poses apart.
        assert_eq!(pairs, (0..7).map(|i| (i, i + 3)).collect::<Vec<_>>());
        let radians = RpeOptions {
            delta: 30f64.to_radians(),
            delta_unit: DeltaUnit::Radians,
            ..all
        };
        assert_eq!(delta_pairs(&t, &radians).unwrap(), pairs);
        assert!(
            delta_pairs(
                &t,
                &RpeOptions {
                    delta: 181.0,
                    ..all
                }
            )
            .is_err()
        );

        // Point distance: |‖Δref‖ − ‖Δest‖|; the ratio in percent of ‖Δref‖.
        let (reference, estimate) = (line(21, 0.1), line(21, 0.11));
        let point = RpeOptions {
            pose_relation: PoseRelation::PointDistance,
            ..RpeOptions::default()
        };
        let r = rpe(&reference, &estimate, &point).unwrap();
        assert!(r.errors.iter().all(|e| (e - 0.1).abs() < 1e-12));
        let ratio = RpeOptions {
            pose_relation: PoseRelation::PointDistanceErrorRatio,
            ..point
        };
        let r = rpe(&reference, &estimate, &ratio).unwrap();
        assert!(
            r.errors.iter().all(|e| (e - 10.0).abs() < 1e-9),
            "{:?}",
            r.errors
        );
        // A standing reference has no ratio.
        assert!(rpe(&line(21, 0.0), &estimate, &ratio).is_err());
        assert!(ape(&reference, &estimate, PoseRelation::PointDistanceErrorRatio).is_err());

        // rot_part = ‖R − I‖_F = 2√2·sin(θ/2).
        let mut turned = reference.clone();
        turned.orientations[3] = DQuat::from_rotation_x(0.7);
        let a = ape(&reference, &turned, PoseRelation::RotationPart).unwrap();
        assert!((a.errors[3] - 2.0 * 2f64.sqrt() * 0.35f64.sin()).abs() < 1e-12);
        for r in PoseRelation::ALL {
            assert_eq!(r.to_string().parse::<PoseRelation>().unwrap(), r);
        }
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
