//! Venues: the printed image anchor a place shares, its observations, a session's alignment
//! to the venue frame, and the venue map (`GET /v1/venues/{id}/map.json`).
//!
//! **The venue frame**: origin at the anchor's centre, +Y world up (both conventions' world
//! frames are gravity-aligned), +X the image's +X levelled onto the horizontal plane, the
//! third axis completing the session convention's handedness. A session's world frame and
//! the venue frame therefore differ by a translation and a heading (a turn about +Y):
//! `p_world = R_y(heading) · p_venue + translation`, where `R_y(α)` is the matrix
//! `[[cos α, 0, sin α], [0, 1, 0], [−sin α, 0, cos α]]` — the same numbers in either
//! convention, so the third axis is `+X × +Y`'s mirror in Unity's left-handed world and the
//! right-handed one in ARCore's (a physical point has venue coordinates `(x, y, z)` in a
//! Unity session and `(x, y, −z)` in an ARCore session, as its world coordinates do).
//!
//! [`align`] is the one estimate of that alignment, used by the phone (`Session`) and the
//! backend: from the `full` observations only, a median position and a median heading,
//! observations far from them rejected as outliers, then the medians of the rest, with
//! their spread (RMS position deviation in metres, RMS heading deviation in degrees).

use std::fmt::Write as _;

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::{Convention, Error, ErrorClass, Pose};

/// The longest anchor id, in bytes.
pub const MAX_ANCHOR_ID_BYTES: usize = 64;

/// The header of a session folder's `anchors.csv`.
pub const ANCHORS_HEADER: &str = "t_ns,anchor,px,py,pz,qx,qy,qz,qw,tracking";

/// How well the platform tracked the anchor image in one observation (numbers as in the
/// C ABI).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[repr(i32)]
pub enum Tracking {
    /// Not tracked (the pose is the last known one).
    None = 0,
    /// Tracked with limited quality (AR Foundation `Limited`, ARCore `LAST_KNOWN_POSE`).
    Limited = 1,
    /// Fully tracked: the only observations alignment uses.
    Full = 2,
}

impl Tracking {
    /// `"none"`, `"limited"` or `"full"`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Limited => "limited",
            Self::Full => "full",
        }
    }

    /// The inverse of [`Tracking::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "none" => Some(Self::None),
            "limited" => Some(Self::Limited),
            "full" => Some(Self::Full),
            _ => None,
        }
    }

    /// 0 none, 1 limited, 2 full; another number is an [`Error::InvalidArgument`] naming
    /// `tracking`.
    pub fn from_code(code: i32) -> Result<Self, Error> {
        match code {
            0 => Ok(Self::None),
            1 => Ok(Self::Limited),
            2 => Ok(Self::Full),
            _ => Err(Error::arg(
                "tracking",
                format!("{code} is not a tracking state (0 none, 1 limited, 2 full)"),
            )),
        }
    }
}

/// One observation of an anchor image: the pose the platform reports for it
/// (world-from-image, in the session's convention and world frame; image +X to its right).
#[derive(Debug, Clone, PartialEq)]
pub struct AnchorObservation {
    /// When it was observed (ns, the session's clock).
    pub t_ns: i64,
    /// The anchor's id (1…64 bytes, no comma, quote or control character).
    pub anchor: String,
    /// World-from-image pose.
    pub pose: Pose,
    /// Tracking state.
    pub tracking: Tracking,
}

/// Checks an anchor id: 1…[`MAX_ANCHOR_ID_BYTES`] bytes, and (so that `anchors.csv` holds it
/// as one cell) no comma, double quote or control character. The error names `anchor_id`.
pub fn check_anchor_id(id: &str) -> Result<(), Error> {
    if id.is_empty() {
        return Err(Error::arg("anchor_id", "is empty"));
    }
    if id.len() > MAX_ANCHOR_ID_BYTES {
        return Err(Error::arg(
            "anchor_id",
            format!(
                "is {} bytes long; at most {MAX_ANCHOR_ID_BYTES} are allowed",
                id.len()
            ),
        ));
    }
    if let Some(c) = id
        .chars()
        .find(|c| *c == ',' || *c == '"' || c.is_control())
    {
        return Err(Error::arg(
            "anchor_id",
            format!(
                "`{}` contains {c:?}, which anchors.csv cannot hold",
                id.escape_debug()
            ),
        ));
    }
    Ok(())
}

