//! The trajectory type: stamped world-from-camera poses.

use glam::{DMat3, DQuat, DVec3};

use crate::Error;

/// Largest accepted deviation of a quaternion's norm from 1 (inputs within it are normalised).
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-3;

/// The unit a trajectory's timestamps were written in; output keeps it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum TimeUnit {
    /// Integer nanoseconds (ARCore, EuRoC).
    #[default]
    Nanoseconds,
    /// Decimal seconds (classic TUM files).
    Seconds,
    /// ROS header stamps (`sec`, `nanosec`, from bags): evo holds them as the float64
    /// `sec + nanosec * 1e-9`, which can be one ulp off the float nearest the decimal.
    RosStamp,
}

impl TimeUnit {
    /// Formats a nanosecond stamp in this unit: an integer for ns, 9 decimals for seconds.
    pub fn format_stamp(self, t_ns: i64) -> String {
        match self {
            TimeUnit::Nanoseconds => t_ns.to_string(),
            TimeUnit::Seconds | TimeUnit::RosStamp => {
                let sign = if t_ns < 0 { "-" } else { "" };
                let abs = t_ns.unsigned_abs();
                format!("{sign}{}.{:09}", abs / 1_000_000_000, abs % 1_000_000_000)
            }
        }
    }

    /// A stamp as the float64 seconds evo holds. Read as seconds: the float nearest the
    /// decimal, which is what Python's `float()` makes of a TUM stamp written with up to 9
    /// decimals. Read as nanoseconds: evo's `float(ns) / 1e9` (its EuRoC reader), rounded twice
    /// above 2⁵³ ns as there. ROS stamps: evo's `sec + nanosec * 1e-9`.
    pub fn seconds(self, t_ns: i64) -> f64 {
        const EXACT: u64 = 1 << 53;
        match self {
            TimeUnit::RosStamp => {
                let (sec, nanosec) = (
                    t_ns.div_euclid(1_000_000_000),
                    t_ns.rem_euclid(1_000_000_000),
                );
                sec as f64 + nanosec as f64 * 1e-9
            }
            TimeUnit::Seconds if t_ns.unsigned_abs() >= EXACT => nearest_quotient(t_ns),
            // Below 2⁵³ both operands are exact, so the one division rounds correctly.
            TimeUnit::Seconds | TimeUnit::Nanoseconds => t_ns as f64 / 1e9,
        }
    }

    /// Stamps in (float) seconds, as evo's: decimal seconds or ROS stamps.
    pub fn is_seconds(self) -> bool {
        matches!(self, TimeUnit::Seconds | TimeUnit::RosStamp)
    }
}

/// The float nearest `t_ns / 10⁹` (ties to even) for |t_ns| ≥ 2⁵³, where `t_ns as f64` would
/// round first: a close guess, then the nearest of it and its two neighbours, compared
/// exactly in integers (every candidate is `m·2^e` with e < 0 here).
fn nearest_quotient(t_ns: i64) -> f64 {
    let abs = t_ns.unsigned_abs();
    let (whole, fraction) = (abs / 1_000_000_000, abs % 1_000_000_000);
    let guess = whole as f64 + fraction as f64 / 1e9;
    let parts = |c: f64| {
        let bits = c.to_bits();
        let mantissa = (bits & ((1 << 52) - 1)) | (1 << 52);
        (i128::from(mantissa), ((bits >> 52) & 0x7ff) as i32 - 1075)
    };
    let below = f64::from_bits(guess.to_bits() - 1);
    let lowest_exponent = parts(below).1;
    let target = i128::from(abs) << -lowest_exponent;
    let error = |c: f64| {
        let (m, e) = parts(c);
        (((m * 1_000_000_000) << (e - lowest_exponent)) - target).abs()
    };
    let mut best = below;
    for candidate in [guess, f64::from_bits(guess.to_bits() + 1)] {
        let (d, b) = (error(candidate), error(best));
        if d < b || (d == b && parts(candidate).0 & 1 == 0) {
            best = candidate;
        }
    }
    if t_ns < 0 { -best } else { best }
}

