//! The minimal pose solver of the RANSAC tracker: perspective-three-point (P3P) after
//! Persson & Nordberg's *Lambda Twist* (ECCV 2018), written from the paper's equations on
//! glam (see the crate docs for why not the `lambda-twist` crate).
//!
//! Three world points `x_i` seen along unit bearings `y_i` give the depths `λ_i` through
//! `|λ_i y_i − λ_j y_j|² = |x_i − x_j|²`. Two homogeneous combinations of these quadrics,
//! `D1` and `D2`, share the solutions; the member `D0 = D1 + γ·D2` with `det D0 = 0` (a cubic
//! in γ) is a pair of planes through the origin, so each solution lies on one of two planes;
//! on each plane `D2` leaves a quadratic. Up to four real solutions, each polished by Newton
//! steps on the three original constraints, then the rotation follows from the two triangles.

use glam::{DMat3, DVec3};

/// A camera pose as the solver and the tracker use it: camera-from-world, in the computer-
/// vision camera frame (x right, y down, z forward): `p_camera = rotation · p_world +
/// translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CameraPose {
    pub rotation: DMat3,
    pub translation: DVec3,
}

impl CameraPose {
    /// The point in the camera frame.
    pub fn apply(&self, world: DVec3) -> DVec3 {
        self.rotation * world + self.translation
    }

    /// The camera centre in the world.
    pub fn centre(&self) -> DVec3 {
        -(self.rotation.transpose() * self.translation)
    }
}

/// Every real, positive-depth P3P solution for bearings `y` (unit, camera frame) of world
/// points `x`; at most four. Degenerate input (collinear points, parallel bearings) gives
/// fewer or none, never NaN.
pub(crate) fn p3p(y: [DVec3; 3], x: [DVec3; 3]) -> [Option<CameraPose>; 4] {
    let mut out = [None; 4];
    let c12 = y[0].dot(y[1]);
    let c13 = y[0].dot(y[2]);
    let c23 = y[1].dot(y[2]);
    let a12 = x[0].distance_squared(x[1]);
    let a13 = x[0].distance_squared(x[2]);
    let a23 = x[1].distance_squared(x[2]);
    let scale = a12.max(a13).max(a23);
    if !(scale.is_finite() && scale > 1e-18) {
        return out;
    }
    // Quadrics Λᵀ M_ij Λ = a_ij (columns of glam matrices are given, all are symmetric).
    let m12 = DMat3::from_cols(
        DVec3::new(1.0, -c12, 0.0),
        DVec3::new(-c12, 1.0, 0.0),
        DVec3::ZERO,
    );
    let m13 = DMat3::from_cols(
        DVec3::new(1.0, 0.0, -c13),
        DVec3::ZERO,
        DVec3::new(-c13, 0.0, 1.0),
    );
    let m23 = DMat3::from_cols(
        DVec3::ZERO,
        DVec3::new(0.0, 1.0, -c23),
        DVec3::new(0.0, -c23, 1.0),
    );
    // Normalised by the scale so the cubic's coefficients are of order one.
    let d1 = (m12 * a23 - m23 * a12) * (1.0 / scale);
    let d2 = (m13 * a23 - m23 * a13) * (1.0 / scale);
    let Some(gamma) = degenerate_member(&d1, &d2) else {
        return out;
    };
    let d0 = d1 + d2 * gamma;
    let Some((e1, e2, s)) = plane_pair(&d0) else {
        return out;
    };
    let mut found = 0;
    for sign in [1.0, -1.0] {
        // Solutions satisfy k·Λ = 0 on this plane: λ1 = w0·λ2 + w1·λ3.
        let k = e1 - e2 * (sign * s);
        if k.x.abs() < 1e-12 {
            continue;
        }
        let (w0, w1) = (-k.y / k.x, -k.z / k.x);
        // Λ = λ3·(τ·p + q) with τ = λ2/λ3; D2 gives a quadratic in τ.
        let p = DVec3::new(w0, 1.0, 0.0);
        let q = DVec3::new(w1, 0.0, 1.0);
        let qa = p.dot(d2 * p);
        let qb = 2.0 * p.dot(d2 * q);
        let qc = q.dot(d2 * q);
        for tau in quadratic_roots(qa, qb, qc).into_iter().flatten() {
            if tau <= 0.0 {
                continue;
            }
            let denominator = tau * tau - 2.0 * c23 * tau + 1.0;
            if denominator <= 0.0 {
                continue;
            }
            let l3 = (a23 / denominator).sqrt();
            let mut lambda = DVec3::new((w0 * tau + w1) * l3, tau * l3, l3);
            if lambda.x <= 0.0 {
                continue;
            }
            lambda = polish([c12, c13, c23], [a12, a13, a23], lambda);
            if !(lambda.is_finite() && lambda.min_element() > 0.0) {
                continue;
            }
            if let Some(pose) = pose_from_depths(y, x, lambda)
                && found < 4
            {
                out[found] = Some(pose);
                found += 1;
            }
        }
    }
    out
}

