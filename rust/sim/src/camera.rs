//! Camera models: the phone's depth camera and what the tracking camera sees.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use sitar_core::DisplayRotation;

use crate::{Room, SurfaceKind};

/// The phone's pinhole model, shared with `sitar-core` so a rendered image and its
/// intrinsics go to the phone logic as they are.
pub use sitar_core::Intrinsics;

/// A depth camera like ARCore's Depth API: 16-bit millimetres, 0 = no depth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DepthCamera {
    /// Intrinsics of the depth image.
    pub intrinsics: Intrinsics,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Depths beyond this are reported as 0 (no depth), like ARCore's 8 m limit.
    pub max_range_m: f64,
    /// Share of the pixels on glass that still get a depth (speckle; the rest read 0): phone
    /// depth fails on glass and mirrors, which the colour image shows as a surface.
    #[serde(default = "all_pixels")]
    pub glass_valid_share: f64,
}

fn all_pixels() -> f64 {
    1.0
}

/// The horizontal field of view of the simulated phone's cameras (depth and luminance).
pub(crate) const PHONE_HFOV_DEG: f64 = 64.0;

/// Square-pixel intrinsics with the principal point at the centre pixel.
pub(crate) fn centred_pinhole(width: u32, height: u32, hfov_deg: f64) -> Intrinsics {
    let f = f64::from(width) / 2.0 / (hfov_deg / 2.0).to_radians().tan();
    Intrinsics {
        fx: f,
        fy: f,
        cx: f64::from(width / 2),
        cy: f64::from(height / 2),
    }
}

impl DepthCamera {
    /// A phone-like 160 × 120 depth image with a 64° horizontal field of view, principal
    /// point at the centre pixel (80, 60), 8 m range; 30 % of the pixels on glass have depth.
    pub fn phone() -> Self {
        let (width, height) = (160u32, 120u32);
        Self {
            intrinsics: centred_pinhole(width, height, PHONE_HFOV_DEG),
            width,
            height,
            max_range_m: 8.0,
            glass_valid_share: 0.3,
        }
    }
}

/// Direction, in the display-oriented ARCore camera frame (x right, y up, looking along −z),
/// of the optical ray through sensor image point `(u, v)`; its z component is −1 so that `t`
/// along it is the z-depth.
///
/// The sensor image appears on the display turned clockwise by the display rotation θ: in
/// screen coordinates (x right, y down) an offset `(x, y)` becomes
/// `(x cos θ − y sin θ, x sin θ + y cos θ)`. Written here with trigonometry rather than with
/// `sitar-core`'s exact quarter-turn tables, so a test that compares the two checks something.
pub(crate) fn camera_ray(k: &Intrinsics, u: f64, v: f64, display: DisplayRotation) -> DVec3 {
    let (x, y) = ((u - k.cx) / k.fx, (v - k.cy) / k.fy);
    let (sin, cos) = f64::from(display.degrees()).to_radians().sin_cos();
    // Quarter turns: sin and cos are exactly 0 or ±1 (sin_cos leaves ~1e-16 residues).
    let (sin, cos) = (sin.round(), cos.round());
    let (x, y) = (x * cos - y * sin, x * sin + y * cos);
    DVec3::new(x, -y, -1.0)
}

impl Room {
    /// Renders the depth image a phone at `position`/`rotation` would see, held so that the
    /// display rotation is 0 (see [`Room::render_depth_mm_rotated`]).
    pub fn render_depth_mm(
        &self,
        position: DVec3,
        rotation: DQuat,
        camera: &DepthCamera,
    ) -> Vec<u16> {
        self.render_depth_mm_rotated(position, rotation, camera, DisplayRotation::Deg0)
    }

