//! `--transform_left`/`--transform_right`: reading the transformation (a 4×4 matrix as text
//! or `.npy`, or evo's JSON) and applying it to a trajectory's poses.

use std::path::Path;

use anyhow::{Context, Result, bail};
use glam::{DMat3, DMat4, DQuat, DVec3};
use sitar_estimator::Trajectory;

/// evo's `load_transform`: a 4×4 matrix as text or `.npy`, or JSON with `x y z qx qy qz qw`
/// (and optionally `scale`); it must be an SE(3) or Sim(3) matrix.
pub(super) fn load_transform(path: &Path) -> Result<DMat4> {
    let bytes = std::fs::read(path)
        .with_context(|| format!("{}: cannot read the transformation", path.display()))?;
    let name = path.display();
    let rows: Vec<f64> = if bytes.starts_with(b"\x93NUMPY") {
        let array =
            crate::results::archive::parse_npy(&bytes).with_context(|| format!("{name}"))?;
        if array.shape != [4, 4] {
            bail!(
                "{name} doesn't contain a 4x4 matrix (shape {:?})",
                array.shape
            );
        }
        array.data
    } else if bytes.trim_ascii_start().starts_with(b"{") {
        let json: serde_json::Value =
            serde_json::from_slice(&bytes).with_context(|| format!("{name}: not JSON"))?;
        let get = |k: &str| json[k].as_f64();
        let keys = ["x", "y", "z", "qx", "qy", "qz", "qw"];
        let values: Option<Vec<f64>> = keys.iter().map(|k| get(k)).collect();
        let Some(v) = values else {
            bail!("invalid transform file {name} - expected keys {keys:?}");
        };
        let scale = get("scale").unwrap_or(1.0);
        let q = DQuat::from_xyzw(v[3], v[4], v[5], v[6]).normalize();
        let m = DMat4::from_scale_rotation_translation(
            DVec3::splat(scale),
            q,
            DVec3::new(v[0], v[1], v[2]),
        );
        return Ok(m);
    } else {
        let text = String::from_utf8_lossy(&bytes);
        text.lines()
            .filter(|l| !l.trim_start().starts_with('#'))
            .flat_map(str::split_whitespace)
            .map(|t| {
                t.parse::<f64>()
                    .with_context(|| format!("{name}: '{t}' is not a number"))
            })
            .collect::<Result<_>>()?
    };
    if rows.len() != 16 {
        bail!(
            "{name} doesn't contain a valid Sim(3) or SE(3) matrix ({} values, 16 expected)",
            rows.len()
        );
    }
    let m = DMat4::from_cols_slice(&rows).transpose();
    let linear = DMat3::from_mat4(m);
    let scale = linear.determinant().cbrt();
    let rotation = linear * (1.0 / scale);
    let orthonormal = (rotation * rotation.transpose() - DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .all(|e| e.abs() < 1e-6);
    if !(scale > 0.0 && orthonormal && m.row(3).abs_diff_eq(glam::DVec4::W, 1e-9)) {
        bail!("{name} doesn't contain a valid Sim(3) or SE(3) matrix");
    }
    Ok(m)
}

/// A pose as a 4×4 matrix.
pub(super) fn pose_matrix(t: &Trajectory, i: usize) -> DMat4 {
    DMat4::from_rotation_translation(t.orientations[i], t.positions[i])
}

/// Applies `m` to every pose: `m·P` (left), `P·m` (right) or, with `propagate`, the
/// relative motions right-multiplied and chained from the first pose (evo's `transform`).
pub(super) fn apply_transform(
    t: &mut Trajectory,
    m: DMat4,
    right: bool,
    propagate: bool,
) -> Result<()> {
    let poses: Vec<DMat4> = (0..t.len()).map(|i| pose_matrix(t, i)).collect();
    let new: Vec<DMat4> = if right && propagate {
        let mut out = vec![poses[0]];
        for w in poses.windows(2) {
            let relative = w[0].inverse() * w[1] * m;
            let last = *out.last().unwrap_or(&poses[0]);
            out.push(last * relative);
        }
        out
    } else if right {
        poses.iter().map(|p| *p * m).collect()
    } else {
        poses.iter().map(|p| m * *p).collect()
    };
    for (i, p) in new.iter().enumerate() {
        let (scale, rotation, translation) = p.to_scale_rotation_translation();
        if !(scale - DVec3::ONE).abs().max_element().is_finite() {
            bail!("the transformation gives a non-finite pose");
        }
        t.positions[i] = translation;
        t.orientations[i] = rotation.normalize();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transforms_left_right_and_propagated() {
        let mut t = Trajectory {
            stamps: vec![0, 1, 2],
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0],
            orientations: vec![DQuat::IDENTITY; 3],
            time_unit: sitar_estimator::TimeUnit::Seconds,
        };
        let shift = DMat4::from_translation(DVec3::Y);
        let mut left = t.clone();
        apply_transform(&mut left, shift, false, false).unwrap();
        assert!(left.positions[2].abs_diff_eq(DVec3::new(2.0, 1.0, 0.0), 1e-12));
        let turn = DMat4::from_rotation_z(std::f64::consts::FRAC_PI_2);
        apply_transform(&mut t, turn, true, true).unwrap();
        // Each unit step turns a further quarter: (0,0) → (1,0) → (1,1).
        assert!(
            t.positions[2].abs_diff_eq(DVec3::new(1.0, 1.0, 0.0), 1e-12),
            "{}",
            t.positions[2]
        );
    }
}