/// A real root γ of `det(D1 + γ·D2) = 0`, polished by Newton steps.
fn degenerate_member(d1: &DMat3, d2: &DMat3) -> Option<f64> {
    // det(A + γB) = det A + γ·tr(adj(A)·B) + γ²·tr(adj(B)·A) + γ³·det B.
    let c0 = d1.determinant();
    let c1 = trace(&(adjugate(d1) * *d2));
    let c2 = trace(&(adjugate(d2) * *d1));
    let c3 = d2.determinant();
    let f = |g: f64| ((c3 * g + c2) * g + c1) * g + c0;
    let df = |g: f64| (3.0 * c3 * g + 2.0 * c2) * g + c1;
    let mut gamma = cubic_real_root(c3, c2, c1, c0)?;
    for _ in 0..4 {
        let slope = df(gamma);
        if slope == 0.0 {
            break;
        }
        let step = f(gamma) / slope;
        if !step.is_finite() {
            break;
        }
        gamma -= step;
    }
    gamma.is_finite().then_some(gamma)
}

fn trace(m: &DMat3) -> f64 {
    m.x_axis.x + m.y_axis.y + m.z_axis.z
}

/// The adjugate (transposed cofactor matrix): `adj(A)·A = det(A)·I`.
fn adjugate(m: &DMat3) -> DMat3 {
    // Rows of the adjugate are cross products of the columns.
    let (a, b, c) = (m.x_axis, m.y_axis, m.z_axis);
    DMat3::from_cols(b.cross(c), c.cross(a), a.cross(b)).transpose()
}

/// One real root of `a·x³ + b·x² + c·x + d` (lower degrees when leading terms vanish).
fn cubic_real_root(a: f64, b: f64, c: f64, d: f64) -> Option<f64> {
    let size = b.abs().max(c.abs()).max(d.abs());
    if a.abs() <= 1e-12 * size {
        return quadratic_roots(b, c, d).into_iter().flatten().next();
    }
    // Depressed cubic t³ + p·t + q with x = t − b/(3a).
    let (b, c, d) = (b / a, c / a, d / a);
    let shift = b / 3.0;
    let p = c - b * b / 3.0;
    let q = 2.0 * b * b * b / 27.0 - b * c / 3.0 + d;
    let discriminant = q * q / 4.0 + p * p * p / 27.0;
    let t = if discriminant >= 0.0 {
        let r = discriminant.sqrt();
        (-q / 2.0 + r).cbrt() + (-q / 2.0 - r).cbrt()
    } else {
        // Three real roots: the largest, by the trigonometric form.
        let m = 2.0 * (-p / 3.0).sqrt();
        let theta = (3.0 * q / (p * m)).clamp(-1.0, 1.0).acos() / 3.0;
        m * theta.cos()
    };
    let x = t - shift;
    x.is_finite().then_some(x)
}

/// Real roots of `a·x² + b·x + c` (a linear equation when `a` vanishes).
fn quadratic_roots(a: f64, b: f64, c: f64) -> [Option<f64>; 2] {
    let size = b.abs().max(c.abs());
    if a.abs() <= 1e-14 * size {
        if b.abs() <= 1e-300 {
            return [None, None];
        }
        return [Some(-c / b), None];
    }
    let discriminant = b * b - 4.0 * a * c;
    if discriminant < 0.0 {
        return [None, None];
    }
    // The numerically stable form: no cancellation between −b and the root.
    let r = discriminant.sqrt();
    let q = -0.5 * (b + b.signum() * r);
    let first = q / a;
    let second = if q != 0.0 { c / q } else { first };
    [Some(first), Some(second)]
}

