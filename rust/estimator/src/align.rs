//! Trajectory alignment: Umeyama SE(3)/Sim(3), scale only, origin (evo `geometry.py`,
//! `trajectory.py`).

use glam::{DMat3, DQuat, DVec3};
use nalgebra::Matrix3;

use crate::{Error, Trajectory};

/// A similarity transform `x ↦ scale·rotation·x + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Similarity {
    /// Rotation matrix (proper: determinant +1).
    pub rotation: DMat3,
    /// Translation.
    pub translation: DVec3,
    /// Scale (1 without scale correction).
    pub scale: f64,
}

impl Similarity {
    /// Applies the transform to a point.
    pub fn apply(&self, x: DVec3) -> DVec3 {
        self.scale * (self.rotation * x) + self.translation
    }

    /// The 4×4 matrix `[[s·R, t], [0, 0, 0, 1]]`, row by row (evo's `lie.sim3`).
    pub fn to_matrix(&self) -> [[f64; 4]; 4] {
        let r = self.rotation;
        let mut m = [[0.0; 4]; 4];
        for (i, row) in m.iter_mut().take(3).enumerate() {
            for (j, value) in row.iter_mut().take(3).enumerate() {
                *value = self.scale * r.col(j)[i];
            }
            row[3] = self.translation[i];
        }
        m[3][3] = 1.0;
        m
    }
}

/// How to align an estimate onto a reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Alignment {
    /// No alignment.
    #[default]
    None,
    /// Umeyama rigid (SE(3)) alignment (evo `--align`).
    Se3,
    /// Umeyama similarity (Sim(3)) alignment (evo `--align --correct_scale`).
    Sim3,
    /// Scale correction only (evo `--correct_scale`).
    ScaleOnly,
    /// Move the estimate's first pose onto the reference's first pose (evo `--align_origin`).
    Origin,
    /// 4-DoF alignment (not in evo): a translation and a rotation about the gravity axis only,
    /// as rpg_trajectory_evaluation's `posyaw` and common VIO practice (roll and pitch are
    /// observable from gravity, so they are not aligned away). The yaw is the least-squares
    /// one over the positions: after centring both point sets, with `(a, b)` the coordinates
    /// in the horizontal plane such that a rotation by θ maps `a ↦ a·cosθ − b·sinθ`
    /// (`(x, y)` about z, `(z, x)` about y),
    /// `θ = atan2(Σ(a_e·b_r − b_e·a_r), Σ(a_e·a_r + b_e·b_r))` (e: estimate, r: reference),
    /// and the translation moves the rotated estimate's centroid onto the reference's.
    /// No scale.
    PositionYaw {
        /// The gravity (vertical) axis the yaw is about.
        axis: GravityAxis,
    },
}

/// The vertical axis of a trajectory's world frame: the axis gravity lies along.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum GravityAxis {
    /// z (ROS, EuRoC, TUM: z up).
    #[default]
    Z,
    /// y (ARCore, Unity, OpenGL-style: gravity along −y).
    Y,
}

impl GravityAxis {
    /// The axis as a unit vector (+z or +y; the sign does not matter for a rotation about it
    /// or a component's magnitude).
    pub fn unit(self) -> DVec3 {
        match self {
            GravityAxis::Z => DVec3::Z,
            GravityAxis::Y => DVec3::Y,
        }
    }

    /// The two horizontal coordinates `(a, b)` of `p`, ordered so that a positive rotation
    /// about the axis turns `a` towards `b` (right-handed: `(x, y)` about z, `(z, x)` about y).
    pub fn horizontal(self, p: DVec3) -> (f64, f64) {
        match self {
            GravityAxis::Z => (p.x, p.y),
            GravityAxis::Y => (p.z, p.x),
        }
    }

    /// The name used on the command line and in JSON: `z` or `y`.
    pub fn name(self) -> &'static str {
        match self {
            GravityAxis::Z => "z",
            GravityAxis::Y => "y",
        }
    }
}

