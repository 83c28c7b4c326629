//! The absolute pose error split by direction (not in evo): the translation error in the
//! reference's local along-track / cross-track / vertical frame, and the rotation error split
//! into its yaw about the gravity axis and the remaining roll/pitch (swing-twist).
//!
//! Definitions, at every associated pose `i` (after any alignment):
//!
//! * `e = p_est − p_ref`, the translation error in the world frame (as evo's APE `trans_part`,
//!   whose value is `‖e‖`).
//! * `g`: the unit gravity axis (+z, or +y with [`GravityAxis::Y`]), pointing up.
//! * The heading `h`: the reference's direction of motion, from its neighbouring positions
//!   (`p_ref[i+1] − p_ref[i−1]`; forward and backward differences at the ends), projected
//!   onto the horizontal plane and normalised. Where that is zero (standstill, purely
//!   vertical motion) the nearest pose's heading is used, earlier poses first; a reference
//!   that never moves horizontally has none and is an error.
//! * `along = e·h` (positive: the estimate is ahead), `cross = e·(g × h)` (positive: the
//!   estimate is to the left), `vertical = e·g` (positive: above). The three are orthogonal:
//!   `along² + cross² + vertical² = ‖e‖²`.
//! * The rotation error in the world frame `R = R_est·R_refᵀ` (the same angle as evo's
//!   `angle_deg`), as a unit quaternion `(w, v)` with `w ≥ 0`, decomposed as
//!   `R = swing·twist`: `twist` is the normalised `(w, (v·g)·g)` (identity when that is zero),
//!   `swing = R·twist⁻¹` rotates about a horizontal axis. `yaw = 2·atan2(v·g, w)` in
//!   (−180°, 180°] (positive: the estimate is turned counter-clockwise seen from above), and
//!   `roll_pitch` is the swing's angle in [0°, 180°].
//!
//! The signed values are in [`DirectionComponents`]; as APE pose relations
//! ([`DirectionRelation`]) the errors are their absolute values, so that the statistics
//! (RMSE, mean, …) read as evo's do; the RMSEs of along, cross and vertical add up in
//! squares to the `trans_part` RMSE.

use std::fmt;
use std::str::FromStr;

use glam::{DQuat, DVec3};

use crate::trajectory::rotation_angle;
use crate::{Error, GravityAxis, PoseErrors, Trajectory};

/// The APE split by direction, at one pose: signed metres and degrees (see the module).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionComponents {
    /// Along the reference's horizontal heading (m; positive: ahead).
    pub along_track: f64,
    /// Horizontal, across the heading (m; positive: to the left).
    pub cross_track: f64,
    /// Along the gravity axis (m; positive: above).
    pub vertical: f64,
    /// The rotation error's twist about the gravity axis (degrees, (−180, 180]).
    pub yaw_deg: f64,
    /// The rotation error's swing, its part about horizontal axes (degrees, [0, 180]).
    pub roll_pitch_deg: f64,
}

/// One of the direction relations of `sitar ape -r` (absolute values of
/// [`DirectionComponents`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DirectionRelation {
    /// |along-track translation error| (m).
    AlongTrack,
    /// |cross-track translation error| (m).
    CrossTrack,
    /// |vertical translation error| (m).
    Vertical,
    /// |yaw error| about the gravity axis (deg).
    YawDeg,
    /// Roll/pitch error: the swing's angle (deg).
    RollPitchDeg,
}

impl DirectionRelation {
    /// Every direction relation.
    pub const ALL: [DirectionRelation; 5] = [
        DirectionRelation::AlongTrack,
        DirectionRelation::CrossTrack,
        DirectionRelation::Vertical,
        DirectionRelation::YawDeg,
        DirectionRelation::RollPitchDeg,
    ];

    /// The description in titles, after evo's style ("along-track translation", …).
    pub fn description(self) -> &'static str {
        match self {
            DirectionRelation::AlongTrack => "along-track translation",
            DirectionRelation::CrossTrack => "cross-track translation",
            DirectionRelation::Vertical => "vertical translation",
            DirectionRelation::YawDeg => "yaw angle in degrees",
            DirectionRelation::RollPitchDeg => "roll-pitch angle in degrees",
        }
    }

    /// The unit: `m` or `deg`.
    pub fn unit(self) -> &'static str {
        match self {
            DirectionRelation::AlongTrack
            | DirectionRelation::CrossTrack
            | DirectionRelation::Vertical => "m",
            DirectionRelation::YawDeg | DirectionRelation::RollPitchDeg => "deg",
        }
    }

    /// This relation's (absolute) value of one pose's components.
    pub fn value(self, c: &DirectionComponents) -> f64 {
        match self {
            DirectionRelation::AlongTrack => c.along_track.abs(),
            DirectionRelation::CrossTrack => c.cross_track.abs(),
            DirectionRelation::Vertical => c.vertical.abs(),
            DirectionRelation::YawDeg => c.yaw_deg.abs(),
            DirectionRelation::RollPitchDeg => c.roll_pitch_deg,
        }
    }
}