/// Stamped poses (world-from-camera). Stamps are nanoseconds, orientations unit quaternions.
/// [`Trajectory::from_poses`] and SiTAR's readers also make the stamps strictly increasing;
/// a trajectory read by evo's rules ([`crate::ReadOptions::EVO`]) keeps them as written,
/// repeated or unsorted, as evo does.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trajectory {
    /// Timestamps in nanoseconds, strictly increasing.
    pub stamps: Vec<i64>,
    /// Camera positions in the world frame (metres).
    pub positions: Vec<DVec3>,
    /// Camera orientations (world-from-camera), unit quaternions.
    pub orientations: Vec<DQuat>,
    /// The unit the stamps were read in (kept on output).
    pub time_unit: TimeUnit,
}

impl Trajectory {
    /// Builds a checked trajectory: equal lengths, finite values, strictly increasing stamps,
    /// quaternions within [`QUATERNION_NORM_TOLERANCE`] of unit norm (they are normalised).
    pub fn from_poses(
        stamps: Vec<i64>,
        positions: Vec<DVec3>,
        orientations: Vec<DQuat>,
        time_unit: TimeUnit,
    ) -> Result<Self, Error> {
        if stamps.len() != positions.len() || stamps.len() != orientations.len() {
            return Err(Error::InvalidTrajectory(format!(
                "{} stamps, {} positions and {} orientations",
                stamps.len(),
                positions.len(),
                orientations.len()
            )));
        }
        let mut orientations = orientations;
        for (i, (p, q)) in positions.iter().zip(orientations.iter_mut()).enumerate() {
            if !p.is_finite() || !q.is_finite() {
                return Err(Error::InvalidTrajectory(format!("pose {i} is not finite")));
            }
            let norm = q.length();
            if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
                return Err(Error::InvalidTrajectory(format!(
                    "pose {i}: quaternion norm {norm} is not 1"
                )));
            }
            *q /= norm;
        }
        if let Some(i) = stamps.windows(2).position(|w| w[1] <= w[0]) {
            return Err(Error::InvalidTrajectory(format!(
                "stamp {} ({}) does not increase after stamp {} ({})",
                i + 1,
                stamps[i + 1],
                i,
                stamps[i]
            )));
        }
        Ok(Self {
            stamps,
            positions,
            orientations,
            time_unit,
        })
    }

    /// Checks the invariants [`Trajectory::from_poses`] establishes (the fields are public):
    /// equal lengths, strictly increasing stamps, finite positions, unit quaternions.
    pub fn validate(&self) -> Result<(), Error> {
        self.validate_poses()?;
        if let Some(i) = self.stamps.windows(2).position(|w| w[1] <= w[0]) {
            return Err(Error::InvalidTrajectory(format!(
                "stamp {} does not increase after stamp {i}",
                i + 1
            )));
        }
        Ok(())
    }

    /// [`Trajectory::validate`] without the stamp order: what metrics and alignment need.
    /// An *associated* trajectory may repeat a stamp, because two poses of the walked
    /// trajectory can share their nearest match (evo keeps both, and so do we).
    pub fn validate_poses(&self) -> Result<(), Error> {
        if self.stamps.len() != self.positions.len() || self.stamps.len() != self.orientations.len()
        {
            return Err(Error::InvalidTrajectory(format!(
                "{} stamps, {} positions and {} orientations",
                self.stamps.len(),
                self.positions.len(),
                self.orientations.len()
            )));
        }
        let bad =
            |q: &DQuat| !q.is_finite() || (q.length() - 1.0).abs() > QUATERNION_NORM_TOLERANCE;
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::InvalidTrajectory(format!(
                "position {i} is not finite"
            )));
        }
        if let Some(i) = self.orientations.iter().position(bad) {
            return Err(Error::InvalidTrajectory(format!(
                "orientation {i} is not a unit quaternion"
            )));
        }
        Ok(())
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.stamps.len()
    }

    /// True when there are no poses.
    pub fn is_empty(&self) -> bool {
        self.stamps.is_empty()
    }

    /// A copy holding only the poses at `ids` (in that order; ids may repeat, as evo's `reduce_to_ids`).
    pub fn reduce_to_ids(&self, ids: &[usize]) -> Trajectory {
        Trajectory {
            stamps: ids.iter().map(|&i| self.stamps[i]).collect(),
            positions: ids.iter().map(|&i| self.positions[i]).collect(),
            orientations: ids.iter().map(|&i| self.orientations[i]).collect(),
            time_unit: self.time_unit,
        }
    }

    /// Applies `x ↦ rotation·(scale·x) + translation` to every pose (evo's `scale` then `transform`).
    pub fn transform(&mut self, rotation: DQuat, translation: DVec3, scale: f64) {
        for (p, q) in self.positions.iter_mut().zip(self.orientations.iter_mut()) {
            *p = rotation * (*p * scale) + translation;
            *q = rotation * *q;
        }
    }

    /// Total path length (sum of distances between consecutive positions), metres, summed
    /// as numpy's `sum` does (pairwise), so that it equals evo's `path_length` to the bit.
    pub fn path_length(&self) -> f64 {
        let steps: Vec<f64> = self
            .positions
            .windows(2)
            .map(|w| (w[0] - w[1]).length())
            .collect();
        pairwise_sum(&steps)
    }

    /// Path length from the first pose to each pose, metres (evo's `distances`).
    pub fn distances(&self) -> Vec<f64> {
        let mut total = 0.0;
        let mut out = Vec::with_capacity(self.len());
        for (i, p) in self.positions.iter().enumerate() {
            if i > 0 {
                total += (*p - self.positions[i - 1]).length();
            }
            out.push(total);
        }
        out
    }

    /// The stamps as evo's float64 seconds (see [`TimeUnit::seconds`]).
    pub fn seconds(&self) -> Vec<f64> {
        self.stamps
            .iter()
            .map(|&t| self.time_unit.seconds(t))
            .collect()
    }

    /// True when no stamp is below the one before it (repeats allowed).
    pub fn is_sorted(&self) -> bool {
        self.stamps.windows(2).all(|w| w[0] <= w[1])
    }

    /// Keeps at most `max_poses` evenly spaced poses, as evo's `downsample` (numpy's
    /// `linspace(0, n − 1, max_poses)` truncated to indices); fewer poses are left alone.
    pub fn downsample(&mut self, max_poses: usize) -> Result<(), Error> {
        let n = self.len();
        if n <= max_poses {
            return Ok(());
        }
        if max_poses == 0 {
            return Err(Error::InvalidArgument(
                "can't downsample to less than one pose".into(),
            ));
        }
        let ids: Vec<usize> = if max_poses == 1 {
            vec![0]
        } else {
            let step = (n - 1) as f64 / (max_poses - 1) as f64;
            (0..max_poses)
                .map(|i| {
                    if i == max_poses - 1 {
                        n - 1
                    } else {
                        (i as f64 * step) as usize
                    }
                })
                .collect()
        };
        *self = self.reduce_to_ids(&ids);
        Ok(())
    }

    /// evo's `motion_filter`: keeps the first pose and every pose that moved at least
    /// `distance_m` along the path, or turned at least `angle_deg`, since the last kept one.
    pub fn motion_filter(&mut self, distance_m: f64, angle_deg: f64) -> Result<(), Error> {
        if self.len() < 2 {
            return Err(Error::InvalidArgument(
                "motion filter: poses must contain at least two poses".into(),
            ));
        }
        if !(distance_m >= 0.0 && angle_deg >= 0.0) {
            return Err(Error::InvalidArgument(format!(
                "motion filter thresholds must be >= 0 (got {distance_m} m, {angle_deg} deg)"
            )));
        }
        let angle = angle_deg.to_radians();
        let distances = self.distances();
        let (mut last, mut last_distance) = (0usize, 0.0);
        let mut ids = vec![0];
        for (i, &distance) in distances.iter().enumerate().skip(1) {
            let turned = rotation_angle(self.orientations[last].conjugate() * self.orientations[i]);
            if distance - last_distance >= distance_m || turned >= angle {
                ids.push(i);
                last = i;
                last_distance = distance;
            }
        }
        *self = self.reduce_to_ids(&ids);
        Ok(())
    }

    /// Keeps the poses with `start ≤ stamp ≤ end` (ns; `None`: the first or last stamp), as
    /// evo's `reduce_to_time_range`, on the float64 seconds evo holds
    /// ([`Trajectory::seconds`]): keeps the poses with `start ≤ stamp ≤ end` (seconds;
    /// `None`: the first or last stamp).
    pub fn reduce_to_time_range(
        &mut self,
        start: Option<f64>,
        end: Option<f64>,
    ) -> Result<(), Error> {
        let seconds = self.seconds();
        let (Some(&first), Some(&last)) = (seconds.first(), seconds.last()) else {
            return Err(Error::InvalidTrajectory("trajectory is empty".into()));
        };
        let (start, end) = (start.unwrap_or(first), end.unwrap_or(last));
        if start > end {
            return Err(Error::InvalidArgument(format!(
                "start time is greater than end time ({start} > {end} s)"
            )));
        }
        let ids: Vec<usize> = (0..self.len())
            .filter(|&i| seconds[i] >= start && seconds[i] <= end)
            .collect();
        *self = self.reduce_to_ids(&ids);
        Ok(())
    }

    /// Projects into `plane` as evo's `project`: the normal coordinate becomes 0 and each
    /// orientation the rotation about the normal by its static-xyz Euler angle of that axis.
    pub fn project(&mut self, plane: Plane) {
        let normal = plane.normal_axis();
        for (p, q) in self.positions.iter_mut().zip(self.orientations.iter_mut()) {
            p[normal] = 0.0;
            let angle = euler_sxyz(DMat3::from_quat(*q))[normal];
            let mut axis = DVec3::ZERO;
            axis[normal] = 1.0;
            *q = DQuat::from_axis_angle(axis, angle);
        }
    }

    /// The trajectory at `stamps` as evo's `interpolate` (no extrapolation): positions
    /// linearly, orientations by slerp between the poses around each stamp; stamps outside
    /// the trajectory take its first or last pose. The stamps must be sorted.
    pub fn interpolate(&self, stamps: &[i64]) -> Result<Trajectory, Error> {
        let n = self.len();
        if n < 2 {
            return Err(Error::InvalidArgument(
                "can't interpolate a trajectory with less than two poses".into(),
            ));
        }
        let mut out = Trajectory {
            stamps: stamps.to_vec(),
            positions: Vec::with_capacity(stamps.len()),
            orientations: Vec::with_capacity(stamps.len()),
            time_unit: self.time_unit,
        };
        for &t in stamps {
            let k = self.stamps.partition_point(|&s| s < t).clamp(1, n - 1);
            let (t0, t1) = (self.stamps[k - 1], self.stamps[k]);
            let dt = (t1 - t0) as f64;
            let f = if dt > 0.0 {
                ((t - t0) as f64 / dt).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (p0, p1) = (self.positions[k - 1], self.positions[k]);
            out.positions.push(p0 + f * (p1 - p0));
            out.orientations
                .push(slerp(self.orientations[k - 1], self.orientations[k], f));
        }
        Ok(out)
    }

    /// All poses of `trajectories` in one, sorted by stamp (stable), as evo's `merge`.
    pub fn merge(trajectories: &[Trajectory]) -> Trajectory {
        let mut all: Vec<(i64, DVec3, DQuat)> = trajectories
            .iter()
            .flat_map(|t| {
                (0..t.len()).map(move |i| (t.stamps[i], t.positions[i], t.orientations[i]))
            })
            .collect();
        all.sort_by_key(|e| e.0);
        Trajectory {
            stamps: all.iter().map(|e| e.0).collect(),
            positions: all.iter().map(|e| e.1).collect(),
            orientations: all.iter().map(|e| e.2).collect(),
            time_unit: trajectories
                .first()
                .map_or_else(TimeUnit::default, |t| t.time_unit),
        }
    }
}

