//! Drift over path length: the KITTI odometry benchmark's translational and rotational error,
//! as its devkit (`evaluate_odometry.cpp`) defines it.
//!
//! Segments are cut from the ground truth by *path length*: from every `step`-th pose
//! (`first` = 0, step, 2·step, …) and for every length `L` (100, 200, …, 800 m by default)
//! the segment ends at the first pose `last ≥ first` whose cumulative ground-truth path
//! length exceeds that of `first` by more than `L` (the devkit's
//! `lastFrameFromSegmentLength`); when there is none, that (first, L) gives no segment. Per
//! segment, with `G` the ground-truth poses and `E` the estimate's (world-from-body),
//!
//! ```text
//! error pose   = (G_first⁻¹·G_last)⁻¹ · (E_first⁻¹·E_last)
//! t_err        = ‖translation of the error pose‖ / L            (reported in %)
//! r_err        = rotation angle of the error pose / L           (reported in deg/m)
//! speed        = L / (interval · (last − first + 1))            (frames, KITTI: 0.1 s)
//!              = L / (t_last − t_first)                         (stamps)
//! ```
//!
//! The averages are means over segments: over every segment (the devkit's `stats.txt`),
//! per length and per speed bin (the devkit's error plots: a bin centred on `c` takes the
//! segments with `|speed − c| < half width`, and a bin is shown only with at least 3
//! segments).
//!
//! Differences from the devkit, all on purpose:
//! * f64 throughout (the devkit accumulates path length and errors in float32, which over a
//!   KITTI sequence of 4 km loses about a millimetre of path per kilometre);
//! * the rotation angle is `2·atan2(‖q_xyz‖, |q_w|)` of the error quaternion, the angle the
//!   devkit's `acos((trace − 1)/2)` computes, without the loss of precision of `acos` near 0;
//! * the rotational error is reported in degrees per metre (the devkit keeps radians per
//!   metre in its numbers and multiplies by 57.3 in its plots; here `to_degrees`, 180/π);
//! * the devkit's error pose is `(E_first⁻¹·E_last)⁻¹ · (G_first⁻¹·G_last)`, the inverse of
//!   the one above: both have the same rotation angle and the same translation length;
//! * segments are grouped by their nominal length (the devkit's `|len − L| < 1 m` is the same
//!   for its lengths 100 m apart, but would merge lengths under a metre apart);
//! * trajectories with stamps take the speed from the ground truth's stamps (float64
//!   seconds, as evo holds them), not from a 10 Hz frame rate.

use crate::{Error, RigidPose, Trajectory, rotation_angle};

/// The KITTI benchmark's segment lengths, metres.
pub const KITTI_LENGTHS_M: [f64; 8] = [100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0];
/// The KITTI devkit's step between segment starts, poses.
pub const KITTI_STEP: usize = 10;
/// KITTI's frame interval (10 Hz), seconds.
pub const KITTI_FRAME_INTERVAL_S: f64 = 0.1;
/// The devkit's spacing of speed bins (centres 2, 4, …, 24 m/s, each ± 2 m/s), m/s.
pub const KITTI_SPEED_STEP_M_S: f64 = 2.0;
/// Number of speed bins of the devkit's plots.
pub const SPEED_BINS: usize = 12;
/// The devkit's plots show a length or speed only with at least this many segments.
pub const MIN_SEGMENTS_PER_BIN: usize = 3;

/// How a segment's duration is known, for its speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SegmentDuration {
    /// Poses at a fixed interval (KITTI: 0.1 s): `interval · (last − first + 1)`, as the
    /// devkit counts it.
    Frames {
        /// Seconds between poses.
        interval_s: f64,
    },
    /// From the reference's stamps: `t_last − t_first` (float64 seconds, as evo's).
    Stamps,
}