impl fmt::Display for DirectionRelation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DirectionRelation::AlongTrack => "along_track",
            DirectionRelation::CrossTrack => "cross_track",
            DirectionRelation::Vertical => "vertical",
            DirectionRelation::YawDeg => "yaw_deg",
            DirectionRelation::RollPitchDeg => "roll_pitch_deg",
        })
    }
}

impl FromStr for DirectionRelation {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        DirectionRelation::ALL
            .into_iter()
            .find(|r| r.to_string() == s)
            .ok_or_else(|| {
                Error::InvalidArgument(format!(
                    "unknown direction relation '{s}' (expected along_track, cross_track, vertical, yaw_deg or roll_pitch_deg)"
                ))
            })
    }
}

/// The reference's unit horizontal heading at every pose (see the module).
pub fn headings(reference: &Trajectory, axis: GravityAxis) -> Result<Vec<DVec3>, Error> {
    let p = &reference.positions;
    let n = p.len();
    let g = axis.unit();
    let raw: Vec<Option<DVec3>> = (0..n)
        .map(|i| {
            if n < 2 {
                return None;
            }
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let d = p[b] - p[a];
            let horizontal = d - d.dot(g) * g;
            let length = horizontal.length();
            (length > 0.0 && length.is_finite()).then(|| horizontal / length)
        })
        .collect();
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let found = raw[i].or_else(|| {
            (1..n).find_map(|k| {
                let before = i.checked_sub(k).and_then(|j| raw[j]);
                before.or_else(|| raw.get(i + k).copied().flatten())
            })
        });
        match found {
            Some(h) => out.push(h),
            None => {
                return Err(Error::InvalidArgument(
                    "the reference never moves horizontally: along-track and cross-track are undefined"
                        .into(),
                ));
            }
        }
    }
    Ok(out)
}

/// The swing-twist split of a world-frame rotation about `g`: (signed twist angle in
/// (−π, π], swing angle in [0, π]), radians.
pub fn swing_twist(rotation: DQuat, g: DVec3) -> (f64, f64) {
    let q = if rotation.w < 0.0 {
        -rotation
    } else {
        rotation
    };
    let along = q.xyz().dot(g);
    let twist_norm = (q.w * q.w + along * along).sqrt();
    if twist_norm == 0.0 {
        return (0.0, rotation_angle(q));
    }
    let twist = DQuat::from_xyzw(
        along * g.x / twist_norm,
        along * g.y / twist_norm,
        along * g.z / twist_norm,
        q.w / twist_norm,
    );
    let mut yaw = 2.0 * along.atan2(q.w);
    if yaw <= -std::f64::consts::PI {
        yaw += std::f64::consts::TAU;
    }
    let swing = q * twist.conjugate();
    (yaw, rotation_angle(swing))
}

/// The signed direction components at every pose of two associated trajectories (same
/// length, already aligned as wanted).
pub fn direction_components(
    reference: &Trajectory,
    estimate: &Trajectory,
    axis: GravityAxis,
) -> Result<Vec<DirectionComponents>, Error> {
    reference.validate_poses()?;
    estimate.validate_poses()?;
    if reference.len() != estimate.len() {
        return Err(Error::InvalidArgument(format!(
            "trajectories must be associated (same number of poses): {} vs {}",
            reference.len(),
            estimate.len()
        )));
    }
    if reference.is_empty() {
        return Err(Error::NoPairs("empty trajectories".into()));
    }
    let g = axis.unit();
    let headings = headings(reference, axis)?;
    Ok((0..reference.len())
        .map(|i| {
            let e = estimate.positions[i] - reference.positions[i];
            let h = headings[i];
            let rotation =
                (estimate.orientations[i] * reference.orientations[i].conjugate()).normalize();
            let (yaw, roll_pitch) = swing_twist(rotation, g);
            DirectionComponents {
                along_track: e.dot(h),
                cross_track: e.dot(g.cross(h)),
                vertical: e.dot(g),
                yaw_deg: yaw.to_degrees(),
                roll_pitch_deg: roll_pitch.to_degrees(),
            }
        })
        .collect())
}