/// Checks two point sets for a fit (same size, not empty, finite) and gives their size and
/// centroids.
fn centroids(x: &[DVec3], y: &[DVec3]) -> Result<(f64, DVec3, DVec3), Error> {
    if x.len() != y.len() {
        return Err(Error::InvalidArgument(format!(
            "point sets differ in size: {} vs {}",
            x.len(),
            y.len()
        )));
    }
    if x.is_empty() {
        return Err(Error::DegenerateAlignment("no points".into()));
    }
    if !x.iter().chain(y).all(|p| p.is_finite()) {
        return Err(Error::InvalidArgument(
            "alignment points must be finite".into(),
        ));
    }
    let n = x.len() as f64;
    let mean_x = x.iter().copied().sum::<DVec3>() / n;
    let mean_y = y.iter().copied().sum::<DVec3>() / n;
    Ok((n, mean_x, mean_y))
}

/// The least-squares 4-DoF fit `y ≈ R_axis(θ)·x + t` (see [`Alignment::PositionYaw`]).
pub fn position_yaw(x: &[DVec3], y: &[DVec3], axis: GravityAxis) -> Result<Similarity, Error> {
    let (_, mean_x, mean_y) = centroids(x, y)?;
    let (mut sin_sum, mut cos_sum) = (0.0, 0.0);
    for (p, q) in x.iter().zip(y) {
        let (ae, be) = axis.horizontal(*p - mean_x);
        let (ar, br) = axis.horizontal(*q - mean_y);
        sin_sum += ae * br - be * ar;
        cos_sum += ae * ar + be * br;
    }
    // All points on the vertical line through the centroid (or a single point): any yaw
    // fits; keep the estimate's heading (θ = 0) rather than fail.
    let yaw = if sin_sum == 0.0 && cos_sum == 0.0 {
        0.0
    } else {
        sin_sum.atan2(cos_sum)
    };
    let rotation = DMat3::from_axis_angle(axis.unit(), yaw);
    Ok(Similarity {
        rotation,
        translation: mean_y - rotation * mean_x,
        scale: 1.0,
    })
}

/// Umeyama's least-squares `y ≈ c·R·x + t` as evo's `umeyama_alignment(x, y, with_scale)`,
/// including the reflection fix; rank-deficient covariance (e.g. collinear points) is an error.
pub fn umeyama(x: &[DVec3], y: &[DVec3], with_scale: bool) -> Result<Similarity, Error> {
    let (n, mean_x, mean_y) = centroids(x, y)?;
    let sigma_x = x
        .iter()
        .map(|p| (*p - mean_x).length_squared())
        .sum::<f64>()
        / n;
    let mut cov = Matrix3::<f64>::zeros();
    for (p, q) in x.iter().zip(y) {
        let (dx, dy) = (*p - mean_x, *q - mean_y);
        cov += nalgebra::Vector3::new(dy.x, dy.y, dy.z)
            * nalgebra::Vector3::new(dx.x, dx.y, dx.z).transpose();
    }
    cov /= n;
    // An iteration cap: nalgebra's plain `svd` has none, and must never hang on odd input.
    let Some(svd) = cov.try_svd(true, true, f64::EPSILON * 5.0, 10_000) else {
        return Err(Error::DegenerateAlignment("SVD did not converge".into()));
    };
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Err(Error::DegenerateAlignment("SVD did not converge".into()));
    };
    let d = svd.singular_values;
    if d.iter().filter(|&&s| s > f64::EPSILON).count() < 2 {
        return Err(Error::DegenerateAlignment(
            "degenerate covariance rank, Umeyama alignment is not possible (are the points collinear?)".into(),
        ));
    }
    let mut s = Matrix3::<f64>::identity();
    if u.determinant() * v_t.determinant() < 0.0 {
        s[(2, 2)] = -1.0;
    }
    let r = u * s * v_t;
    let c = if with_scale {
        (Matrix3::from_diagonal(&d) * s).trace() / sigma_x
    } else {
        1.0
    };
    let rotation = DMat3::from_cols_array(&[
        r[(0, 0)],
        r[(1, 0)],
        r[(2, 0)],
        r[(0, 1)],
        r[(1, 1)],
        r[(2, 1)],
        r[(0, 2)],
        r[(1, 2)],
        r[(2, 2)],
    ]);
    let translation = mean_y - c * (rotation * mean_x);
    Ok(Similarity {
        rotation,
        translation,
        scale: c,
    })
}

/// Aligns `estimate` onto `reference` in place (both associated, same length), as evo's
/// `PosePath3D.align` / `align_origin`; returns the transform applied.
pub fn align(
    estimate: &mut Trajectory,
    reference: &Trajectory,
    alignment: Alignment,
) -> Result<Similarity, Error> {
    align_first(estimate, reference, alignment, None)
}