    /// Renders the depth image a phone at `position`/`rotation` would see, with the sensor
    /// image turned clockwise by `display` on the screen (e.g. 90 for a phone whose landscape
    /// sensor is shown in portrait).
    ///
    /// The pose is the display-oriented world-from-camera pose in the ARCore convention
    /// (right-handed, +Y up, camera looks along −Z, +X right), as ARCore and AR Foundation
    /// report it. The returned image is in the *sensor* orientation, as ARCore's depth API
    /// gives it: row-major, `width × height`, row 0 at the top. Each pixel holds the depth along
    /// the optical axis (z-depth, as ARCore reports it) in millimetres, rounded to nearest; 0
    /// where the ray hits nothing or the depth exceeds `max_range_m` or 65.535 m, and on glass
    /// outside the camera's `glass_valid_share` of speckle pixels (fixed per sensor pixel).
    pub fn render_depth_mm_rotated(
        &self,
        position: DVec3,
        rotation: DQuat,
        camera: &DepthCamera,
        display: DisplayRotation,
    ) -> Vec<u16> {
        let k = &camera.intrinsics;
        let mut image = Vec::with_capacity(camera.width as usize * camera.height as usize);
        for v in 0..camera.height {
            for u in 0..camera.width {
                let ray = camera_ray(k, f64::from(u), f64::from(v), display);
                let world_dir = rotation * ray;
                let depth_m = self
                    .raycast(position, world_dir)
                    .filter(|hit| {
                        hit.surface != SurfaceKind::Glass
                            || crate::noise::hash(i64::from(u), i64::from(v), 0x61A55)
                                < camera.glass_valid_share
                    })
                    // Distance along the unit ray / |ray| = z-depth (the ray has z = −1).
                    .map(|hit| hit.distance / ray.length())
                    .filter(|&d| d.is_finite() && d <= camera.max_range_m);
                image.push(match depth_m {
                    Some(d) => {
                        let mm = (d * 1000.0).round();
                        if mm >= 1.0 && mm <= f64::from(u16::MAX) {
                            mm as u16
                        } else {
                            0
                        }
                    }
                    None => 0,
                });
            }
        }
        image
    }

    /// What the tracking camera at `position`/`rotation` (ARCore convention) sees, sampled on a
    /// 9 × 7 grid over a 64° × 50° field of view.
    pub fn view(&self, position: DVec3, rotation: DQuat) -> View {
        const COLS: u32 = 9;
        const ROWS: u32 = 7;
        let half_h = (32f64).to_radians().tan();
        let half_v = (25f64).to_radians().tan();
        let (mut poverty, mut reflect, mut hits) = (0.0, 0.0, 0u32);
        for r in 0..ROWS {
            for c in 0..COLS {
                let x = (2.0 * f64::from(c) / f64::from(COLS - 1) - 1.0) * half_h;
                let y = (2.0 * f64::from(r) / f64::from(ROWS - 1) - 1.0) * half_v;
                if let Some(hit) = self.raycast(position, rotation * DVec3::new(x, y, -1.0)) {
                    poverty += hit.surface.feature_poverty();
                    reflect += hit.surface.reflectivity();
                    hits += 1;
                }
            }
        }
        let centre = self.raycast(position, rotation * -DVec3::Z);
        if hits == 0 {
            // Looking into nothing: nothing to track.
            return View {
                difficulty: 1.0,
                reflectivity: 0.0,
                facing: None,
                facing_kind: None,
            };
        }
        View {
            difficulty: poverty / f64::from(hits),
            reflectivity: reflect / f64::from(hits),
            facing_kind: centre.as_ref().map(|h| h.surface),
            facing: centre.map(|h| h.surface_name),
        }
    }
}