/// The APE under a direction relation: one absolute value per pose, pairs `(i, i)`.
pub fn ape_by_direction(
    reference: &Trajectory,
    estimate: &Trajectory,
    relation: DirectionRelation,
    axis: GravityAxis,
) -> Result<PoseErrors, Error> {
    let components = direction_components(reference, estimate, axis)?;
    Ok(PoseErrors {
        pairs: (0..components.len()).map(|i| (i, i)).collect(),
        errors: components.iter().map(|c| relation.value(c)).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TimeUnit;

    fn circle(n: usize) -> Trajectory {
        let positions: Vec<DVec3> = (0..n)
            .map(|i| {
                let t = i as f64 * 0.05;
                DVec3::new(5.0 * t.cos(), 5.0 * t.sin(), 1.0 + 0.2 * t)
            })
            .collect();
        Trajectory {
            stamps: (0..n as i64).collect(),
            orientations: (0..n)
                .map(|i| DQuat::from_rotation_z(i as f64 * 0.05 + 1.5))
                .collect(),
            positions,
            time_unit: TimeUnit::Nanoseconds,
        }
    }

    #[test]
    fn a_shift_along_the_track_is_neither_cross_nor_vertical() {
        let reference = circle(100);
        let headings = headings(&reference, GravityAxis::Z).unwrap();
        let mut estimate = reference.clone();
        for (p, h) in estimate.positions.iter_mut().zip(&headings) {
            *p += 0.3 * *h;
        }
        for c in direction_components(&reference, &estimate, GravityAxis::Z).unwrap() {
            assert!((c.along_track - 0.3).abs() < 1e-12);
            assert!(c.cross_track.abs() < 1e-12 && c.vertical.abs() < 1e-12);
            assert!(c.yaw_deg.abs() < 1e-9 && c.roll_pitch_deg.abs() < 1e-9);
        }
        // Moving counter-clockwise on the circle, left is towards the centre.
        let mut inward = reference.clone();
        for p in &mut inward.positions {
            *p -= 0.1 * DVec3::new(p.x, p.y, 0.0).normalize();
        }
        let c = direction_components(&reference, &inward, GravityAxis::Z).unwrap();
        assert!((c[50].cross_track - 0.1).abs() < 1e-12 && c[50].along_track.abs() < 1e-12);
    }

    #[test]
    fn a_pure_yaw_error_has_no_roll_pitch_and_a_tilt_no_yaw() {
        let reference = circle(20);
        for axis in [GravityAxis::Z, GravityAxis::Y] {
            let mut estimate = reference.clone();
            let yaw = DQuat::from_axis_angle(axis.unit(), -0.4);
            for q in &mut estimate.orientations {
                *q = yaw * *q;
            }
            estimate.positions[3] += 0.5 * axis.unit();
            let c = direction_components(&reference, &estimate, axis).unwrap();
            assert!((c[0].yaw_deg + 0.4f64.to_degrees()).abs() < 1e-9);
            assert!(c[0].roll_pitch_deg.abs() < 1e-9);
            assert!((c[3].vertical - 0.5).abs() < 1e-12);
            let tilt = DQuat::from_rotation_x(0.2);
            let mut tilted = reference.clone();
            for q in &mut tilted.orientations {
                *q = tilt * *q;
            }
            let c = direction_components(&reference, &tilted, GravityAxis::Z).unwrap();
            assert!(c[5].yaw_deg.abs() < 1e-9);
            assert!((c[5].roll_pitch_deg - 0.2f64.to_degrees()).abs() < 1e-9);
        }
    }

    #[test]
    fn squares_add_up_and_standstill_takes_a_neighbouring_heading() {
        let mut reference = circle(30);
        for i in 0..5 {
            reference.positions[i] = reference.positions[5];
        }
        let mut estimate = reference.clone();
        for (i, p) in estimate.positions.iter_mut().enumerate() {
            *p += DVec3::new(0.1 * (i as f64).sin(), -0.05, 0.02 * i as f64);
        }
        let h = headings(&reference, GravityAxis::Z).unwrap();
        assert_eq!(h[0], h[4]);
        let c = direction_components(&reference, &estimate, GravityAxis::Z).unwrap();
        for (i, c) in c.iter().enumerate() {
            let e = estimate.positions[i] - reference.positions[i];
            let sum = c.along_track.powi(2) + c.cross_track.powi(2) + c.vertical.powi(2);
            assert!((sum - e.length_squared()).abs() < 1e-12);
        }
        let mut still = reference.clone();
        still.positions = vec![DVec3::ONE; 30];
        assert!(direction_components(&still, &still, GravityAxis::Z).is_err());
        assert_eq!(
            "roll_pitch_deg".parse::<DirectionRelation>().unwrap(),
            DirectionRelation::RollPitchDeg
        );
    }
}