/// [`align`] with the Umeyama fit on the first `n` poses only (evo's `--n_to_align`; `None`
/// or more than there are: all), applied to every pose.
pub fn align_first(
    estimate: &mut Trajectory,
    reference: &Trajectory,
    alignment: Alignment,
    n: Option<usize>,
) -> Result<Similarity, Error> {
    if estimate.len() != reference.len() {
        return Err(Error::InvalidArgument(format!(
            "trajectories must be associated (same number of poses): {} vs {}",
            reference.len(),
            estimate.len()
        )));
    }
    estimate.validate_poses()?;
    reference.validate_poses()?;
    let identity = Similarity {
        rotation: DMat3::IDENTITY,
        translation: DVec3::ZERO,
        scale: 1.0,
    };
    let transform = match alignment {
        Alignment::None => return Ok(identity),
        Alignment::Se3 | Alignment::Sim3 | Alignment::ScaleOnly => {
            let with_scale = alignment != Alignment::Se3;
            let n = n.unwrap_or(usize::MAX).min(estimate.len());
            let found = umeyama(
                &estimate.positions[..n],
                &reference.positions[..n],
                with_scale,
            )?;
            if alignment == Alignment::ScaleOnly {
                Similarity {
                    scale: found.scale,
                    ..identity
                }
            } else {
                found
            }
        }
        Alignment::PositionYaw { axis } => {
            let n = n.unwrap_or(usize::MAX).min(estimate.len());
            position_yaw(&estimate.positions[..n], &reference.positions[..n], axis)?
        }
        Alignment::Origin => {
            if estimate.is_empty() {
                return Err(Error::DegenerateAlignment("no poses".into()));
            }
            // to_ref_origin = T_ref0 · T_est0⁻¹
            let rotation = reference.orientations[0] * estimate.orientations[0].conjugate();
            let translation = reference.positions[0] - rotation * estimate.positions[0];
            Similarity {
                rotation: DMat3::from_quat(rotation),
                translation,
                scale: 1.0,
            }
        }
    };
    let rotation = DQuat::from_mat3(&transform.rotation).normalize();
    estimate.transform(rotation, transform.translation, transform.scale);
    Ok(transform)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn points(seed: &[f64]) -> Vec<DVec3> {
        seed.chunks(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]))
            .collect()
    }

    #[test]
    fn collinear_points_are_degenerate() {
        let x: Vec<DVec3> = (0..10)
            .map(|i| DVec3::new(f64::from(i), 0.0, 0.0))
            .collect();
        assert!(matches!(
            umeyama(&x, &x, false),
            Err(Error::DegenerateAlignment(_))
        ));
        assert!(matches!(
            umeyama(&[], &[], false),
            Err(Error::DegenerateAlignment(_))
        ));
    }

    #[test]
    fn matrix_and_first_n_poses() {
        let t = Similarity {
            rotation: DMat3::from_rotation_z(0.5),
            translation: DVec3::new(1.0, 2.0, 3.0),
            scale: 2.0,
        };
        let m = t.to_matrix();
        let x = DVec3::new(0.3, -0.7, 1.1);
        let y = t.apply(x);
        for (i, row) in m.iter().take(3).enumerate() {
            let v = row[0] * x.x + row[1] * x.y + row[2] * x.z + row[3];
            assert!((v - y[i]).abs() < 1e-12);
        }
        assert_eq!(m[3], [0.0, 0.0, 0.0, 1.0]);
        // Fitting on the first poses only: later poses that disagree do not move the fit.
        let positions: Vec<DVec3> = (0..12)
            .map(|i| DVec3::new(f64::from(i), f64::from(i * i % 5), f64::from(i % 3)))
            .collect();
        let mut reference = Trajectory {
            stamps: (0..12).collect(),
            positions: positions.clone(),
            orientations: vec![DQuat::IDENTITY; 12],
            time_unit: crate::TimeUnit::Nanoseconds,
        };
        let mut estimate = reference.clone();
        estimate.positions = positions.iter().map(|p| *p + DVec3::X).collect();
        reference.positions[11] += DVec3::new(0.0, 9.0, 0.0);
        let found = align_first(&mut estimate, &reference, Alignment::Se3, Some(8)).unwrap();
        assert!(found.translation.abs_diff_eq(-DVec3::X, 1e-9), "{found:?}");
        assert!(estimate.positions[3].abs_diff_eq(positions[3], 1e-9));
    }

    #[test]
    fn reflection_is_not_returned() {
        // y is a mirror image of x: the best proper rotation is returned, det = +1.
        let x = points(&[0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 1., 1., 1.]);
        let y: Vec<DVec3> = x.iter().map(|p| DVec3::new(-p.x, p.y, p.z)).collect();
        let t = umeyama(&x, &y, false).unwrap();
        assert!((t.rotation.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn position_yaw_recovers_a_yaw_and_shift_about_either_axis() {
        let x: Vec<DVec3> = (0..20)
            .map(|i| {
                let t = f64::from(i);
                DVec3::new(t.sin() * 3.0, (0.7 * t).cos() * 2.0, 0.1 * t)
            })
            .collect();
        for axis in [GravityAxis::Z, GravityAxis::Y] {
            for yaw in [-2.9, -0.4, 0.0, 0.3, 1.7, 3.1] {
                let rotation = DMat3::from_axis_angle(axis.unit(), yaw);
                let shift = DVec3::new(1.0, -2.0, 0.5);
                let y: Vec<DVec3> = x.iter().map(|p| rotation * *p + shift).collect();
                let found = position_yaw(&x, &y, axis).unwrap();
                assert!(
                    found.rotation.abs_diff_eq(rotation, 1e-12),
                    "{axis:?} {yaw}"
                );
                assert!(found.translation.abs_diff_eq(shift, 1e-12));
                assert_eq!(found.scale, 1.0);
            }
        }
        // A roll in the truth is not fitted: the result stays a rotation about the axis.
        let roll = DMat3::from_rotation_x(0.3);
        let y: Vec<DVec3> = x.iter().map(|p| roll * *p).collect();
        let found = position_yaw(&x, &y, GravityAxis::Z).unwrap();
        assert!((found.rotation * DVec3::Z).abs_diff_eq(DVec3::Z, 1e-12));
        // The yaw is the least-squares one: a brute-force scan finds no better.
        let cost = |theta: f64| -> f64 {
            let r = DMat3::from_rotation_z(theta);
            let (mx, my) = (
                x.iter().copied().sum::<DVec3>() / 20.0,
                y.iter().copied().sum::<DVec3>() / 20.0,
            );
            x.iter()
                .zip(&y)
                .map(|(p, q)| (r * (*p - mx) - (*q - my)).length_squared())
                .sum()
        };
        let best = cost(found.rotation.x_axis.y.atan2(found.rotation.x_axis.x));
        for k in 0..3600 {
            assert!(cost(f64::from(k) * std::f64::consts::TAU / 3600.0) >= best - 1e-12);
        }
    }

    proptest! {
        #[test]
        fn recovers_a_known_similarity(coords in prop::collection::vec(-5.0f64..5.0, 30..60),
                                       axis in (-1.0f64..1.0, -1.0f64..1.0, 0.1f64..1.0),
                                       angle in -3.0f64..3.0, shift in (-9.0f64..9.0, -9.0f64..9.0, -9.0f64..9.0),
                                       scale in 0.2f64..5.0) {
            let x = points(&coords[..coords.len() / 3 * 3]);
            let rotation = DMat3::from_axis_angle(DVec3::new(axis.0, axis.1, axis.2).normalize(), angle);
            let truth = Similarity { rotation, translation: DVec3::new(shift.0, shift.1, shift.2), scale };
            let y: Vec<DVec3> = x.iter().map(|p| truth.apply(*p)).collect();
            // Random points in a box are never (numerically) collinear for ≥ 10 points.
            let found = umeyama(&x, &y, true).unwrap();
            prop_assert!((found.scale - scale).abs() < 1e-9);
            prop_assert!(found.rotation.abs_diff_eq(rotation, 1e-9));
            prop_assert!(found.translation.abs_diff_eq(truth.translation, 1e-8));
            let rigid = Similarity { scale: 1.0, ..truth };
            let y: Vec<DVec3> = x.iter().map(|p| rigid.apply(*p)).collect();
            let found = umeyama(&x, &y, false).unwrap();
            prop_assert!(found.rotation.abs_diff_eq(rotation, 1e-9));
            prop_assert!((found.scale - 1.0).abs() == 0.0);
        }
    }
}