/// The options of [`drift`]; the default is the KITTI benchmark's.
#[derive(Debug, Clone, PartialEq)]
pub struct DriftOptions {
    /// Segment lengths along the ground truth's path, metres, each positive and finite.
    pub lengths_m: Vec<f64>,
    /// A segment starts at every `step`-th pose (≥ 1).
    pub step: usize,
    /// How a segment's duration (for its speed) is known.
    pub duration: SegmentDuration,
    /// Centres of the speed bins, m/s.
    pub speed_bins_m_s: Vec<f64>,
    /// A segment belongs to every bin whose centre is nearer than this to its speed, m/s.
    pub speed_bin_half_width_m_s: f64,
    /// Lengths and speed bins with fewer segments are left out of the per-length and
    /// per-speed averages (not out of the overall one).
    pub min_segments_per_bin: usize,
}

impl Default for DriftOptions {
    fn default() -> Self {
        Self {
            lengths_m: KITTI_LENGTHS_M.to_vec(),
            step: KITTI_STEP,
            duration: SegmentDuration::Frames {
                interval_s: KITTI_FRAME_INTERVAL_S,
            },
            speed_bins_m_s: speed_bins(KITTI_SPEED_STEP_M_S),
            speed_bin_half_width_m_s: KITTI_SPEED_STEP_M_S,
            min_segments_per_bin: MIN_SEGMENTS_PER_BIN,
        }
    }
}

impl DriftOptions {
    /// These options with speed bins `step` apart: centres `step, 2·step, …, 12·step`, each
    /// `± step` wide, as the devkit's 2, 4, …, 24 m/s are for cars (`step` 2 m/s).
    pub fn with_speed_step(mut self, step_m_s: f64) -> Self {
        self.speed_bins_m_s = speed_bins(step_m_s);
        self.speed_bin_half_width_m_s = step_m_s;
        self
    }
}

/// Centres `step, 2·step, …, 12·step`.
fn speed_bins(step: f64) -> Vec<f64> {
    (1..=SPEED_BINS).map(|k| k as f64 * step).collect()
}

/// One segment and its errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriftSegment {
    /// Index of its first pose.
    pub first: usize,
    /// Index of its last pose.
    pub last: usize,
    /// Its nominal length `L`, metres.
    pub length_m: f64,
    /// `L` over its duration, m/s.
    pub speed_m_s: f64,
    /// Translational error: 100 · ‖t_err‖ / L.
    pub t_err_percent: f64,
    /// Rotational error: angle (degrees) / L.
    pub r_err_deg_per_m: f64,
}

/// The mean errors of the segments of one length or one speed bin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriftBin {
    /// The length (m) or the speed bin's centre (m/s).
    pub centre: f64,
    /// Number of segments averaged.
    pub segments: usize,
    /// Mean translational error, %.
    pub t_err_percent: f64,
    /// Mean rotational error, deg/m.
    pub r_err_deg_per_m: f64,
}

/// The drift of an estimate: every segment, and the averages.
#[derive(Debug, Clone, PartialEq)]
pub struct Drift {
    /// Every segment, by start pose then by length in the options' order (the devkit's).
    pub segments: Vec<DriftSegment>,
    /// Mean translational error over every segment, % (the devkit's `stats.txt`, × 100).
    pub t_err_percent: f64,
    /// Mean rotational error over every segment, deg/m (`stats.txt`, in degrees).
    pub r_err_deg_per_m: f64,
    /// Per length, in the options' order; lengths with too few segments left out.
    pub by_length: Vec<DriftBin>,
    /// Per speed bin, in the options' order; bins with too few segments left out.
    pub by_speed: Vec<DriftBin>,
}

