//! What one run's own motion shows over a window: the features a calibration reads from the
//! walk itself, and the moving mean that smooths them over neighbouring windows.

use glam::{DQuat, DVec3};

/// How a run moved over one window of `delta` frames (frames `k … k + delta`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WindowMotion {
    /// Path length through every frame of the window, metres.
    pub path_m: f64,
    /// Rotation angle between the window's first and last orientation, degrees.
    pub rotation_deg: f64,
    /// Straight-line distance between the window's first and last position, metres (with the
    /// path length: how much the trajectory wiggles).
    pub displacement_m: f64,
    /// Jitter: the mean of |v₊ − v₋| / Δt over the window's inner frames, m/s², where v₋ and
    /// v₊ are the velocities over the frame intervals before and after a frame and Δt is the
    /// time between those intervals' midpoints. Intervals without time (repeated stamps) are
    /// left out; 0 when no term is left (windows of one frame).
    pub jitter_mps2: f64,
}

/// The angle of a rotation, radians in [0, π] (the same rule as the estimator's).
pub fn rotation_angle(q: DQuat) -> f64 {
    2.0 * q.xyz().length().atan2(q.w.abs())
}

/// The motion of the window starting at frame `k` and spanning `delta` frames, or `None`
/// when the run ends before `k + delta` (or the slices differ in length).
pub fn window_motion(
    stamps: &[i64],
    positions: &[DVec3],
    orientations: &[DQuat],
    k: usize,
    delta: usize,
) -> Option<WindowMotion> {
    let n = stamps.len();
    if positions.len() != n || orientations.len() != n || delta == 0 || k + delta >= n {
        return None;
    }
    let end = k + delta;
    let path_m: f64 = (k..end)
        .map(|i| (positions[i + 1] - positions[i]).length())
        .sum();
    let turn = orientations[k].inverse() * orientations[end];
    let seconds = |a: usize, b: usize| (stamps[b] - stamps[a]) as f64 * 1e-9;
    let velocity = |i: usize| {
        let dt = seconds(i, i + 1);
        (dt > 0.0).then(|| (positions[i + 1] - positions[i]) / dt)
    };
    let (mut sum, mut terms) = (0.0, 0usize);
    for i in k..end.saturating_sub(1) {
        let (Some(before), Some(after)) = (velocity(i), velocity(i + 1)) else {
            continue;
        };
        let dt = 0.5 * seconds(i, i + 2);
        if dt > 0.0 {
            sum += (after - before).length() / dt;
            terms += 1;
        }
    }
    Some(WindowMotion {
        path_m,
        rotation_deg: rotation_angle(turn).to_degrees(),
        displacement_m: (positions[end] - positions[k]).length(),
        jitter_mps2: if terms == 0 { 0.0 } else { sum / terms as f64 },
    })
}

/// The motion of every window of a run, one per start frame `0 … n − delta − 1`.
pub fn run_motion(
    stamps: &[i64],
    positions: &[DVec3],
    orientations: &[DQuat],
    delta: usize,
) -> Vec<WindowMotion> {
    (0..stamps.len().saturating_sub(delta))
        .map_while(|k| window_motion(stamps, positions, orientations, k, delta))
        .collect()
}

/// Moving mean of each column over a row and `h` neighbours on either side, the ends padded
/// with the first and last row (`scipy.ndimage.uniform_filter1d(size=2h+1, mode="nearest")`).
pub fn smooth_columns<const N: usize>(rows: &[[f64; N]], h: usize) -> Vec<[f64; N]> {
    let n = rows.len();
    if n == 0 || h == 0 {
        return rows.to_vec();
    }
    let width = (2 * h + 1) as f64;
    (0..n)
        .map(|i| {
            let mut sum = [0.0f64; N];
            for offset in 0..=2 * h {
                let j = (i + offset).saturating_sub(h).min(n - 1);
                for (s, v) in sum.iter_mut().zip(&rows[j]) {
                    *s += v;
                }
            }
            sum.map(|s| s / width)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_straight_walk_has_no_wiggle_and_no_jitter() {
        let stamps: Vec<i64> = (0..12).map(|i| i * 100_000_000).collect();
        let positions: Vec<DVec3> = (0..12).map(|i| DVec3::X * 0.1 * i as f64).collect();
        let orientations: Vec<DQuat> = (0..12)
            .map(|i| DQuat::from_rotation_y((2.0 * i as f64).to_radians()))
            .collect();
        let m = window_motion(&stamps, &positions, &orientations, 1, 10).unwrap();
        assert!((m.path_m - 1.0).abs() < 1e-12);
        assert!((m.displacement_m - 1.0).abs() < 1e-12);
        assert!((m.rotation_deg - 20.0).abs() < 1e-9);
        assert!(m.jitter_mps2.abs() < 1e-9);
        assert_eq!(
            window_motion(&stamps, &positions, &orientations, 2, 10),
            None
        );
        assert_eq!(run_motion(&stamps, &positions, &orientations, 10).len(), 2);
    }

    #[test]
    fn jitter_is_the_mean_change_of_velocity_per_second() {
        // Back and forth by 1 cm every 0.1 s: v = ±0.1 m/s, |Δv| = 0.2 m/s per 0.1 s.
        let stamps: Vec<i64> = (0..4).map(|i| i * 100_000_000).collect();
        let positions: Vec<DVec3> = [0.0, 0.01, 0.0, 0.01].map(|x| DVec3::X * x).to_vec();
        let orientations = vec![DQuat::IDENTITY; 4];
        let m = window_motion(&stamps, &positions, &orientations, 0, 3).unwrap();
        assert!((m.jitter_mps2 - 2.0).abs() < 1e-9, "{m:?}");
        assert!((m.path_m - 0.03).abs() < 1e-12 && (m.displacement_m - 0.01).abs() < 1e-12);
        // A repeated stamp leaves its terms out instead of dividing by zero.
        let repeated = [0, 100_000_000, 100_000_000, 300_000_000];
        let m = window_motion(&repeated, &positions, &orientations, 0, 3).unwrap();
        assert!(m.jitter_mps2.is_finite());
    }

    #[test]
    fn smoothing_pads_with_the_ends() {
        let rows = [[1.0], [2.0], [6.0]];
        let s = smooth_columns(&rows, 1);
        assert_eq!(s, vec![[4.0 / 3.0], [3.0], [14.0 / 3.0]]);
        assert_eq!(smooth_columns(&rows, 0), rows.to_vec());
    }
}