/// numpy's pairwise summation of float64: blocks of up to 128 values summed with eight
/// interleaved accumulators, larger ranges split in halves (a multiple of eight first).
pub fn pairwise_sum(values: &[f64]) -> f64 {
    let n = values.len();
    if n < 8 {
        return values.iter().fold(-0.0, |sum, v| sum + v);
    }
    if n <= 128 {
        let mut r = [0.0; 8];
        r.copy_from_slice(&values[..8]);
        let whole = n - n % 8;
        for chunk in values[8..whole].chunks_exact(8) {
            for (acc, v) in r.iter_mut().zip(chunk) {
                *acc += v;
            }
        }
        let mut sum = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for v in &values[whole..] {
            sum += v;
        }
        return sum;
    }
    let mut half = n / 2;
    half -= half % 8;
    pairwise_sum(&values[..half]) + pairwise_sum(&values[half..])
}

/// A coordinate plane (evo's `Plane`, for `--project_to_plane`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Plane {
    /// The xy plane (z = 0).
    Xy,
    /// The xz plane (y = 0).
    Xz,
    /// The yz plane (x = 0).
    Yz,
}

impl Plane {
    /// Index of the coordinate the projection sets to zero.
    pub fn normal_axis(self) -> usize {
        match self {
            Plane::Xy => 2,
            Plane::Xz => 1,
            Plane::Yz => 0,
        }
    }
}

