//! A printed image anchor on a wall, and how a phone's image tracker sees it.

use glam::{DMat3, DQuat, DVec3};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use sitar_core::{Pose, Tracking};

use crate::{Error, Room, Surface, SurfaceKind};

/// The name of the anchor's surface in a room ([`Room::with_anchor`]).
pub const ANCHOR_SURFACE: &str = "printed anchor";

/// The printed anchor of the demo venue: its id, as the phone samples name it.
pub const DEMO_ANCHOR_ID: &str = "sitar-anchor-a4";

/// A printed image (A4 by default) fixed flat on a wall.
///
/// Its pose is room-from-image: +X the image's right, +Y its up, +Z out of the image towards
/// whoever looks at it (the wall's normal into the room). That is the pose an image tracker
/// reports; only its centre and levelled +X define the venue frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PrintedAnchor {
    /// The id the phone reports (`anchors.csv`'s `anchor`).
    pub id: String,
    /// Room-from-image pose.
    pub pose: Pose,
    /// Width along the image's +X (m).
    pub width_m: f64,
    /// Height along the image's +Y (m).
    pub height_m: f64,
}

/// A4 landscape, metres.
const A4_M: (f64, f64) = (0.297, 0.210);

/// How far in front of its wall the print lies, so rays hit it first.
const PRINT_OFFSET_M: f64 = 0.005;

impl PrintedAnchor {
    /// An A4 print (landscape) on `wall`, at `(u, v)` metres from its centre along its
    /// `axis_u` and `axis_v`, with +X along `axis_u` (the wall's own orientation: for the
    /// demo room's north wall that is the right of someone facing it).
    pub fn a4_on(id: &str, wall: &Surface, u: f64, v: f64) -> Result<Self, Error> {
        sitar_core::venue::check_anchor_id(id)
            .map_err(|e| Error::InvalidArgument(e.to_string()))?;
        if wall.normal.y.abs() > 1e-6 {
            return Err(Error::InvalidArgument(format!(
                "the anchor goes on a wall; `{}` is not vertical",
                wall.name
            )));
        }
        let (w, h) = A4_M;
        if u.abs() + w / 2.0 > wall.half_u || v.abs() + h / 2.0 > wall.half_v {
            return Err(Error::InvalidArgument(format!(
                "an A4 print at ({u}, {v}) m from the centre of `{}` does not fit on it",
                wall.name
            )));
        }
        let (x, y, z) = (wall.axis_u, wall.axis_v(), wall.normal);
        let centre = wall.centre + x * u + y * v + z * PRINT_OFFSET_M;
        let rotation = DQuat::from_mat3(&DMat3::from_cols(x, y, z)).normalize();
        Ok(Self {
            id: id.to_owned(),
            pose: Pose::new(centre, rotation),
            width_m: w,
            height_m: h,
        })
    }

    /// The demo venue's anchor: [`DEMO_ANCHOR_ID`] on the demo room's north wall, 1.3 m right
    /// of the middle (beside the painting), its centre 1.45 m above the floor.
    pub fn demo() -> Self {
        let room = Room::demo();
        let wall = room
            .surface("north wall")
            .expect("the demo room has a north wall");
        Self::a4_on(DEMO_ANCHOR_ID, wall, 1.3, 1.45 - wall.centre.y)
            .expect("the demo anchor fits on the north wall")
    }

    /// The print as a room surface named [`ANCHOR_SURFACE`]: textured (a printed anchor is a
    /// high-texture image).
    pub fn surface(&self) -> Surface {
        let r = self.pose.rotation;
        Surface::new(
            ANCHOR_SURFACE,
            SurfaceKind::Textured,
            self.pose.position,
            r * DVec3::Z,
            r * DVec3::X,
            self.width_m / 2.0,
            self.height_m / 2.0,
        )
    }

    /// The four corners in the room.
    pub fn corners(&self) -> [DVec3; 4] {
        self.surface().corners()
    }
}