/// The observations as `anchors.csv` text ([`ANCHORS_HEADER`], one row per observation;
/// numbers in Rust's shortest round-trip form).
pub fn anchors_csv(observations: &[AnchorObservation]) -> String {
    let mut csv = String::from(ANCHORS_HEADER);
    csv.push('\n');
    for o in observations {
        let (p, q) = (o.pose.position, o.pose.rotation);
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{}",
            o.t_ns,
            o.anchor,
            p.x,
            p.y,
            p.z,
            q.x,
            q.y,
            q.z,
            q.w,
            o.tracking.name()
        );
    }
    csv
}

/// Parses `anchors.csv` text; errors name `source`, the line and the column.
pub fn parse_anchors_csv(text: &str, source: &str) -> Result<Vec<AnchorObservation>, Error> {
    let columns: Vec<&str> = ANCHORS_HEADER.split(',').collect();
    let mut out = Vec::new();
    for (line_no, cells) in crate::csv_rows::rows(text, source, &[ANCHORS_HEADER])? {
        let number = |j: usize| -> Result<f64, Error> {
            match cells[j].parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(Error::parse(
                    source,
                    line_no,
                    columns[j],
                    format!("`{}` is not a finite number", cells[j]),
                )),
            }
        };
        let t_ns: i64 = cells[0].parse().map_err(|_| {
            Error::parse(
                source,
                line_no,
                columns[0],
                format!("`{}` is not integer nanoseconds", cells[0]),
            )
        })?;
        check_anchor_id(cells[1])
            .map_err(|e| Error::parse(source, line_no, columns[1], e.to_string()))?;
        let pose = Pose::new(
            DVec3::new(number(2)?, number(3)?, number(4)?),
            DQuat::from_xyzw(number(5)?, number(6)?, number(7)?, number(8)?),
        )
        .validated("pose")
        .map_err(|e| Error::parse(source, line_no, "qx", e.to_string()))?;
        let tracking = Tracking::from_name(cells[9]).ok_or_else(|| {
            Error::parse(
                source,
                line_no,
                columns[9],
                format!("`{}` is not none, limited or full", cells[9]),
            )
        })?;
        out.push(AnchorObservation {
            t_ns,
            anchor: cells[1].to_owned(),
            pose,
            tracking,
        });
    }
    Ok(out)
}

/// The heading of an image rotation: the angle `α` with `R_y(α)·(1, 0, 0)` along the image's
/// +X levelled onto the horizontal plane (`atan2(−x_z, x_x)`); `None` when the image's +X is
/// (within 1e-6) vertical, so that it has no heading.
pub fn heading_of(rotation: DQuat) -> Option<f64> {
    let x = rotation * DVec3::X;
    let level = (x.x * x.x + x.z * x.z).sqrt();
    (level > 1e-6).then(|| (-x.z).atan2(x.x))
}

/// `a` wrapped into (−π, π].
fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let w = a - t * (a / t).round();
    if w <= -std::f64::consts::PI { w + t } else { w }
}

/// The median of `v` (reordered in place, O(n) by selection; the mean of the middle two for an
/// even count). `v` must not be empty.
fn median(v: &mut [f64]) -> f64 {
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

/// A map cell's kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[repr(i32)]
pub enum CellKind {
    /// Where cameras were: the midpoint positions of sub-trajectories.
    Path = 0,
    /// What cameras looked at: the surface points of valid depth samples.
    Surface = 1,
}

/// One cell of a venue map, in the venue frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VenueCell {
    /// The cell's centre `[x, y, z]` in the venue frame (m).
    pub center: [f64; 3],
    /// `path` or `surface`.
    pub kind: CellKind,
    /// Sessions with a sub-trajectory in it.
    pub sessions: u32,
    /// Sub-trajectories in it.
    pub subtrajectories: u32,
    /// The 30 % trimmed mean of their errors (m).
    pub error_m: f64,
    /// The class of `error_m` by the default thresholds.
    pub class: ErrorClass,
    /// Sub-trajectories by the camera's heading in 8 sectors of 45° (sector 0 centred on
    /// venue +X, counter-clockwise seen from above).
    pub directions: [u32; 8],
}