/// Static-frame x-y-z Euler angles of a rotation matrix (the `sxyz` convention of evo's
/// `transformations.euler_from_matrix`).
pub fn euler_sxyz(m: DMat3) -> [f64; 3] {
    // m.col(c)[r] is the matrix element (r, c).
    let e = |r: usize, c: usize| m.col(c)[r];
    let cy = (e(0, 0) * e(0, 0) + e(1, 0) * e(1, 0)).sqrt();
    if cy > 4.0 * f64::EPSILON {
        [
            e(2, 1).atan2(e(2, 2)),
            (-e(2, 0)).atan2(cy),
            e(1, 0).atan2(e(0, 0)),
        ]
    } else {
        [(-e(1, 2)).atan2(e(1, 1)), (-e(2, 0)).atan2(cy), 0.0]
    }
}

/// Spherical linear interpolation along the shorter arc, as evo's `quaternion_slerp`.
fn slerp(q0: DQuat, q1: DQuat, f: f64) -> DQuat {
    let (q0, mut q1) = (q0.normalize(), q1.normalize());
    if f == 0.0 {
        return q0;
    }
    if f == 1.0 {
        return q1;
    }
    let mut d = q0.dot(q1);
    if (d.abs() - 1.0).abs() < 4.0 * f64::EPSILON {
        return q0;
    }
    if d < 0.0 {
        d = -d;
        q1 = -q1;
    }
    let angle = d.acos();
    if angle.abs() < 4.0 * f64::EPSILON {
        return q0;
    }
    let isin = 1.0 / angle.sin();
    q0 * (((1.0 - f) * angle).sin() * isin) + q1 * ((f * angle).sin() * isin)
}