/// The plane pair of a rank-2 symmetric `D0 = σ1·e1e1ᵀ + σ2·e2e2ᵀ` with σ1 > 0 > σ2 (up to an
/// overall sign): unit `e1`, `e2` and `s = sqrt(−σ2/σ1)`, so that `Λᵀ D0 Λ = 0` means
/// `e1·Λ = ±s·e2·Λ`.
fn plane_pair(d0: &DMat3) -> Option<(DVec3, DVec3, f64)> {
    let null = null_vector(d0)?;
    // The two other eigenvalues: their sum is the trace, their product the sum of the
    // principal 2×2 minors (the third eigenvalue is zero).
    let (a, b, c) = (d0.x_axis, d0.y_axis, d0.z_axis);
    let tr = a.x + b.y + c.z;
    let minors = (a.x * b.y - a.y * b.x) + (a.x * c.z - a.z * c.x) + (b.y * c.z - b.z * c.y);
    if minors >= 0.0 {
        // Both of one sign: the conic is a single point, no plane pair.
        return None;
    }
    let root = (tr * tr - 4.0 * minors).sqrt();
    let (s1, s2) = ((tr + root) / 2.0, (tr - root) / 2.0);
    let e1 = null_vector(&(*d0 - DMat3::from_diagonal(DVec3::splat(s1))))?;
    let e2 = null.cross(e1).try_normalize()?;
    Some((e1, e2, (-s2 / s1).sqrt()))
}

/// A unit vector spanning the null space of a (numerically) rank-2 3×3 matrix: the longest
/// cross product of two of its rows.
fn null_vector(m: &DMat3) -> Option<DVec3> {
    let t = m.transpose();
    let (r0, r1, r2) = (t.x_axis, t.y_axis, t.z_axis);
    [r0.cross(r1), r0.cross(r2), r1.cross(r2)]
        .into_iter()
        .max_by(|u, v| u.length_squared().total_cmp(&v.length_squared()))
        .and_then(DVec3::try_normalize)
}

/// Newton steps on the three distance constraints.
fn polish(c: [f64; 3], a: [f64; 3], mut l: DVec3) -> DVec3 {
    let [c12, c13, c23] = c;
    for _ in 0..3 {
        let f = DVec3::new(
            l.x * l.x + l.y * l.y - 2.0 * c12 * l.x * l.y - a[0],
            l.x * l.x + l.z * l.z - 2.0 * c13 * l.x * l.z - a[1],
            l.y * l.y + l.z * l.z - 2.0 * c23 * l.y * l.z - a[2],
        );
        // Rows of the Jacobian, as columns of the transpose.
        let jt = DMat3::from_cols(
            DVec3::new(2.0 * (l.x - c12 * l.y), 2.0 * (l.y - c12 * l.x), 0.0),
            DVec3::new(2.0 * (l.x - c13 * l.z), 0.0, 2.0 * (l.z - c13 * l.x)),
            DVec3::new(0.0, 2.0 * (l.y - c23 * l.z), 2.0 * (l.z - c23 * l.y)),
        );
        let j = jt.transpose();
        if j.determinant().abs() < 1e-300 {
            break;
        }
        let step = j.inverse() * f;
        if !step.is_finite() {
            break;
        }
        l -= step;
    }
    l
}

/// The rigid motion taking the world triangle onto the camera-frame triangle `λ_i·y_i`.
fn pose_from_depths(y: [DVec3; 3], x: [DVec3; 3], lambda: DVec3) -> Option<CameraPose> {
    let p = [y[0] * lambda.x, y[1] * lambda.y, y[2] * lambda.z];
    let (dx1, dx2) = (x[0] - x[1], x[0] - x[2]);
    let (dp1, dp2) = (p[0] - p[1], p[0] - p[2]);
    let world = DMat3::from_cols(dx1, dx2, dx1.cross(dx2));
    let camera = DMat3::from_cols(dp1, dp2, dp1.cross(dp2));
    if world.determinant().abs() < 1e-18 {
        return None;
    }
    let rotation = orthonormalise(camera * world.inverse())?;
    let translation = p[0] - rotation * x[0];
    Some(CameraPose {
        rotation,
        translation,
    })
}

