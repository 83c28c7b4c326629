//! Relative error at sub-trajectory lengths, as rpg_trajectory_evaluation defines it
//! (`compute_relative_error`, Zhang & Scaramuzza, IROS 2018).
//!
//! On two associated trajectories (pose `i` of the estimate paired with pose `i` of the
//! ground truth), with `D_i` the ground truth's path length from its first pose to pose `i`
//! (sum of the steps in order), each pose `i` is the start of one sub-trajectory per length
//! `L`: its end is the pose `j ≥ i` whose `D_j` is nearest to `D_i + L`, provided
//! `|D_j − (D_i + L)| < 0.2·L` (the earliest on ties). Its error is the ground truth's
//! relative pose undone from the estimate's, `E = (G_i⁻¹·G_j)⁻¹ · (Ê_i⁻¹·Ê_j)`, the estimate's
//! relative translation multiplied by the alignment's scale (Sim(3); 1 otherwise), then
//! expressed in the world by the estimate's rotation at the end, `E_w = R̂_j·E·R̂_jᵀ`
//! (translation `R̂_j·t_E`). From `E_w`:
//! - `trans_m = ‖t‖`, `trans_percent = 100·‖t‖ / L`;
//! - `rot_deg`: its angle, `acos((tr R − 1)/2)`; `rot_deg_per_m = rot_deg / L`;
//! - `yaw_deg = |yaw|` and `roll_pitch_deg = √(pitch² + roll²)`, from the Z-Y-X Euler angles
//!   `R = R_z(yaw)·R_y(pitch)·R_x(roll)` (rpg's `rzyx`, its `rel_yaw` and `rel_gravity`).
//!
//! With fewer than two sub-trajectories at a length, rpg computes nothing; so does this.
//! The estimate is used as read (rpg's relative error does not use the aligned poses, so the
//! world frame of the yaw / roll-pitch split is the estimate's). rpg drops starts without an
//! end from its list and then numbers the rest from 0 as if they were the first poses; here a
//! sub-trajectory keeps its own start. The two agree whenever the starts with an end are a
//! prefix of the poses, as on every dense trajectory (consecutive poses closer than 0.4·L).

use glam::{DMat3, DVec3};

use crate::{Error, Trajectory};

/// rpg's default lengths: 10, 20, 30, 40 and 50 % of the ground truth's path.
pub const RPG_DEFAULT_PERCENTS: [f64; 5] = [10.0, 20.0, 30.0, 40.0, 50.0];

/// rpg's tolerance on a sub-trajectory's length: 0.2 × the length.
pub const RPG_LENGTH_TOLERANCE: f64 = 0.2;

/// One sub-trajectory and its errors.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RelativeSample {
    /// Index of its first (associated) pose.
    pub start: usize,
    /// Index of its last pose.
    pub end: usize,
    /// Translation error, metres.
    pub trans_m: f64,
    /// Translation error over the nominal length, %.
    pub trans_percent: f64,
    /// Rotation angle of the error, degrees.
    pub rot_deg: f64,
    /// Rotation angle over the nominal length, deg/m.
    pub rot_deg_per_m: f64,
    /// |yaw| of the error in the world frame, degrees.
    pub yaw_deg: f64,
    /// √(pitch² + roll²) of the error in the world frame, degrees (rpg's "gravity" error).
    pub roll_pitch_deg: f64,
}

/// Every sub-trajectory of one length.
#[derive(Debug, Clone, PartialEq)]
pub struct RelativeAtLength {
    /// The nominal length `L`, metres.
    pub length_m: f64,
    /// Its sub-trajectories by start pose; empty when fewer than two fit.
    pub samples: Vec<RelativeSample>,
}

/// The lengths rpg takes as percentages of a path: `pct/100 · path`, truncated (not rounded)
/// to centimetres, as its `compute_boxplot_distances`.
pub fn lengths_from_percents(path_length_m: f64, percents: &[f64]) -> Vec<f64> {
    percents
        .iter()
        .map(|p| (p / 100.0 * path_length_m * 100.0).trunc() / 100.0)
        .collect()
}

