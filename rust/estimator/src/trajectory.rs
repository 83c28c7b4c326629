//! The trajectory type: stamped world-from-camera poses.

use glam::{DQuat, DVec3};

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
}

impl TimeUnit {
    /// Formats a nanosecond stamp in this unit: an integer for ns, 9 decimals for seconds.
    pub fn format_stamp(self, t_ns: i64) -> String {
        match self {
            TimeUnit::Nanoseconds => t_ns.to_string(),
            TimeUnit::Seconds => {
                let sign = if t_ns < 0 { "-" } else { "" };
                let abs = t_ns.unsigned_abs();
                format!("{sign}{}.{:09}", abs / 1_000_000_000, abs % 1_000_000_000)
            }
        }
    }
}

/// Stamped poses (world-from-camera). Stamps are strictly increasing nanoseconds,
/// orientations unit quaternions; [`Trajectory::from_poses`] checks both.
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

    /// Total path length (sum of distances between consecutive positions), metres.
    pub fn path_length(&self) -> f64 {
        self.positions
            .windows(2)
            .map(|w| (w[1] - w[0]).length())
            .sum()
    }
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

    #[test]
    fn formats_stamps_in_unit() {
        assert_eq!(TimeUnit::Seconds.format_stamp(1_500_000_001), "1.500000001");
        assert_eq!(TimeUnit::Seconds.format_stamp(-5), "-0.000000005");
        assert_eq!(TimeUnit::Nanoseconds.format_stamp(42), "42");
    }
}