impl Room {
    /// This room with `anchor` printed on its wall (a surface named [`ANCHOR_SURFACE`]).
    pub fn with_anchor(mut self, anchor: &PrintedAnchor) -> Result<Self, Error> {
        if self.surface(ANCHOR_SURFACE).is_some() {
            return Err(Error::InvalidArgument(
                "the room already has a printed anchor".into(),
            ));
        }
        self.surfaces.push(anchor.surface());
        Room::new(self.surfaces)
    }
}

/// How a phone's image tracker (ARCore Augmented Images, AR Foundation's tracked images)
/// sees a printed anchor: only when the whole print is inside the camera frustum, facing the
/// camera, near enough and not hidden; `full` tracking when close and frontal, `limited`
/// otherwise; the reported pose noisy, more so with distance and obliquity, and now and
/// then grossly wrong (a mis-detection).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnchorSensor {
    /// Half field of view (degrees) on both image axes: the narrower side of the camera
    /// image, so it holds whichever way the phone is held.
    pub half_fov_deg: f64,
    /// Farthest detection (m).
    pub max_range_m: f64,
    /// Most oblique detection: angle between the print's normal and the line to the camera
    /// (degrees).
    pub max_view_angle_deg: f64,
    /// Full tracking up to this distance (m) …
    pub full_range_m: f64,
    /// … and this view angle (degrees); `limited` beyond.
    pub full_view_angle_deg: f64,
    /// Position noise across the line of sight at 0 m, and its growth per metre of
    /// `distance · (1 + 2 (1 − cos angle))` (m, m/m). Along the line of sight it is twice.
    pub position_sigma_m: (f64, f64),
    /// Rotation noise per axis at 0 m and its growth per metre likewise (degrees, deg/m).
    pub rotation_sigma_deg: (f64, f64),
    /// Noise multiplier of `limited` observations.
    pub limited_noise_scale: f64,
    /// Probability that an observation is a gross mis-detection (0.1–0.5 m, 5–30° off).
    pub outlier_probability: f64,
}

impl Default for AnchorSensor {
    fn default() -> Self {
        Self {
            half_fov_deg: 25.0,
            max_range_m: 3.0,
            max_view_angle_deg: 60.0,
            full_range_m: 2.0,
            full_view_angle_deg: 45.0,
            position_sigma_m: (0.002, 0.004),
            rotation_sigma_deg: (0.2, 0.6),
            limited_noise_scale: 3.0,
            outlier_probability: 0.02,
        }
    }
}

/// What the camera sees of the anchor in one frame, before noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sighting {
    /// Camera to the anchor's centre (m).
    pub distance_m: f64,
    /// Angle between the print's normal and the line to the camera (degrees).
    pub view_angle_deg: f64,
    /// `full` or `limited`.
    pub tracking: Tracking,
}

impl AnchorSensor {
    /// Whether a camera at `position`, `rotation` (room frame, ARCore convention: looking
    /// along −Z) sees `anchor` in `room`, and how well; `None` when it does not.
    pub fn sighting(
        &self,
        room: &Room,
        anchor: &PrintedAnchor,
        position: DVec3,
        rotation: DQuat,
    ) -> Option<Sighting> {
        let centre = anchor.pose.position;
        let to_camera = position - centre;
        let distance_m = to_camera.length();
        if !(distance_m > 1e-6 && distance_m <= self.max_range_m) {
            return None;
        }
        let normal = anchor.pose.rotation * DVec3::Z;
        let view_angle_deg = (normal.dot(to_camera) / distance_m)
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees();
        if view_angle_deg > self.max_view_angle_deg {
            return None;
        }
        let limit = self.half_fov_deg.to_radians().tan();
        let inverse = rotation.inverse();
        let in_frustum = anchor.corners().iter().all(|&c| {
            let d = inverse * (c - position);
            let depth = -d.z;
            depth > 0.05 && (d.x / depth).abs() <= limit && (d.y / depth).abs() <= limit
        });
        if !in_frustum {
            return None;
        }
        // Nothing in between: the first surface on the line of sight is the print.
        let hit = room.raycast(position, centre - position)?;
        if hit.surface_name != ANCHOR_SURFACE {
            return None;
        }
        let full = distance_m <= self.full_range_m && view_angle_deg <= self.full_view_angle_deg;
        Some(Sighting {
            distance_m,
            view_angle_deg,
            tracking: if full {
                Tracking::Full
            } else {
                Tracking::Limited
            },
        })
    }

