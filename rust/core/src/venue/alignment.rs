//! A session's alignment to the venue frame: a translation and a heading, estimated
//! robustly from the `full` observations of the anchor.

use glam::{DQuat, DVec3};

use super::{AnchorObservation, Tracking};

/// The heading of an image rotation: the angle `α` with `R_y(α)·(1, 0, 0)` along the image's
/// +X levelled onto the horizontal plane (`atan2(−x_z, x_x)`); `None` when the image's +X is
/// (within 1e-6) vertical, so that it has no heading.
pub fn heading_of(rotation: DQuat) -> Option<f64> {
    let x = rotation * DVec3::X;
    let level = (x.x * x.x + x.z * x.z).sqrt();
    (level > 1e-6).then(|| (-x.z).atan2(x.x))
}

/// `a` wrapped into (−π, π].
pub(crate) fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let w = a - t * (a / t).round();
    if w <= -std::f64::consts::PI { w + t } else { w }
}

/// The median of `v` (reordered in place, O(n) by selection; the mean of the middle two for an
/// even count). `v` must not be empty.
pub(crate) fn median(v: &mut [f64]) -> f64 {
    let n = v.len();
    let (below, &mut upper, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n.is_multiple_of(2) {
        let lower = below
            .iter()
            .copied()
            .max_by(f64::total_cmp)
            .unwrap_or(upper);
        0.5 * (lower + upper)
    } else {
        upper
    }
}

/// A session's place in the venue frame (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Alignment {
    /// Where the anchor's centre (the venue origin) is in the session's world frame.
    pub translation: DVec3,
    /// The turn about +Y from the venue frame to the world frame (radians, in (−π, π]).
    pub heading_rad: f64,
    /// `full` observations used (inliers).
    pub observations: usize,
    /// `full` observations rejected as outliers.
    pub rejected: usize,
    /// RMS distance of the used observations from [`Alignment::translation`] (m).
    pub position_spread_m: f64,
    /// RMS heading deviation of the used observations (degrees).
    pub heading_spread_deg: f64,
}

impl Alignment {
    /// The rotation venue → world, `R_y(heading)`.
    pub fn rotation(&self) -> DQuat {
        DQuat::from_rotation_y(self.heading_rad)
    }

    /// A point in the venue frame, in the session's world frame.
    pub fn to_world(&self, venue: DVec3) -> DVec3 {
        self.rotation() * venue + self.translation
    }

    /// A point in the session's world frame, in the venue frame.
    pub fn to_venue(&self, world: DVec3) -> DVec3 {
        self.rotation().inverse() * (world - self.translation)
    }
}

/// Why a session could not be put into the venue frame.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("not aligned: {reason}")]
pub struct NotAligned {
    /// What is missing, in words.
    pub reason: String,
}

/// A `full` observation farther than this many robust standard deviations (1.4826 × the
/// median deviation) from the median position or heading is an outlier.
pub const OUTLIER_SIGMAS: f64 = 3.0;
/// Deviations up to this are never outliers, however tight the others are (m).
pub const OUTLIER_FLOOR_M: f64 = 0.02;
/// Heading deviations up to this are never outliers (degrees).
pub const OUTLIER_FLOOR_DEG: f64 = 2.0;

/// The alignment of a session from its observations of `anchor`: `full` observations only;
/// a component-wise median position and a median heading (on the circle: the median of the
/// deviations from the circular mean); observations whose distance from the median position
/// or whose heading deviation exceeds [`OUTLIER_SIGMAS`] robust standard deviations (at least
/// [`OUTLIER_FLOOR_M`] / [`OUTLIER_FLOOR_DEG`]) rejected; the medians of the rest, and their
/// RMS deviations as the spread. Observations whose image +X is vertical have no heading
/// and are not used.
pub fn align(observations: &[AnchorObservation], anchor: &str) -> Result<Alignment, NotAligned> {
    let of_anchor: Vec<&AnchorObservation> =
        observations.iter().filter(|o| o.anchor == anchor).collect();
    if of_anchor.is_empty() {
        return Err(NotAligned {
            reason: format!("the anchor `{anchor}` was never observed"),
        });
    }
    let full: Vec<(DVec3, f64)> = of_anchor
        .iter()
        .filter(|o| o.tracking == Tracking::Full)
        .filter_map(|o| Some((o.pose.position, heading_of(o.pose.rotation)?)))
        .collect();
    if full.is_empty() {
        let n_full = of_anchor
            .iter()
            .filter(|o| o.tracking == Tracking::Full)
            .count();
        return Err(NotAligned {
            reason: if n_full == 0 {
                format!(
                    "the anchor `{anchor}` was observed {} times but never with full tracking",
                    of_anchor.len()
                )
            } else {
                format!(
                    "none of the {n_full} full observations of the anchor `{anchor}` has a heading (its +X was vertical)"
                )
            },
        });
    }
    let (p0, h0) = centre(&full);
    let mut r: Vec<f64> = full.iter().map(|(p, _)| p.distance(p0)).collect();
    let mut a: Vec<f64> = full.iter().map(|(_, h)| wrap(h - h0).abs()).collect();
    let pos_limit = (OUTLIER_SIGMAS * 1.4826 * median(&mut r)).max(OUTLIER_FLOOR_M);
    let ang_limit = (OUTLIER_SIGMAS * 1.4826 * median(&mut a)).max(OUTLIER_FLOOR_DEG.to_radians());
    let inliers: Vec<(DVec3, f64)> = full
        .iter()
        .copied()
        .filter(|(p, h)| p.distance(p0) <= pos_limit && wrap(h - h0).abs() <= ang_limit)
        .collect();
    // The medians are inliers by construction unless the sample is split evenly; then keep
    // every observation.
    let used = if inliers.is_empty() {
        full.clone()
    } else {
        inliers
    };
    let (translation, heading_rad) = centre(&used);
    let n = used.len() as f64;
    let position_spread_m = (used
        .iter()
        .map(|(p, _)| p.distance_squared(translation))
        .sum::<f64>()
        / n)
        .sqrt();
    let heading_spread_deg = (used
        .iter()
        .map(|(_, h)| wrap(h - heading_rad).powi(2))
        .sum::<f64>()
        / n)
        .sqrt()
        .to_degrees();
    Ok(Alignment {
        translation,
        heading_rad,
        observations: used.len(),
        rejected: full.len() - used.len(),
        position_spread_m,
        heading_spread_deg,
    })
}

/// Component-wise median position and circular median heading.
fn centre(obs: &[(DVec3, f64)]) -> (DVec3, f64) {
    let axis =
        |f: fn(&DVec3) -> f64| median(&mut obs.iter().map(|(p, _)| f(p)).collect::<Vec<_>>());
    let p = DVec3::new(axis(|p| p.x), axis(|p| p.y), axis(|p| p.z));
    let (s, c) = obs
        .iter()
        .fold((0.0, 0.0), |(s, c), (_, h)| (s + h.sin(), c + h.cos()));
    let reference = if s == 0.0 && c == 0.0 {
        obs[0].1
    } else {
        s.atan2(c)
    };
    let mut dev: Vec<f64> = obs.iter().map(|(_, h)| wrap(h - reference)).collect();
    (p, wrap(reference + median(&mut dev)))
}
