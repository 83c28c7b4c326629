//! What the phone's colour camera sees, as its luminance plane: each surface kind has its
//! own look (the painting and the rug textured, the blank wall plain, the glass a faint
//! reflection), lit differently by region, with a little sensor noise.

use glam::{DQuat, DVec3};
use sitar_core::DisplayRotation;

use crate::camera::camera_ray;
use crate::noise::hash;
use crate::{Intrinsics, Room, SurfaceKind};

/// The colour camera: its luminance plane (ARCore's `Image` plane 0) and intrinsics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LumaCamera {
    /// Intrinsics of the luminance image.
    pub intrinsics: Intrinsics,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl LumaCamera {
    /// A 320 × 240 image with the depth camera's 64° horizontal field of view (a quarter of a
    /// phone's 640 × 480 CPU image in each direction, enough for the properties and cheap to
    /// ray-cast).
    pub fn phone() -> Self {
        let (width, height) = (320u32, 240u32);
        Self {
            intrinsics: crate::camera::centred_pinhole(
                width,
                height,
                crate::camera::PHONE_HFOV_DEG,
            ),
            width,
            height,
        }
    }
}

/// Sensor noise amplitude (grey levels, ±): well under FAST's threshold of 20, as a phone ISP's
/// denoised output.
const NOISE: f64 = 3.0;

/// Albedo (0…255) of a surface kind at in-plane coordinates `(u, v)` metres; `view` is the
/// unit viewing direction (the glass reflection moves with it).
fn albedo(kind: SurfaceKind, surface: usize, u: f64, v: f64, view: DVec3) -> f64 {
    let cell = |size: f64| ((u / size).floor() as i64, (v / size).floor() as i64);
    match kind {
        // Blocks of paint 6 cm across in many tones: corners everywhere.
        SurfaceKind::Textured => {
            let (i, j) = cell(0.06);
            30.0 + 200.0 * hash(i, j, surface as i64)
        }
        // Painted wall: a few dark marks (switches, frames) 8 cm across on a 0.6 m grid.
        SurfaceKind::Plain => {
            let (i, j) = cell(0.6);
            let (fu, fv) = (u / 0.6 - i as f64, v / 0.6 - j as f64);
            let mark = hash(i, j, 7 + surface as i64) < 0.5 && fu < 0.13 && fv < 0.13;
            if mark { 60.0 } else { 175.0 }
        }
        SurfaceKind::Blank => 185.0,
        // Dark glass with a faint, smooth reflection of the room that slides with the view.
        SurfaceKind::Glass => {
            let phase = 2.5 * (u + 2.0 * view.x) + 1.5 * (v + 2.0 * view.y);
            70.0 + 10.0 * phase.sin()
        }
        SurfaceKind::Dark => 10.0,
    }
}

/// Illumination (0…1) at a world point: a bright window end (−z), a dimmer far end, a lamp
/// pool on the west side, so the same surface kind reads differently by region.
fn lighting(p: DVec3) -> f64 {
    let along = (0.85 - 0.08 * p.z).clamp(0.55, 1.0);
    let lamp = 0.25 * (-((p.x + 2.0).powi(2) + (p.z - 0.3).powi(2)) / 1.5).exp();
    (along + lamp).min(1.0)
}

impl Room {
    /// Renders the 8-bit luminance plane a phone at `position`/`rotation` (ARCore
    /// convention, display-oriented, as for [`Room::render_depth_mm_rotated`]) would see with
    /// its sensor image turned clockwise by `display`. The image is in sensor orientation,
    /// row-major, `width × height` (stride = width). Rays that hit nothing are black;
    /// `seed` varies the sensor noise between frames.
    pub fn render_luma_rotated(
        &self,
        position: DVec3,
        rotation: DQuat,
        camera: &LumaCamera,
        display: DisplayRotation,
        seed: u64,
    ) -> Vec<u8> {
        let k = &camera.intrinsics;
        let mut image = Vec::with_capacity(camera.width as usize * camera.height as usize);
        for v in 0..camera.height {
            for u in 0..camera.width {
                let ray = camera_ray(k, f64::from(u), f64::from(v), display);
                let dir = (rotation * ray).normalize();
                let hit = self
                    .surfaces
                    .iter()
                    .enumerate()
                    .filter_map(|(i, s)| s.intersect(position, dir).map(|t| (i, t)))
                    .min_by(|a, b| a.1.total_cmp(&b.1));
                let value = match hit {
                    None => 0.0,
                    Some((i, t)) => {
                        let s = &self.surfaces[i];
                        let p = position + dir * t;
                        let local = p - s.centre;
                        let (su, sv) = (local.dot(s.axis_u), local.dot(s.axis_v()));
                        let noise =
                            NOISE * (2.0 * hash(i64::from(u), i64::from(v), seed as i64) - 1.0);
                        albedo(s.kind, i, su, sv, dir) * lighting(p) + noise
                    }
                };
                image.push(value.round().clamp(0.0, 255.0) as u8);
            }
        }
        image
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::look_rotation;
    use sitar_core::{Causes, ImageProperties, LumaImage};

    fn properties_facing(target: &str) -> ImageProperties {
        let room = Room::demo();
        let s = room.surface(target).unwrap();
        let position = s.centre + s.normal * 1.2;
        let rotation = look_rotation(-s.normal, 0.0);
        let cam = LumaCamera::phone();
        let luma = room.render_luma_rotated(position, rotation, &cam, DisplayRotation::Deg0, 1);
        ImageProperties::measure(&LumaImage::new(&luma, cam.width, cam.height, cam.width).unwrap())
    }

    #[test]
    fn surfaces_look_as_their_kind_says() {
        let painting = properties_facing("painting");
        let blank = properties_facing("blank wall");
        let glass = properties_facing("glass pane");
        assert!(painting.corners_per_10k > 20.0, "{painting:?}");
        assert!(
            blank.corners_per_10k < sitar_core::LOW_TEXTURE_CORNERS,
            "{blank:?}"
        );
        assert!(
            glass.corners_per_10k < sitar_core::LOW_TEXTURE_CORNERS,
            "{glass:?}"
        );
        assert!(glass.mean_brightness < blank.mean_brightness);
        let _ = Causes::LOW_TEXTURE;
    }

    #[test]
    fn the_display_rotation_turns_the_sensor_image() {
        let room = Room::demo();
        let s = room.surface("painting").unwrap();
        let (position, rotation) = (s.centre + s.normal * 1.0, look_rotation(-s.normal, 0.0));
        let cam = LumaCamera {
            width: 40,
            height: 30,
            ..LumaCamera::phone()
        };
        let cam = LumaCamera {
            intrinsics: Intrinsics {
                fx: 40.0,
                fy: 40.0,
                cx: 19.5,
                cy: 14.5,
            },
            ..cam
        };
        let upright = room.render_luma_rotated(position, rotation, &cam, DisplayRotation::Deg0, 0);
        // Held at 180°, the sensor image is the upright one turned half a turn.
        let turned = room.render_luma_rotated(position, rotation, &cam, DisplayRotation::Deg180, 0);
        let (w, h) = (40usize, 30usize);
        let mut differ = 0;
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                let a = i32::from(upright[y * w + x]);
                let b = i32::from(turned[(h - 1 - y) * w + (w - 1 - x)]);
                // The same point up to the noise (which is per sensor pixel).
                if (a - b).abs() > 2 * NOISE as i32 + 1 {
                    differ += 1;
                }
            }
        }
        assert!(differ < 40, "{differ} pixels differ");
    }
}