/// The ground truth's path length from its first pose to its last, summed in order (rpg's
/// `get_distance_from_start(...)[-1]`, on every pose of the ground-truth file).
pub fn cumulative_path_length(reference: &Trajectory) -> f64 {
    reference.distances().last().copied().unwrap_or(0.0)
}

/// The end pose of the sub-trajectory of length `length_m` starting at `start` (see the
/// module docs), given the nondecreasing distances `d`.
fn end_index(d: &[f64], start: usize, length_m: f64) -> Option<usize> {
    let target = d[start] + length_m;
    let tolerance = RPG_LENGTH_TOLERANCE * length_m;
    let above = start + d[start..].partition_point(|&x| x < target);
    let mut best: Option<(usize, f64)> = None;
    if above > start {
        // The earliest pose with the largest distance below the target.
        let mut below = above - 1;
        while below > start && d[below - 1] == d[below] {
            below -= 1;
        }
        best = Some((below, (d[below] - target).abs()));
    }
    if above < d.len() {
        let error = (d[above] - target).abs();
        if best.is_none_or(|(_, e)| error < e) {
            best = Some((above, error));
        }
    }
    best.filter(|&(_, e)| e < tolerance).map(|(i, _)| i)
}

/// `|yaw|` and `√(pitch² + roll²)` (radians) of `R = R_z(yaw)·R_y(pitch)·R_x(roll)`.
fn yaw_and_roll_pitch(r: DMat3) -> (f64, f64) {
    // glam is column-major: r.col(j)[i] is R[i][j].
    let m = |i: usize, j: usize| r.col(j)[i];
    let yaw = m(1, 0).atan2(m(0, 0));
    let pitch = (-m(2, 0)).atan2((m(0, 0) * m(0, 0) + m(1, 0) * m(1, 0)).sqrt());
    let roll = m(2, 1).atan2(m(2, 2));
    (yaw.abs(), (pitch * pitch + roll * roll).sqrt())
}

/// The errors of the sub-trajectory `start → end` (see the module docs).
fn sample(
    reference: &Trajectory,
    estimate: &Trajectory,
    rotations: (&[DMat3], &[DMat3]),
    scale: f64,
    (start, end): (usize, usize),
    length_m: f64,
) -> RelativeSample {
    let (r_ref, r_est) = rotations;
    let rel = |r: &[DMat3], p: &[DVec3], s: f64| {
        let r1t = r[start].transpose();
        (r1t * r[end], s * (r1t * (p[end] - p[start])))
    };
    let (rg, tg) = rel(r_ref, &reference.positions, 1.0);
    let (re, te) = rel(r_est, &estimate.positions, scale);
    let rgt = rg.transpose();
    let (r_err, t_err) = (rgt * re, rgt * (te - tg));
    let world = r_est[end];
    let r_w = world * r_err * world.transpose();
    let t_w = world * t_err;
    let trans_m = t_w.length();
    let cos = ((r_w.x_axis.x + r_w.y_axis.y + r_w.z_axis.z - 1.0) / 2.0).clamp(-1.0, 1.0);
    let rot_deg = cos.acos().to_degrees();
    let (yaw, roll_pitch) = yaw_and_roll_pitch(r_w);
    RelativeSample {
        start,
        end,
        trans_m,
        trans_percent: trans_m / length_m * 100.0,
        rot_deg,
        rot_deg_per_m: rot_deg / length_m,
        yaw_deg: yaw.to_degrees(),
        roll_pitch_deg: roll_pitch.to_degrees(),
    }
}