/// The rotation angle in [0, π] of a unit quaternion (as scipy's `as_rotvec` norm).
#[inline]
pub fn rotation_angle(q: DQuat) -> f64 {
    2.0 * q.xyz().length().atan2(q.w.abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_poses_rejects_bad_input() {
        let p = vec![DVec3::ZERO; 2];
        let q = vec![DQuat::IDENTITY; 2];
        let ns = TimeUnit::Nanoseconds;
        assert!(Trajectory::from_poses(vec![1, 2], p.clone(), q.clone(), ns).is_ok());
        assert!(Trajectory::from_poses(vec![2, 2], p.clone(), q.clone(), ns).is_err());
        assert!(Trajectory::from_poses(vec![3, 2], p.clone(), q.clone(), ns).is_err());
        assert!(Trajectory::from_poses(vec![1], p.clone(), q.clone(), ns).is_err());
        let bad_q = vec![DQuat::IDENTITY, DQuat::from_xyzw(0.0, 0.0, 0.0, 1.1)];
        assert!(Trajectory::from_poses(vec![1, 2], p.clone(), bad_q, ns).is_err());
        let nan_p = vec![DVec3::ZERO, DVec3::new(f64::NAN, 0.0, 0.0)];
        assert!(Trajectory::from_poses(vec![1, 2], nan_p, q, ns).is_err());
    }

    fn line(n: usize) -> Trajectory {
        Trajectory {
            stamps: (0..n as i64).map(|i| i * 1_000_000_000).collect(),
            positions: (0..n).map(|i| DVec3::new(i as f64, 0.0, 0.0)).collect(),
            orientations: (0..n)
                .map(|i| DQuat::from_rotation_z(i as f64 * 0.1))
                .collect(),
            time_unit: TimeUnit::Seconds,
        }
    }

    #[test]
    fn downsample_takes_numpy_linspace_indices() {
        let mut t = line(10);
        t.downsample(4).unwrap();
        // linspace(0, 9, 4) = 0, 3, 6, 9
        assert_eq!(
            t.positions.iter().map(|p| p.x).collect::<Vec<_>>(),
            [0.0, 3.0, 6.0, 9.0]
        );
        let mut t = line(10);
        t.downsample(7).unwrap();
        // 0, 1.5, 3, 4.5, 6, 7.5, 9 truncated
        assert_eq!(
            t.positions.iter().map(|p| p.x as i32).collect::<Vec<_>>(),
            [0, 1, 3, 4, 6, 7, 9]
        );
        let mut t = line(3);
        t.downsample(5).unwrap();
        assert_eq!(t.len(), 3);
        assert!(t.downsample(0).is_err());
    }

    #[test]
    fn motion_filter_time_range_and_merge() {
        let mut t = line(10);
        t.motion_filter(2.5, 90.0).unwrap();
        assert_eq!(
            t.positions.iter().map(|p| p.x).collect::<Vec<_>>(),
            [0.0, 3.0, 6.0, 9.0]
        );
        let mut t = line(10);
        // 0.1 rad (5.73 deg) per pose: 20 deg are reached every fourth pose.
        t.motion_filter(100.0, 20.0).unwrap();
        assert_eq!(
            t.positions.iter().map(|p| p.x).collect::<Vec<_>>(),
            [0.0, 4.0, 8.0]
        );
        let mut t = line(10);
        t.reduce_to_time_range(Some(2.0), Some(4.5)).unwrap();
        assert_eq!(t.stamps, [2_000_000_000, 3_000_000_000, 4_000_000_000]);
        assert!(line(3).reduce_to_time_range(Some(5.0), Some(4.0)).is_err());
        let mut a = line(3);
        a.stamps = vec![0, 20, 40];
        let mut b = line(2);
        b.stamps = vec![10, 30];
        assert_eq!(Trajectory::merge(&[a, b]).stamps, [0, 10, 20, 30, 40]);
    }

    #[test]
    fn project_and_interpolate() {
        let mut t = line(3);
        t.positions[1].z = 5.0;
        // Static x, then z: R = Rz(0.2)·Rx(0.3) keeps 0.2 about the normal.
        t.orientations[1] = DQuat::from_rotation_z(0.2) * DQuat::from_rotation_x(0.3);
        t.project(Plane::Xy);
        assert_eq!(t.positions[1].z, 0.0);
        let (axis, angle) = t.orientations[1].to_axis_angle();
        assert!(
            axis.abs_diff_eq(DVec3::Z, 1e-12) && (angle - 0.2).abs() < 1e-12,
            "{axis} {angle}"
        );
        let t = line(3);
        let i = t
            .interpolate(&[-1, 500_000_000, 1_250_000_000, 9_000_000_000])
            .unwrap();
        assert_eq!(
            i.positions.iter().map(|p| p.x).collect::<Vec<_>>(),
            [0.0, 0.5, 1.25, 2.0]
        );
        assert!(i.orientations[1].angle_between(DQuat::from_rotation_z(0.05)) < 1e-12);
        assert!(line(1).interpolate(&[0]).is_err());
        // Euler angles of a known rotation: static x, then y, then z.
        let m =
            DMat3::from_rotation_z(0.3) * DMat3::from_rotation_y(0.2) * DMat3::from_rotation_x(0.1);
        let e = euler_sxyz(m);
        assert!(
            (e[0] - 0.1).abs() < 1e-12 && (e[1] - 0.2).abs() < 1e-12 && (e[2] - 0.3).abs() < 1e-12
        );
    }

    #[test]
    fn seconds_as_python_reads_them() {
        // Python: float("1311868226.310950") == 1311868226.31095 (nearest float); the
        // naive ns as f64 / 1e9 is one ulp off for this stamp.
        let ns = 1_311_868_226_310_950_000;
        let want: f64 = "1311868226.310950".parse().unwrap();
        assert_eq!(TimeUnit::Seconds.seconds(ns), want);
        assert_ne!(ns as f64 / 1e9, want);
        // evo's EuRoC reader: float(ns) / 1e9, kept as it rounds.
        assert_eq!(TimeUnit::Nanoseconds.seconds(ns), ns as f64 / 1e9);
        assert_eq!(TimeUnit::Seconds.seconds(-1_500_000_000), -1.5);
        assert_eq!(TimeUnit::Seconds.seconds(i64::MIN), i64::MIN as f64 / 1e9);
        for ns in [1 << 53, (1 << 53) + 1, i64::MAX, -i64::MAX] {
            let text = TimeUnit::Seconds.format_stamp(ns);
            assert_eq!(
                TimeUnit::Seconds.seconds(ns),
                text.parse::<f64>().unwrap(),
                "{ns}"
            );
        }
    }

    proptest::proptest! {
        /// Seconds read with up to 9 decimals come back as the float Rust (and Python) parse
        /// from the same decimal, over the whole range of i64 nanoseconds.
        #[test]
        fn seconds_equal_the_parsed_decimal(ns in proptest::num::i64::ANY) {
            let text = TimeUnit::Seconds.format_stamp(ns);
            proptest::prop_assert_eq!(TimeUnit::Seconds.seconds(ns), text.parse::<f64>().unwrap());
        }
    }

    #[test]
    fn formats_stamps_in_unit() {
        assert_eq!(TimeUnit::Seconds.format_stamp(1_500_000_001), "1.500000001");
        assert_eq!(TimeUnit::Seconds.format_stamp(-5), "-0.000000005");
        assert_eq!(TimeUnit::Nanoseconds.format_stamp(42), "42");
    }

    /// ROS stamps are evo's `sec + nanosec * 1e-9`, which is not always the float nearest
    /// the decimal (Python: 63 + 817077201 * 1e-9 == 63.817077201000004).
    #[test]
    fn ros_stamps_are_evos_sum() {
        let ns = 63_817_077_201;
        assert_eq!(TimeUnit::RosStamp.seconds(ns), 63.817_077_201_000_004);
        assert_eq!(TimeUnit::Seconds.seconds(ns), 63.817_077_201);
        assert_eq!(TimeUnit::RosStamp.format_stamp(ns), "63.817077201");
        assert!(TimeUnit::RosStamp.is_seconds() && !TimeUnit::Nanoseconds.is_seconds());
    }
}