/// One session of a venue map: aligned (with its spread) or not (with the reason).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum VenueSession {
    /// In the map. (Listed first: an untagged enum tries its variants in order.)
    Aligned {
        /// The server session id.
        id: String,
        /// Always true here.
        aligned: bool,
        /// `full` observations used.
        observations: u32,
        /// RMS position deviation (m).
        position_spread_m: f64,
        /// RMS heading deviation (degrees).
        heading_spread_deg: f64,
        /// Sub-trajectories it brought into the cells.
        subtrajectories: u32,
    },
    /// Out of the map.
    NotAligned {
        /// The server session id.
        id: String,
        /// Always false here.
        aligned: bool,
        /// Why (e.g. the anchor was never fully tracked).
        reason: String,
    },
}

/// The backend's `GET /v1/venues/{id}/map.json`: coordinates in the venue frame, errors in
/// metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VenueMap {
    /// The venue id (`v` and 16 hex digits).
    pub id: String,
    /// Its name.
    pub name: String,
    /// The anchor id its sessions observe.
    pub anchor: String,
    /// Cell edge (m, 0.05…2).
    pub cell_m: f64,
    /// The convention its sessions share.
    pub convention: Convention,
    /// Always `"m"`.
    pub unit: String,
    /// Its sessions.
    pub sessions: Vec<VenueSession>,
    /// Its cells.
    pub cells: Vec<VenueCell>,
}

impl VenueMap {
    /// Parses and checks `map.json`: unknown keys, wrong types, a `unit` other than `"m"`, a
    /// `cell_m` outside 0.05…2, a non-finite centre or a negative error, or a session whose
    /// `aligned` does not fit its fields are [`Error::Parse`] naming the key (its JSON path)
    /// and the line.
    pub fn from_json(text: &str) -> Result<Self, Error> {
        const SRC: &str = "map.json";
        let de = &mut serde_json::Deserializer::from_str(text);
        let map: VenueMap = serde_path_to_error::deserialize(de).map_err(|e| {
            let line = e.inner().line();
            Error::parse(SRC, line, e.path().to_string(), e.into_inner().to_string())
        })?;
        let bad =
            |field: String, message: String| Err::<Self, _>(Error::parse(SRC, 0, field, message));
        if map.unit != "m" {
            return bad("unit".into(), format!("`{}` is not \"m\"", map.unit));
        }
        if !(0.05..=2.0).contains(&map.cell_m) {
            return bad(
                "cell_m".into(),
                format!("{} is not within 0.05…2", map.cell_m),
            );
        }
        if let Err(e) = check_anchor_id(&map.anchor) {
            return bad("anchor".into(), e.to_string());
        }
        for (i, s) in map.sessions.iter().enumerate() {
            let (aligned, expected) = match s {
                VenueSession::Aligned { aligned, .. } => (*aligned, true),
                VenueSession::NotAligned { aligned, .. } => (*aligned, false),
            };
            if aligned != expected {
                return bad(
                    format!("sessions[{i}].aligned"),
                    format!("is {aligned} but the session has the fields of aligned={expected}"),
                );
            }
        }
        for (i, c) in map.cells.iter().enumerate() {
            if !c.center.iter().all(|v| v.is_finite()) {
                return bad(format!("cells[{i}].center"), "is not finite".into());
            }
            if !(c.error_m.is_finite() && c.error_m >= 0.0) {
                return bad(
                    format!("cells[{i}].error_m"),
                    format!("{} is not a finite number ≥ 0", c.error_m),
                );
            }
        }
        Ok(map)
    }

    /// The map as JSON (what the backend serves).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }
}

/// A venue cell in a session's world frame ([`crate::Session::venue_cells`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldCell {
    /// Its centre in the session's world frame.
    pub position: DVec3,
    /// `path` or `surface`.
    pub kind: CellKind,
    /// Its class.
    pub class: ErrorClass,
    /// Sessions with a sub-trajectory in it.
    pub sessions: u32,
    /// Its error (m).
    pub error_m: f64,
}