/// rpg's relative errors of `estimate` against `reference`, two associated trajectories,
/// at each of `lengths_m` (see the module docs); `scale` multiplies the estimate's relative
/// translations (the Sim(3) alignment's scale, else 1). Errors on unequal lengths, a length
/// that is not positive and finite, a scale that is not, or non-finite poses.
pub fn relative_errors(
    reference: &Trajectory,
    estimate: &Trajectory,
    scale: f64,
    lengths_m: &[f64],
) -> Result<Vec<RelativeAtLength>, Error> {
    if reference.len() != estimate.len() {
        return Err(Error::InvalidArgument(format!(
            "the relative error needs associated trajectories of equal length ({} and {} poses)",
            reference.len(),
            estimate.len()
        )));
    }
    if let Some(bad) = lengths_m.iter().find(|l| !(l.is_finite() && **l > 0.0)) {
        return Err(Error::InvalidArgument(format!(
            "sub-trajectory lengths must be positive and finite, got {bad}"
        )));
    }
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::InvalidArgument(format!(
            "the scale must be positive and finite, got {scale}"
        )));
    }
    reference.validate_poses()?;
    estimate.validate_poses()?;
    let d = reference.distances();
    let r_ref: Vec<DMat3> = reference
        .orientations
        .iter()
        .map(|q| DMat3::from_quat(*q))
        .collect();
    let r_est: Vec<DMat3> = estimate
        .orientations
        .iter()
        .map(|q| DMat3::from_quat(*q))
        .collect();
    Ok(lengths_m
        .iter()
        .map(|&length_m| {
            let pairs: Vec<(usize, usize)> = (0..d.len())
                .filter_map(|i| end_index(&d, i, length_m).map(|j| (i, j)))
                .collect();
            let samples = if pairs.len() < 2 {
                Vec::new()
            } else {
                pairs
                    .into_iter()
                    .map(|p| sample(reference, estimate, (&r_ref, &r_est), scale, p, length_m))
                    .collect()
            };
            RelativeAtLength { length_m, samples }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TimeUnit;
    use glam::DQuat;

    /// rpg's linear search, for comparison.
    fn brute(d: &[f64], start: usize, length: f64) -> Option<usize> {
        let mut best = None;
        let mut error = RPG_LENGTH_TOLERANCE * length;
        for (i, &x) in d.iter().enumerate().skip(start) {
            let e = (x - (d[start] + length)).abs();
            if e < error {
                best = Some(i);
                error = e;
            }
        }
        best
    }

    #[test]
    fn end_index_is_rpg_linear_search() {
        // Stops (repeated distances), gaps and a tie exactly halfway.
        let d = [0.0, 0.5, 0.5, 0.5, 1.0, 1.5, 1.5, 3.0, 3.5, 3.5, 4.0, 8.0];
        for length in [0.25, 0.5, 1.0, 1.25, 2.0, 3.0, 5.0] {
            for start in 0..d.len() {
                assert_eq!(end_index(&d, start, length), brute(&d, start, length));
            }
        }
    }

    #[test]
    fn percent_lengths_truncate_to_centimetres() {
        assert_eq!(
            lengths_from_percents(36.4567, &[10.0, 50.0]),
            vec![3.64, 18.22]
        );
    }

    #[test]
    fn a_pure_yaw_error_is_all_yaw() {
        // Straight line along x; the estimate turns by 2° about z at pose 5 onward.
        let n = 11;
        let stamps: Vec<i64> = (0..n).collect();
        let p: Vec<DVec3> = (0..n).map(|i| DVec3::new(i as f64, 0.0, 0.0)).collect();
        let gt = Trajectory::from_poses(
            stamps.clone(),
            p.clone(),
            vec![DQuat::IDENTITY; n as usize],
            TimeUnit::Seconds,
        )
        .unwrap();
        let q: Vec<DQuat> = (0..n)
            .map(|i| DQuat::from_rotation_z(if i >= 5 { 2f64.to_radians() } else { 0.0 }))
            .collect();
        let est = Trajectory::from_poses(stamps, p, q, TimeUnit::Seconds).unwrap();
        let at = &relative_errors(&gt, &est, 1.0, &[3.0]).unwrap()[0];
        assert_eq!(at.samples.len(), 8);
        let crossing = at.samples.iter().find(|s| s.start == 3).unwrap();
        assert_eq!(crossing.end, 6);
        assert!((crossing.yaw_deg - 2.0).abs() < 1e-9);
        assert!((crossing.rot_deg - 2.0).abs() < 1e-6);
        assert!(crossing.roll_pitch_deg < 1e-9);
        assert!(crossing.trans_m < 1e-12);
        let before = at.samples.iter().find(|s| s.start == 0).unwrap();
        assert!(before.rot_deg < 1e-6 && before.trans_m < 1e-12);
    }
}