    /// The pose the tracker reports for `anchor` (room-from-image, room frame) given a
    /// `sighting` from a camera at `position`: the true pose with noise, or a mis-detection.
    pub fn noisy_pose(
        &self,
        anchor: &PrintedAnchor,
        sighting: &Sighting,
        position: DVec3,
        rng: &mut ChaCha8Rng,
    ) -> Pose {
        let mut normal = || -> f64 { StandardNormal.sample(rng) };
        let (n0, n1, n2, n3, n4, n5) = (normal(), normal(), normal(), normal(), normal(), normal());
        let truth = anchor.pose;
        if rng.random_bool(self.outlier_probability) {
            let offset = DVec3::new(n0, n1, n2).normalize_or(DVec3::X) * rng.random_range(0.1..0.5);
            let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            let turn = DQuat::from_rotation_y(sign * rng.random_range(5.0f64..30.0).to_radians());
            return Pose::new(truth.position + offset, (turn * truth.rotation).normalize());
        }
        let cos = sighting.view_angle_deg.to_radians().cos();
        let scale = sighting.distance_m * (1.0 + 2.0 * (1.0 - cos));
        let extra = match sighting.tracking {
            Tracking::Full => 1.0,
            _ => self.limited_noise_scale,
        };
        let sigma_p = (self.position_sigma_m.0 + self.position_sigma_m.1 * scale) * extra;
        let sigma_r =
            (self.rotation_sigma_deg.0 + self.rotation_sigma_deg.1 * scale).to_radians() * extra;
        // Across the line of sight σ, along it 2σ (depth from a monocular image is weaker).
        let ray = (truth.position - position).normalize_or(DVec3::NEG_Z);
        let across = ray.any_orthonormal_pair();
        let offset = (across.0 * n0 + across.1 * n1 + ray * 2.0 * n2) * sigma_p;
        let wobble = DQuat::from_scaled_axis(DVec3::new(n3, n4, n5) * sigma_r);
        Pose::new(
            truth.position + offset,
            (wobble * truth.rotation).normalize(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::look_rotation;
    use rand::SeedableRng;

    #[test]
    fn the_demo_anchor_lies_on_the_north_wall_facing_the_room() {
        let anchor = PrintedAnchor::demo();
        let p = anchor.pose.position;
        assert!((p - DVec3::new(1.3, 1.45, -2.0 + PRINT_OFFSET_M)).length() < 1e-12);
        // Facing the wall from the room (looking along −Z), +X is to the right: +x.
        assert!((anchor.pose.rotation * DVec3::X - DVec3::X).length() < 1e-12);
        assert!((anchor.pose.rotation * DVec3::Z - DVec3::Z).length() < 1e-12);
        let room = Room::demo().with_anchor(&anchor).unwrap();
        let (s, d) = room.nearest_surface(p).unwrap();
        assert_eq!((s.name.as_str(), d), (ANCHOR_SURFACE, 0.0));
        assert!(room.clone().with_anchor(&anchor).is_err());
    }

    #[test]
    fn a4_prints_must_fit_their_wall_and_have_a_valid_id() {
        let room = Room::demo();
        let wall = room.surface("north wall").unwrap();
        assert!(PrintedAnchor::a4_on("a", wall, 2.4, 0.0).is_err());
        assert!(PrintedAnchor::a4_on("a,b", wall, 0.0, 0.0).is_err());
        assert!(PrintedAnchor::a4_on("a", room.surface("floor").unwrap(), 0.0, 0.0).is_err());
    }

    #[test]
    fn the_anchor_is_seen_only_in_view_near_enough_and_facing_it() {
        let anchor = PrintedAnchor::demo();
        let room = Room::demo().with_anchor(&anchor).unwrap();
        let sensor = AnchorSensor::default();
        let c = anchor.pose.position;
        let looking_at = |p: DVec3| look_rotation((c - p).normalize(), 0.0);
        let see = |p: DVec3| sensor.sighting(&room, &anchor, p, looking_at(p));
        // In front at 1.2 m: full.
        let s = see(c + DVec3::Z * 1.2).unwrap();
        assert_eq!(s.tracking, Tracking::Full);
        assert!((s.distance_m - 1.2).abs() < 1e-9 && s.view_angle_deg < 1e-6);
        // 2.5 m: limited; 3.5 m: not seen (the room is 4 m deep, so look from inside it).
        assert_eq!(see(c + DVec3::Z * 2.5).unwrap().tracking, Tracking::Limited);
        let far = c + DVec3::new(-2.0, 0.0, 2.9);
        assert!(far.distance(c) > 3.0 && see(far).is_none());
        // 55° off the normal: limited; 70°: not seen.
        let at = |deg: f64| {
            let a = deg.to_radians();
            c + DVec3::new(-a.sin(), 0.0, a.cos()) * 1.2
        };
        assert_eq!(see(at(55.0)).unwrap().tracking, Tracking::Limited);
        assert!(see(at(70.0)).is_none());
        // Looking away, or from behind the wall: not seen.
        let p = c + DVec3::Z * 1.2;
        assert!(
            sensor
                .sighting(&room, &anchor, p, look_rotation(DVec3::Z, 0.0))
                .is_none()
        );
        assert!(
            sensor
                .sighting(
                    &room,
                    &anchor,
                    p,
                    look_rotation(DVec3::new(0.6, 0.0, -0.8), 0.0)
                )
                .is_none()
        );
        assert!(see(c - DVec3::Z * 1.0).is_none());
    }

    #[test]
    fn noise_grows_with_distance_and_angle() {
        let anchor = PrintedAnchor::demo();
        let room = Room::demo().with_anchor(&anchor).unwrap();
        let sensor = AnchorSensor {
            outlier_probability: 0.0,
            ..AnchorSensor::default()
        };
        let c = anchor.pose.position;
        let rms = |p: DVec3| {
            let s = sensor
                .sighting(&room, &anchor, p, look_rotation((c - p).normalize(), 0.0))
                .unwrap();
            let mut rng = ChaCha8Rng::seed_from_u64(5);
            let n = 2000;
            let (mut pos, mut ang) = (0.0, 0.0);
            for _ in 0..n {
                let o = sensor.noisy_pose(&anchor, &s, p, &mut rng);
                pos += o.position.distance_squared(c);
                ang += o.rotation.angle_between(anchor.pose.rotation).powi(2);
            }
            (
                (pos / n as f64).sqrt(),
                (ang / n as f64).sqrt().to_degrees(),
            )
        };
        let near = rms(c + DVec3::Z * 0.8);
        let far = rms(c + DVec3::Z * 1.9);
        let oblique = rms(c + DVec3::new(-1.9 * 0.64, 0.0, 1.9 * 0.77));
        assert!(
            near.0 < far.0 && far.0 < oblique.0,
            "{near:?} {far:?} {oblique:?}"
        );
        assert!(
            near.1 < far.1 && far.1 < oblique.1,
            "{near:?} {far:?} {oblique:?}"
        );
        // Expected at 0.8 m frontal: σ = 0.002 + 0.004·0.8 = 5.2 mm, RMS √6·σ = 12.7 mm.
        assert!((near.0 - 6f64.sqrt() * 0.0052).abs() < 0.001, "{near:?}");
    }
}