/// The drift of `estimate` against `reference`, two *associated* trajectories (same length,
/// pose `i` of one paired with pose `i` of the other), as the KITTI devkit computes it (see
/// the module docs). Errors on bad options, unequal lengths, non-finite poses, or when no
/// segment fits (the reference's path is not longer than the shortest length).
pub fn drift(
    reference: &Trajectory,
    estimate: &Trajectory,
    options: &DriftOptions,
) -> Result<Drift, Error> {
    check_options(options)?;
    if reference.len() != estimate.len() {
        return Err(Error::InvalidArgument(format!(
            "the drift needs associated trajectories of equal length ({} and {} poses)",
            reference.len(),
            estimate.len()
        )));
    }
    reference.validate_poses()?;
    estimate.validate_poses()?;
    let distances = reference.distances();
    let seconds = match options.duration {
        SegmentDuration::Stamps => Some(reference.seconds()),
        SegmentDuration::Frames { .. } => None,
    };
    let mut segments = Vec::new();
    for first in (0..reference.len()).step_by(options.step) {
        for &length in &options.lengths_m {
            let Some(last) = last_pose(&distances, first, length) else {
                continue;
            };
            let truth = RigidPose::relative(reference.pose(first), reference.pose(last));
            let moved = RigidPose::relative(estimate.pose(first), estimate.pose(last));
            let error = RigidPose::relative(truth, moved);
            let duration = match (options.duration, &seconds) {
                (SegmentDuration::Frames { interval_s }, _) => {
                    interval_s * (last - first + 1) as f64
                }
                (SegmentDuration::Stamps, Some(t)) => t[last] - t[first],
                (SegmentDuration::Stamps, None) => unreachable!("stamps read above"),
            };
            segments.push(DriftSegment {
                first,
                last,
                length_m: length,
                speed_m_s: length / duration,
                t_err_percent: 100.0 * error.translation.length() / length,
                r_err_deg_per_m: rotation_angle(error.rotation).to_degrees() / length,
            });
        }
    }
    if segments.is_empty() {
        let shortest = options
            .lengths_m
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        return Err(Error::NoPairs(format!(
            "no segment: the reference's path ({:.3} m over {} poses) is not longer than the shortest segment length ({shortest} m)",
            distances.last().copied().unwrap_or(0.0),
            reference.len()
        )));
    }
    let all: Vec<&DriftSegment> = segments.iter().collect();
    let (t_err_percent, r_err_deg_per_m) = means(&all);
    let bin = |centre: f64, members: Vec<&DriftSegment>| {
        (members.len() >= options.min_segments_per_bin.max(1)).then(|| {
            let (t, r) = means(&members);
            DriftBin {
                centre,
                segments: members.len(),
                t_err_percent: t,
                r_err_deg_per_m: r,
            }
        })
    };
    let by_length = options
        .lengths_m
        .iter()
        .filter_map(|&length| {
            bin(
                length,
                segments.iter().filter(|s| s.length_m == length).collect(),
            )
        })
        .collect();
    let half = options.speed_bin_half_width_m_s;
    let by_speed = options
        .speed_bins_m_s
        .iter()
        .filter_map(|&centre| {
            bin(
                centre,
                segments
                    .iter()
                    .filter(|s| (s.speed_m_s - centre).abs() < half)
                    .collect(),
            )
        })
        .collect();
    Ok(Drift {
        segments,
        t_err_percent,
        r_err_deg_per_m,
        by_length,
        by_speed,
    })
}

/// The devkit's `lastFrameFromSegmentLength`: the first index `i ≥ first` whose distance
/// exceeds `distances[first] + length` (distances never decrease, so a binary search).
fn last_pose(distances: &[f64], first: usize, length: f64) -> Option<usize> {
    let target = distances[first] + length;
    let last = first + distances[first..].partition_point(|&d| d <= target);
    (last < distances.len()).then_some(last)
}

/// Mean translational and rotational error of `segments` (not empty).
fn means(segments: &[&DriftSegment]) -> (f64, f64) {
    let n = segments.len() as f64;
    let (t, r) = segments.iter().fold((0.0, 0.0), |(t, r), s| {
        (t + s.t_err_percent, r + s.r_err_deg_per_m)
    });
    (t / n, r / n)
}