/// A summary of one camera view, as it matters to tracking.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct View {
    /// Mean feature poverty over the view, 0 (rich) … 1 (nothing to track).
    pub difficulty: f64,
    /// Share of the view that reflects (glass), 0 … 1.
    pub reflectivity: f64,
    /// The surface at the image centre.
    pub facing: Option<String>,
    /// Its kind.
    pub facing_kind: Option<SurfaceKind>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// ARCore-convention rotation looking along `forward` with +Y up.
    fn look(forward: DVec3) -> DQuat {
        crate::walk::look_rotation(forward.normalize(), 0.0)
    }

    #[test]
    fn depth_of_a_fronto_parallel_wall_is_constant() {
        let room = Room::demo();
        let cam = DepthCamera::phone();
        // 1.5 m in front of the blank wall, looking straight at it; the view stays on the wall.
        let pos = DVec3::new(1.0, 1.35, 0.0);
        let img = room.render_depth_mm(pos, look(DVec3::X), &cam);
        assert_eq!(img.len(), 160 * 120);
        assert!(img.iter().all(|&d| d == 1500), "{:?}", &img[..10]);
    }

    #[test]
    fn depth_of_a_tilted_view_matches_the_analytic_plane_depth() {
        let room = Room::demo();
        let cam = DepthCamera::phone();
        let k = cam.intrinsics;
        // Looking down at the floor at 45 degrees from 1.2 m height.
        let pos = DVec3::new(0.0, 1.2, 0.0);
        let rot = look(DVec3::new(0.0, -1.0, -1.0));
        let img = room.render_depth_mm(pos, rot, &cam);
        for (u, v) in [(80u32, 60u32), (0, 0), (159, 119), (40, 100), (120, 10)] {
            let ray = rot * camera_ray(&k, f64::from(u), f64::from(v), DisplayRotation::Deg0);
            // Floor y = 0: pos.y + t * ray.y = 0, and t is the z-depth.
            let z_depth = -pos.y / ray.y;
            let hit = pos + ray * z_depth;
            let expected = if hit.x.abs() <= 2.5 && hit.z.abs() <= 2.0 && ray.y < 0.0 {
                (z_depth * 1000.0).round() as u16
            } else {
                continue;
            };
            assert_eq!(img[(v * 160 + u) as usize], expected, "pixel ({u}, {v})");
        }
        // Image centre: 1.2 * sqrt(2) m along the optical axis.
        assert_eq!(img[60 * 160 + 80], (1200.0 * 2f64.sqrt()).round() as u16);
    }

    #[test]
    fn glass_reads_as_speckle_with_the_cameras_share_of_depth() {
        let room = Room::demo();
        let cam = DepthCamera::phone();
        let glass = room.surface("glass pane").unwrap();
        let pos = glass.centre + glass.normal * 1.0;
        let img = room.render_depth_mm(pos, crate::look_rotation(-glass.normal, 0.0), &cam);
        // The pane fills the central part of the view: count its pixels with depth.
        let central: Vec<u16> = (40..80)
            .flat_map(|v| (60..100).map(move |u| (u, v)))
            .map(|(u, v)| img[v * 160 + u])
            .collect();
        let share = central.iter().filter(|&&d| d != 0).count() as f64 / central.len() as f64;
        assert!((share - 0.3).abs() < 0.06, "share {share}");
        assert!(
            central
                .iter()
                .all(|&d| d == 0 || (d as i32 - 1000).abs() <= 1)
        );
    }

    #[test]
    fn far_and_missing_depth_is_zero() {
        let room = Room::demo();
        let mut cam = DepthCamera::phone();
        cam.max_range_m = 1.0;
        let img = room.render_depth_mm(DVec3::new(1.0, 1.35, 0.0), look(DVec3::X), &cam);
        assert!(img.iter().all(|&d| d == 0));
        // Outside the room looking away: no hits at all.
        let img = room.render_depth_mm(
            DVec3::new(9.0, 1.0, 0.0),
            look(DVec3::X),
            &DepthCamera::phone(),
        );
        assert!(img.iter().all(|&d| d == 0));
    }

    #[test]
    fn views_of_hard_surfaces_are_difficult() {
        let room = Room::demo();
        let eye = |x, z| DVec3::new(x, 1.4, z);
        let blank = room.view(eye(1.0, 0.0), look(DVec3::X));
        let glass = room.view(eye(0.2, 0.6), look(DVec3::Z));
        let shelf = room.view(eye(-1.1, 0.3), look(-DVec3::X));
        assert_eq!(blank.facing.as_deref(), Some("blank wall"));
        assert_eq!(glass.facing.as_deref(), Some("glass pane"));
        assert_eq!(shelf.facing.as_deref(), Some("bookshelf"));
        assert!(blank.difficulty > 0.8, "{blank:?}");
        assert!(
            glass.difficulty > 0.6 && glass.reflectivity > 0.6,
            "{glass:?}"
        );
        assert!(shelf.difficulty < 0.2, "{shelf:?}");
    }

    /// The renderer (trigonometry) and `sitar-core`'s sampling (quarter-turn tables) agree on
    /// the display rotation: for every rotation, a sensor pixel off the centre unprojects with
    /// the core to the point the renderer's ray through that pixel hits, with the wall's normal.
    #[test]
    fn every_display_rotation_agrees_with_the_core_sampling() {
        use sitar_core::{Convention, DepthImage, Pose, sample_surface};
        let room = Room::demo();
        let cam = DepthCamera::phone();
        // Standing in the room, looking slightly down and to the side at a wall.
        let position = DVec3::new(0.3, 1.5, 0.2);
        let rotation = DQuat::from_rotation_y(0.4) * DQuat::from_rotation_x(-0.15);
        let pose = Pose::new(position, rotation);
        for display in [
            DisplayRotation::Deg0,
            DisplayRotation::Deg90,
            DisplayRotation::Deg180,
            DisplayRotation::Deg270,
        ] {
            let depth = room.render_depth_mm_rotated(position, rotation, &cam, display);
            let image = DepthImage::new(&depth, cam.width, cam.height, cam.width * 2).unwrap();
            for (u, v) in [(80, 60), (110, 60), (80, 35), (50, 85)] {
                let sample = sample_surface(
                    &image,
                    &cam.intrinsics,
                    display,
                    Convention::Arcore,
                    &pose,
                    Some((u, v)),
                )
                .unwrap();
                let ray =
                    rotation * camera_ray(&cam.intrinsics, f64::from(u), f64::from(v), display);
                let hit = room.raycast(position, ray).unwrap();
                // Millimetre depth: the point is within a millimetre or so along the ray.
                let miss = (sample.point - hit.point).length();
                assert!(miss < 2e-3, "{display:?} ({u}, {v}): {miss} m off");
                let angle = sample.normal.angle_between(hit.normal).to_degrees();
                assert!(angle < 1.0, "{display:?} ({u}, {v}): normal {angle}° off");
            }
        }
        // A different rotation is a different image: the off-centre pixels see other points.
        let upright = room.render_depth_mm_rotated(position, rotation, &cam, DisplayRotation::Deg0);
        let portrait =
            room.render_depth_mm_rotated(position, rotation, &cam, DisplayRotation::Deg90);
        assert_eq!(upright[60 * 160 + 80], portrait[60 * 160 + 80]);
        assert_ne!(upright, portrait);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// From anywhere inside the room, a rendered pixel equals the raycast's z-depth.
        #[test]
        fn depth_pixels_agree_with_raycast(
            x in -2.3f64..2.3, y in 0.2f64..2.5, z in -1.8f64..1.8,
            yaw in -3.1f64..3.1, pitch in -1.2f64..1.2, u in 0u32..160, v in 0u32..120,
        ) {
            let room = Room::demo();
            // Glass with full depth: this checks geometry (the speckle has its own test).
            let cam = DepthCamera { glass_valid_share: 1.0, ..DepthCamera::phone() };
            let pos = DVec3::new(x, y, z);
            let rot = DQuat::from_rotation_y(yaw) * DQuat::from_rotation_x(pitch);
            let img = room.render_depth_mm(pos, rot, &cam);
            let ray_cam = camera_ray(&cam.intrinsics, f64::from(u), f64::from(v), DisplayRotation::Deg0);
            let hit = room.raycast(pos, rot * ray_cam).unwrap();
            // z-depth is the hit point's distance along the optical axis.
            let z_depth = (hit.point - pos).dot(rot * -DVec3::Z);
            prop_assert!(hit.distance > 0.0);
            let expected = (z_depth * 1000.0).round() as u16;
            prop_assert_eq!(img[(v * 160 + u) as usize], expected);
        }
    }
}