/// The map's cells in the world frame of a session with `alignment`, in the map's order.
pub fn world_cells(map: &VenueMap, alignment: &Alignment) -> Vec<WorldCell> {
    map.cells
        .iter()
        .map(|c| WorldCell {
            position: alignment.to_world(DVec3::from_array(c.center)),
            kind: c.kind,
            class: c.class,
            sessions: c.sessions,
            error_m: c.error_m,
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::*;

    fn obs(anchor: &str, pose: Pose, tracking: Tracking) -> AnchorObservation {
        AnchorObservation {
            t_ns: 0,
            anchor: anchor.to_owned(),
            pose,
            tracking,
        }
    }

    /// An image on a wall facing the venue's +Z (image +Y its normal, as AR Foundation and
    /// ARCore report tracked images), turned about +Y by `heading`, at `t`.
    fn wall_image(t: DVec3, heading: f64, tilt: f64) -> Pose {
        Pose::new(
            t,
            DQuat::from_rotation_y(heading) * DQuat::from_rotation_x(tilt),
        )
    }

    #[test]
    fn one_exact_observation_is_the_alignment() {
        let t = DVec3::new(2.0, 1.4, -3.0);
        let heading = 0.9;
        let a = align(
            &[obs(
                "lobby",
                wall_image(t, heading, FRAC_PI_2),
                Tracking::Full,
            )],
            "lobby",
        )
        .unwrap();
        assert!((a.translation - t).length() < 1e-12);
        assert!((a.heading_rad - heading).abs() < 1e-12);
        assert_eq!((a.observations, a.rejected), (1, 0));
        assert_eq!((a.position_spread_m, a.heading_spread_deg), (0.0, 0.0));
        // The origin is the anchor; venue +X is the image's +X levelled; +Y is up.
        assert!(a.to_venue(t).length() < 1e-12);
        let x = DQuat::from_rotation_y(heading) * DVec3::X;
        assert!((a.to_venue(t + x) - DVec3::X).length() < 1e-12);
        assert!((a.to_venue(t + DVec3::Y) - DVec3::Y).length() < 1e-12);
        let p = DVec3::new(0.3, -1.0, 7.0);
        assert!((a.to_world(a.to_venue(p)) - p).length() < 1e-12);
    }

    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn median_by_selection() {
        assert_eq!(median(&mut [3.0]), 3.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut [5.0, -1.0, 9.0, 0.0, 2.0]), 2.0);
        assert_eq!(median(&mut [1.0, 1.0, 7.0, 1.0]), 1.0);
    }

    #[test]
    fn headings_of_a_levelled_image_x() {
        assert_eq!(heading_of(DQuat::IDENTITY), Some(0.0));
        // +X turned to −Z: +90° about +Y.
        let h = heading_of(DQuat::from_rotation_y(FRAC_PI_2)).unwrap();
        assert!((h - FRAC_PI_2).abs() < 1e-12);
        // A tilt about the image's own +X changes nothing; a roll to vertical has no heading.
        let h = heading_of(DQuat::from_rotation_y(-2.0) * DQuat::from_rotation_x(1.1)).unwrap();
        assert!((h + 2.0).abs() < 1e-12);
        assert_eq!(heading_of(DQuat::from_rotation_z(FRAC_PI_2)), None);
    }

    #[test]
    fn headings_across_the_seam_have_a_median_near_pi() {
        let t = DVec3::ZERO;
        let list: Vec<AnchorObservation> = [PI - 0.01, -PI + 0.01, PI - 0.02, -PI + 0.03, PI]
            .iter()
            .map(|h| obs("a", wall_image(t, *h, 0.0), Tracking::Full))
            .collect();
        let a = align(&list, "a").unwrap();
        assert!(wrap(a.heading_rad - PI).abs() < 0.011, "{}", a.heading_rad);
    }

    #[test]
    fn only_full_observations_count_and_outliers_are_rejected() {
        let t = DVec3::new(1.0, 1.0, 1.0);
        let mut list: Vec<AnchorObservation> = (0..9)
            .map(|i| {
                let e = 0.001 * (i as f64 - 4.0);
                obs(
                    "a",
                    wall_image(t + DVec3::splat(e), 0.5 + e, 0.0),
                    Tracking::Full,
                )
            })
            .collect();
        // Far off but not full: ignored; one full outlier in position, one in heading.
        list.push(obs(
            "a",
            wall_image(DVec3::splat(9.0), 2.0, 0.0),
            Tracking::Limited,
        ));
        list.push(obs(
            "a",
            wall_image(DVec3::splat(5.0), 0.5, 0.0),
            Tracking::Full,
        ));
        list.push(obs("a", wall_image(t, -2.5, 0.0), Tracking::Full));
        list.push(obs(
            "other",
            wall_image(DVec3::splat(-7.0), 1.0, 0.0),
            Tracking::Full,
        ));
        let a = align(&list, "a").unwrap();
        assert_eq!((a.observations, a.rejected), (9, 2));
        assert!((a.translation - t).length() < 1e-12);
        assert!((a.heading_rad - 0.5).abs() < 1e-12);
        // RMS of 0.001·(i−4)·√3 over i = 0…8: 0.001·√(60/9)·√3.
        let expected = 0.001 * (60.0f64 / 9.0).sqrt() * 3f64.sqrt();
        assert!((a.position_spread_m - expected).abs() < 1e-12);
        let expected_deg = (0.001 * (60.0f64 / 9.0).sqrt()).to_degrees();
        assert!((a.heading_spread_deg - expected_deg).abs() < 1e-9);
    }

    #[test]
    fn without_a_full_observation_a_session_is_not_aligned_and_says_why() {
        let p = wall_image(DVec3::ZERO, 0.0, 0.0);
        let e = align(&[], "a").unwrap_err();
        assert!(e.reason.contains("never observed"), "{e}");
        let e = align(
            &[obs("a", p, Tracking::Limited), obs("a", p, Tracking::None)],
            "a",
        )
        .unwrap_err();
        assert!(
            e.reason.contains("observed 2 times but never with full"),
            "{e}"
        );
        let vertical = Pose::new(DVec3::ZERO, DQuat::from_rotation_z(FRAC_PI_2));
        let e = align(&[obs("a", vertical, Tracking::Full)], "a").unwrap_err();
        assert!(e.reason.contains("heading"), "{e}");
    }

    /// The same physical scene recorded in Unity's and in ARCore's convention: the venue
    /// coordinates of a point differ by the reflection z → −z, as the world coordinates do
    /// (the venue frame's third axis follows each convention's handedness).
    #[test]
    fn the_third_axis_follows_the_conventions_handedness() {
        let image = wall_image(DVec3::new(1.0, 1.2, 4.0), 0.6, FRAC_PI_2);
        let point = DVec3::new(-2.0, 0.5, 3.0);
        let unity = align(&[obs("a", image, Tracking::Full)], "a").unwrap();
        let arcore_image = Convention::Unity.convert_pose(image, Convention::Arcore);
        let arcore = align(&[obs("a", arcore_image, Tracking::Full)], "a").unwrap();
        let in_arcore = Convention::Unity.convert_vector(point, Convention::Arcore);
        let (u, a) = (unity.to_venue(point), arcore.to_venue(in_arcore));
        assert!((a - DVec3::new(u.x, u.y, -u.z)).length() < 1e-12, "{u} {a}");
        // In each, +X is the image's right, +Y up, and the frame is a proper rotation of
        // the world's (so it has the world's handedness).
        let right = image.rotation * DVec3::X;
        assert!((unity.to_venue(image.position + right) - DVec3::X).length() < 1e-12);
        assert!((glam::DMat3::from_quat(unity.rotation()).determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn anchors_csv_round_trips_and_names_line_and_column() {
        let list = vec![
            obs(
                "lobby-a",
                wall_image(DVec3::new(0.1, 0.2, 0.3), 0.4, 0.5),
                Tracking::Full,
            ),
            AnchorObservation {
                t_ns: -5,
                ..obs("é", Pose::IDENTITY, Tracking::None)
            },
        ];
        let csv = anchors_csv(&list);
        assert!(csv.starts_with(&format!("{ANCHORS_HEADER}\n0,lobby-a,0.1,")));
        assert_eq!(parse_anchors_csv(&csv, "anchors.csv").unwrap(), list);
        let field = |text: &str| match parse_anchors_csv(text, "anchors.csv") {
            Err(Error::Parse { line, field, .. }) => (line, field),
            other => panic!("{other:?}"),
        };
        let h = ANCHORS_HEADER;
        assert_eq!(field("t,anchor\n"), (1, "header".into()));
        assert_eq!(
            field(&format!(
                "{h}\n1,a,0,0,0,0,0,0,1,full\nx,a,0,0,0,0,0,0,1,full\n"
            )),
            (3, "t_ns".into())
        );
        assert_eq!(
            field(&format!("{h}\n1,a,0,nan,0,0,0,0,1,full\n")),
            (2, "py".into())
        );
        assert_eq!(
            field(&format!("{h}\n1,a,0,0,0,0,0,0,1,good\n")),
            (2, "tracking".into())
        );
        assert_eq!(
            field(&format!("{h}\n1,,0,0,0,0,0,0,1,full\n")),
            (2, "anchor".into())
        );
        assert_eq!(
            field(&format!("{h}\n1,a,0,0,0,0,0,0,1\n")),
            (2, "row".into())
        );
        assert_eq!(
            field(&format!("{h}\n1,a,0,0,0,0,0,0,0,full\n")),
            (2, "qx".into())
        );
    }

    #[test]
    fn anchor_ids_are_checked() {
        assert!(check_anchor_id("lobby").is_ok());
        assert!(check_anchor_id(&"x".repeat(64)).is_ok());
        for bad in ["", &"x".repeat(65), "a,b", "a\nb", "a\"b"] {
            let e = check_anchor_id(bad).unwrap_err();
            assert!(
                matches!(
                    e,
                    Error::InvalidArgument {
                        name: "anchor_id",
                        ..
                    }
                ),
                "{e}"
            );
        }
        assert!(matches!(
            Tracking::from_code(3),
            Err(Error::InvalidArgument {
                name: "tracking",
                ..
            })
        ));
        assert_eq!(Tracking::from_code(2).unwrap(), Tracking::Full);
    }

    pub(crate) const MAP: &str = r#"{"id":"v0123456789abcdef","name":"Lobby","anchor":"lobby-a",
        "cell_m":0.25,"convention":"unity","unit":"m",
        "sessions":[{"id":"s1","aligned":true,"observations":40,"position_spread_m":0.01,
          "heading_spread_deg":0.4,"subtrajectories":12},
          {"id":"s2","aligned":false,"reason":"the anchor was never fully tracked"}],
        "cells":[{"center":[1.0,0.0,2.0],"kind":"path","sessions":1,"subtrajectories":3,
          "error_m":0.02,"class":"low","directions":[1,0,0,2,0,0,0,0]},
          {"center":[0.5,1.5,-1.0],"kind":"surface","sessions":2,"subtrajectories":4,
          "error_m":0.14,"class":"high","directions":[0,0,4,0,0,0,0,0]}]}"#;

    #[test]
    fn the_map_parses_round_trips_and_names_bad_keys() {
        let map = VenueMap::from_json(MAP).unwrap();
        assert_eq!(map.cells[1].kind, CellKind::Surface);
        assert_eq!(map.cells[1].class, ErrorClass::High);
        assert!(
            matches!(&map.sessions[1], VenueSession::NotAligned { reason, .. } if reason.contains("never"))
        );
        assert_eq!(VenueMap::from_json(&map.to_json()).unwrap(), map);
        let field = |text: String| match VenueMap::from_json(&text) {
            Err(Error::Parse { field, .. }) => field,
            other => panic!("{other:?}"),
        };
        assert_eq!(
            field(MAP.replace("\"surface\"", "\"wall\"")),
            "cells[1].kind"
        );
        assert_eq!(
            field(MAP.replace("\"unit\":\"m\"", "\"unit\":\"deg\"")),
            "unit"
        );
        assert_eq!(field(MAP.replace("0.25", "3")), "cell_m");
        assert_eq!(
            field(MAP.replace("[0,0,4,0,0,0,0,0]", "[0,0,4]")),
            "cells[1].directions"
        );
        assert_eq!(
            field(MAP.replace("\"class\":\"high\"", "\"class\":\"bad\"")),
            "cells[1].class"
        );
        assert_eq!(
            field(MAP.replace("\"aligned\":true", "\"aligned\":false")),
            "sessions[0].aligned"
        );
    }

    #[test]
    fn world_cells_follow_the_alignment() {
        let map = VenueMap::from_json(MAP).unwrap();
        let a = align(
            &[obs(
                "lobby-a",
                wall_image(DVec3::new(3.0, 0.0, 1.0), FRAC_PI_2, 0.0),
                Tracking::Full,
            )],
            "lobby-a",
        )
        .unwrap();
        let cells = world_cells(&map, &a);
        // R_y(90°)·(1, 0, 2) = (2, 0, −1).
        assert!((cells[0].position - DVec3::new(5.0, 0.0, 0.0)).length() < 1e-12);
        assert_eq!(
            (cells[1].kind, cells[1].class, cells[1].sessions),
            (CellKind::Surface, ErrorClass::High, 2)
        );
    }

    fn noise(seed: u64, i: usize, scale: f64) -> f64 {
        // A deterministic, roughly uniform value in [−scale, scale] from (seed, i).
        let mut x = seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        x ^= x >> 33;
        x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
        x ^= x >> 33;
        scale * (2.0 * (x as f64 / u64::MAX as f64) - 1.0)
    }

    proptest! {
        /// A known translation and heading, observed with noise (≤ 1 cm, ≤ 1°) and up to 30 %
        /// gross outliers, is recovered within the noise, in both conventions.
        #[test]
        fn a_known_alignment_is_recovered(t in prop::array::uniform3(-20.0..20.0f64),
            heading in -PI..PI, n in 5usize..60, outlier_share in 0.0..0.3f64,
            seed in any::<u64>(), arcore in any::<bool>()) {
            let t = DVec3::from_array(t);
            let outliers = (n as f64 * outlier_share) as usize;
            let mut list = Vec::new();
            for i in 0..n {
                let (p, h) = if i < outliers {
                    (t + DVec3::new(1.0 + noise(seed, 5 * i, 3.0).abs(), noise(seed, 5 * i + 1, 3.0), 0.5),
                        heading + 0.5 + noise(seed, 5 * i + 2, 2.0).abs())
                } else {
                    (t + DVec3::new(noise(seed, 5 * i, 0.01), noise(seed, 5 * i + 1, 0.01),
                        noise(seed, 5 * i + 3, 0.01)) / 3f64.sqrt(),
                        heading + noise(seed, 5 * i + 2, 1f64.to_radians()))
                };
                let tilt = noise(seed, 5 * i + 4, PI);
                list.push(obs("a", wall_image(p, h, tilt), Tracking::Full));
                list.push(obs("a", wall_image(p * 3.0, h + 1.0, tilt), Tracking::Limited));
            }
            let (list, t) = if arcore {
                let c = |o: AnchorObservation| AnchorObservation {
                    pose: Convention::Unity.convert_pose(o.pose, Convention::Arcore), ..o };
                (list.into_iter().map(c).collect::<Vec<_>>(),
                    Convention::Unity.convert_vector(t, Convention::Arcore))
            } else { (list, t) };
            let heading = if arcore { -heading } else { heading };
            let a = align(&list, "a").unwrap();
            prop_assert!((a.translation - t).length() < 0.01, "{} vs {}", a.translation, t);
            prop_assert!(wrap(a.heading_rad - heading).abs() < 1f64.to_radians());
            prop_assert!(a.position_spread_m < 0.01 && a.heading_spread_deg < 1.0);
            prop_assert!(a.rejected >= outliers);
            prop_assert_eq!(a.observations + a.rejected, n);
        }
    }
}