fn check_options(options: &DriftOptions) -> Result<(), Error> {
    let bad = |what: String| Err(Error::InvalidArgument(what));
    if options.lengths_m.is_empty() {
        return bad("no segment lengths".into());
    }
    if let Some(l) = options
        .lengths_m
        .iter()
        .find(|l| !(l.is_finite() && **l > 0.0))
    {
        return bad(format!("segment lengths must be positive metres, got {l}"));
    }
    if options.step == 0 {
        return bad("the step between segment starts must be at least 1 pose".into());
    }
    if let SegmentDuration::Frames { interval_s } = options.duration
        && !(interval_s.is_finite() && interval_s > 0.0)
    {
        return bad(format!(
            "the frame interval must be positive seconds, got {interval_s}"
        ));
    }
    let half = options.speed_bin_half_width_m_s;
    if !(half.is_finite() && half > 0.0) || options.speed_bins_m_s.iter().any(|c| !c.is_finite()) {
        return bad(format!(
            "speed bins must be finite with a positive half width, got ± {half}"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TimeUnit;
    use glam::{DQuat, DVec3};

    /// Poses along x, `spacing` apart, 10 Hz stamps.
    fn line(n: usize, spacing: f64, scale: f64) -> Trajectory {
        Trajectory {
            stamps: (0..n as i64).map(|i| i * 100_000_000).collect(),
            positions: (0..n)
                .map(|i| DVec3::new(i as f64 * spacing * scale, 0.0, 0.0))
                .collect(),
            orientations: vec![DQuat::IDENTITY; n],
            time_unit: TimeUnit::Nanoseconds,
        }
    }

    #[test]
    fn the_last_pose_is_the_first_beyond_the_length() {
        let d = [0.0, 1.0, 2.0, 3.0, 3.0, 4.5];
        assert_eq!(last_pose(&d, 0, 2.0), Some(3)); // 2.0 is not beyond 2.0
        assert_eq!(last_pose(&d, 0, 2.5), Some(3));
        assert_eq!(last_pose(&d, 1, 2.0), Some(5)); // 3.0 twice, then 4.5
        assert_eq!(last_pose(&d, 2, 2.5), None);
        assert_eq!(last_pose(&d, 0, 0.5), Some(1));
    }

    #[test]
    fn a_constant_scale_error_is_that_share_on_every_segment() {
        let reference = line(400, 1.0, 1.0);
        let estimate = line(400, 1.0, 1.03);
        let options = DriftOptions {
            lengths_m: vec![10.0, 50.0, 100.0],
            ..DriftOptions::default()
        };
        let result = drift(&reference, &estimate, &options).unwrap();
        for s in &result.segments {
            // Poses 1 m apart: the segment is L + 1 m of path (the first pose beyond L).
            let path = (s.last - s.first) as f64;
            assert_eq!(path, s.length_m + 1.0);
            let want = 3.0 * path / s.length_m;
            assert!((s.t_err_percent - want).abs() < 1e-9, "{s:?}");
            assert_eq!(s.r_err_deg_per_m, 0.0);
            assert!((s.speed_m_s - s.length_m / (0.1 * (path + 1.0))).abs() < 1e-12);
        }
        assert_eq!(result.by_length.len(), 3);
        assert_eq!(result.by_length[0].segments, 39); // starts 0..=380 with 11 m left
    }

    #[test]
    fn options_are_checked() {
        let t = line(30, 1.0, 1.0);
        let with = |f: fn(&mut DriftOptions)| {
            let mut o = DriftOptions {
                lengths_m: vec![5.0],
                ..DriftOptions::default()
            };
            f(&mut o);
            drift(&t, &t, &o)
        };
        assert!(with(|_| ()).is_ok());
        assert!(with(|o| o.lengths_m.clear()).is_err());
        assert!(with(|o| o.lengths_m = vec![0.0]).is_err());
        assert!(with(|o| o.lengths_m = vec![f64::NAN]).is_err());
        assert!(with(|o| o.step = 0).is_err());
        assert!(with(|o| o.duration = SegmentDuration::Frames { interval_s: 0.0 }).is_err());
        assert!(with(|o| o.speed_bin_half_width_m_s = -1.0).is_err());
        assert!(matches!(
            with(|o| o.lengths_m = vec![100.0]),
            Err(Error::NoPairs(_))
        ));
        let short = line(29, 1.0, 1.0);
        assert!(drift(&t, &short, &DriftOptions::default()).is_err());
    }
}