/// The nearest rotation, through a normalised quaternion (the input is a rotation up to
/// rounding).
fn orthonormalise(m: DMat3) -> Option<DMat3> {
    if !m.is_finite() || m.determinant() <= 0.0 {
        return None;
    }
    let q = glam::DQuat::from_mat3(&m).normalize();
    q.is_finite().then(|| DMat3::from_quat(q))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use proptest::prelude::*;

    fn solve(pose: &CameraPose, x: [DVec3; 3]) -> Vec<CameraPose> {
        let y = x.map(|p| pose.apply(p).normalize());
        p3p(y, x).into_iter().flatten().collect()
    }

    #[test]
    fn recovers_a_known_pose() {
        let pose = CameraPose {
            rotation: DMat3::from_quat(DQuat::from_euler(glam::EulerRot::YXZ, 0.3, -0.2, 0.1)),
            translation: DVec3::new(0.1, -0.2, 2.0),
        };
        let x = [
            DVec3::new(0.3, 0.1, 0.2),
            DVec3::new(-0.4, 0.2, -0.1),
            DVec3::new(0.1, -0.5, 0.4),
        ];
        let solutions = solve(&pose, x);
        assert!(!solutions.is_empty() && solutions.len() <= 4);
        let best = solutions
            .iter()
            .map(|s| (s.rotation - pose.rotation).abs_diff_eq(DMat3::ZERO, 1e-9) as u8)
            .max()
            .unwrap();
        assert_eq!(best, 1, "{solutions:?}");
        // Every solution reprojects the three points exactly.
        for s in &solutions {
            for p in x {
                let (a, b) = (s.apply(p), pose.apply(p));
                assert!(a.z > 0.0);
                assert!((a.normalize() - b.normalize()).length() < 1e-9);
            }
        }
    }

    #[test]
    fn degenerate_input_gives_no_solution_and_no_nan() {
        let pose = CameraPose {
            rotation: DMat3::IDENTITY,
            translation: DVec3::new(0.0, 0.0, 2.0),
        };
        // Collinear points.
        let x = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        for s in solve(&pose, x) {
            assert!(s.rotation.is_finite() && s.translation.is_finite());
        }
        // Coincident points.
        assert!(solve(&pose, [DVec3::ZERO; 3]).is_empty());
        assert!(
            p3p([DVec3::NAN; 3], [DVec3::X, DVec3::Y, DVec3::Z])
                .iter()
                .all(Option::is_none)
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// For random poses and points in front of the camera, one solution is the true pose.
        #[test]
        fn one_solution_is_the_true_pose(
            yaw in -3.1f64..3.1, pitch in -1.4f64..1.4, roll in -3.1f64..3.1,
            tx in -1.0f64..1.0, ty in -1.0f64..1.0, tz in 1.0f64..6.0,
            pts in proptest::collection::vec((-1.0f64..1.0, -0.8f64..0.8, -0.5f64..1.5), 3),
        ) {
            let rotation = DMat3::from_quat(DQuat::from_euler(glam::EulerRot::YXZ, yaw, pitch, roll));
            let pose = CameraPose { rotation, translation: DVec3::new(tx, ty, tz) };
            // Points in the camera frame in front, mapped to the world.
            let x: Vec<DVec3> = pts.iter().map(|&(a, b, c)| {
                let camera = DVec3::new(a, b, tz + c);
                rotation.transpose() * (camera - pose.translation)
            }).collect();
            let x = [x[0], x[1], x[2]];
            let area = (x[1] - x[0]).cross(x[2] - x[0]).length();
            prop_assume!(area > 0.05);
            let solutions = solve(&pose, x);
            let error = solutions
                .iter()
                .map(|s| (s.centre() - pose.centre()).length())
                .fold(f64::INFINITY, f64::min);
            prop_assert!(error < 1e-6, "centre off by {} over {} solutions", error, solutions.len());
        }
    }
}
