//! Depth geometry: from an ARCore depth image to a surface point and normal.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::{Convention, DisplayRotation, Error, InvalidDepth, Pose};

/// Pinhole intrinsics in pixels of the depth (sensor) image.
///
/// Pixel `(u, v)` has its centre at image coordinates `(u, v)` (OpenCV convention), so the
/// optical ray of pixel `(u, v)` is `((u − cx)/fx, (v − cy)/fy, 1)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    /// Focal length along x (pixels).
    pub fx: f64,
    /// Focal length along y (pixels).
    pub fy: f64,
    /// Principal point x (pixels).
    pub cx: f64,
    /// Principal point y (pixels).
    pub cy: f64,
}

impl Intrinsics {
    /// Checks that the focal lengths are finite and positive and the principal point finite.
    pub fn validate(&self) -> Result<(), Error> {
        if !(self.fx.is_finite() && self.fx > 0.0 && self.fy.is_finite() && self.fy > 0.0) {
            return Err(Error::arg(
                "intrinsics",
                format!(
                    "focal lengths ({}, {}) must be finite and > 0",
                    self.fx, self.fy
                ),
            ));
        }
        if !(self.cx.is_finite() && self.cy.is_finite()) {
            return Err(Error::arg("intrinsics", "principal point is not finite"));
        }
        Ok(())
    }

    /// The optical ray `(x/z, y/z, 1)` through pixel `(u, v)`.
    pub fn ray(&self, u: f64, v: f64) -> DVec3 {
        DVec3::new((u - self.cx) / self.fx, (v - self.cy) / self.fy, 1.0)
    }
}

/// A borrowed 16-bit depth image in millimetres (0 = no depth), sensor orientation.
#[derive(Debug, Clone, Copy)]
pub struct DepthImage<'a> {
    data: &'a [u16],
    width: u32,
    height: u32,
    /// Row stride in `u16` elements.
    stride: usize,
}

impl<'a> DepthImage<'a> {
    /// Wraps `data` (rows `row_stride_bytes` apart). The stride must be even and at least
    /// `2 * width`, and `data` must cover `(height − 1) * stride + 2 * width` bytes.
    pub fn new(
        data: &'a [u16],
        width: u32,
        height: u32,
        row_stride_bytes: u32,
    ) -> Result<Self, Error> {
        if width == 0 || height == 0 {
            return Err(Error::arg(
                "width/height",
                format!("{width}×{height} is empty"),
            ));
        }
        if !row_stride_bytes.is_multiple_of(2) || u64::from(row_stride_bytes) < 2 * u64::from(width)
        {
            return Err(Error::arg(
                "row_stride_bytes",
                format!(
                    "{row_stride_bytes} is odd or less than 2 × width ({})",
                    2 * u64::from(width)
                ),
            ));
        }
        let need = (u64::from(height) - 1) * u64::from(row_stride_bytes) + 2 * u64::from(width);
        let have = data.len() as u64 * 2;
        if have < need {
            return Err(Error::arg(
                "depth",
                format!("{have} bytes given, {need} needed"),
            ));
        }
        Ok(Self {
            data,
            width,
            height,
            stride: row_stride_bytes as usize / 2,
        })
    }

    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The default sample pixel: the image centre `(width / 2, height / 2)`.
    pub fn centre(&self) -> (u32, u32) {
        (self.width / 2, self.height / 2)
    }

    /// Depth in millimetres at `(x, y)`, `None` outside the image.
    pub fn get(&self, x: u32, y: u32) -> Option<u16> {
        if x < self.width && y < self.height {
            self.data
                .get(y as usize * self.stride + x as usize)
                .copied()
        } else {
            None
        }
    }

    /// Point and normal in the sensor's optical frame (metres), see [`sample_surface`].
    pub fn optical_sample(
        &self,
        k: &Intrinsics,
        x: u32,
        y: u32,
    ) -> Result<(DVec3, DVec3), InvalidDepth> {
        let centre_mm = match self.get(x, y) {
            None => return Err(InvalidDepth::OutOfBounds { x, y }),
            Some(0) => return Err(InvalidDepth::NoDepth { x, y }),
            Some(d) => f64::from(d),
        };
        // Weighted mean depth gradient (mm per pixel) over the 5×5 window, after ARCore
        // DepthLab: each neighbour gives a difference quotient (d − d_centre) / offset per
        // axis with a non-zero offset; missing neighbours and those more than 20 % off the
        // centre depth (other surfaces) are skipped. The weight is offset²: a quotient over
        // a longer baseline carries less of the 1 mm quantisation (inverse-variance
        // weighting; on a full window this is the least-squares slope). Opposite offsets
        // cancel the other axis' slope and the curvature terms.
        let (mut gx, mut wx, mut gy, mut wy) = (0.0, 0.0, 0.0, 0.0);
        for dy in -2i32..=2 {
            for dx in -2i32..=2 {
                if dx == 0 && dy == 0 {
                    continue;
                }
                let (nx, ny) = (x as i64 + dx as i64, y as i64 + dy as i64);
                if nx < 0 || ny < 0 {
                    continue;
                }
                let Some(d) = self.get(nx as u32, ny as u32) else {
                    continue;
                };
                if d == 0 {
                    continue;
                }
                let diff = f64::from(d) - centre_mm;
                if diff.abs() > 0.2 * centre_mm {
                    continue;
                }
                if dx != 0 {
                    // w · diff / dx with w = dx²
                    gx += diff * f64::from(dx);
                    wx += f64::from(dx * dx);
                }
                if dy != 0 {
                    gy += diff * f64::from(dy);
                    wy += f64::from(dy * dy);
                }
            }
        }
        if wx == 0.0 || wy == 0.0 {
            return Err(InvalidDepth::NoValidNeighbours { x, y });
        }
        let z = centre_mm / 1000.0;
        let (gx, gy) = (gx / wx / 1000.0, gy / wy / 1000.0);
        let ray = k.ray(f64::from(x), f64::from(y));
        let point = ray * z;
        // Tangents of P(u, v) = z(u, v)·ray(u, v) along the image axes; exact for a pinhole.
        let du = ray * gx + DVec3::new(z / k.fx, 0.0, 0.0);
        let dv = ray * gy + DVec3::new(0.0, z / k.fy, 0.0);
        let mut normal = du.cross(dv).normalize_or_zero();
        if normal == DVec3::ZERO {
            return Err(InvalidDepth::NoValidNeighbours { x, y });
        }
        if normal.dot(point) > 0.0 {
            normal = -normal; // face the camera
        }
        Ok((point, normal))
    }
}

/// A valid depth sample at a midpoint: the surface the camera faced.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DepthSample {
    /// Sample pixel `[x, y]` in the sensor image.
    pub pixel: [u32; 2],
    /// Depth along the optical axis (metres), as stored in the image.
    pub depth_m: f64,
    /// Distance from the camera to the surface point along the ray (metres).
    pub distance_m: f64,
    /// Surface point in the display-oriented camera frame of the session's convention.
    pub camera_point: DVec3,
    /// Unit surface normal (towards the camera) in that camera frame.
    pub camera_normal: DVec3,
    /// Surface point in world coordinates.
    pub point: DVec3,
    /// Unit surface normal in world coordinates, facing the camera.
    pub normal: DVec3,
}

/// Samples the surface at `pixel` (default: the image centre): unprojects it at its depth,
/// estimates the normal (see [`DepthImage::optical_sample`]), turns both by the display
/// rotation into the display-oriented optical frame, then into the convention's camera frame
/// and, with the world-from-camera `pose`, into the world.
pub fn sample_surface(
    image: &DepthImage<'_>,
    k: &Intrinsics,
    rotation: DisplayRotation,
    convention: Convention,
    pose: &Pose,
    pixel: Option<(u32, u32)>,
) -> Result<DepthSample, Error> {
    k.validate()?;
    let (x, y) = pixel.unwrap_or_else(|| image.centre());
    let (p, n) = image.optical_sample(k, x, y).map_err(Error::InvalidDepth)?;
    let camera_point = convention.camera_from_optical(rotation.display_from_sensor(p));
    let camera_normal = convention.camera_from_optical(rotation.display_from_sensor(n));
    Ok(DepthSample {
        pixel: [x, y],
        depth_m: p.z,
        distance_m: p.length(),
        camera_point,
        camera_normal,
        point: pose.transform_point(camera_point),
        normal: pose.transform_vector(camera_normal).normalize(),
    })
}

/// Test helpers: render analytic planes into millimetre depth images.
#[cfg(test)]
pub(crate) mod testing {
    use super::*;

    /// Renders the plane `n · X = d` (sensor optical frame, metres) to rounded millimetres.
    pub fn render_plane(width: u32, height: u32, k: &Intrinsics, n: DVec3, d: f64) -> Vec<u16> {
        let mut out = Vec::with_capacity((width * height) as usize);
        for v in 0..height {
            for u in 0..width {
                let ray = k.ray(f64::from(u), f64::from(v));
                let z = d / n.dot(ray);
                out.push(if z > 0.0 && z < 65.0 {
                    (z * 1000.0).round() as u16
                } else {
                    0
                });
            }
        }
        out
    }

    /// Phone-like 256×192 intrinsics.
    pub fn phone_k() -> Intrinsics {
        Intrinsics {
            fx: 211.0,
            fy: 211.0,
            cx: 127.5,
            cy: 95.5,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::testing::*;
    use super::*;
    use glam::DQuat;

    fn angle_deg(a: DVec3, b: DVec3) -> f64 {
        a.normalize()
            .dot(b.normalize())
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    }

    #[test]
    fn image_validation() {
        let data = vec![1000u16; 12];
        assert!(DepthImage::new(&data, 4, 3, 8).is_ok());
        assert!(DepthImage::new(&data, 4, 3, 7).is_err()); // odd stride
        assert!(DepthImage::new(&data, 4, 3, 6).is_err()); // stride < width
        assert!(DepthImage::new(&data, 3, 3, 10).is_err()); // 2*10+6 = 26 > 24 bytes
        assert!(DepthImage::new(&data, 3, 3, 8).is_ok()); // 2*8+6 = 22 <= 24
        assert!(DepthImage::new(&data, 0, 3, 8).is_err());
    }

    #[test]
    fn padded_stride_reads_the_right_pixels() {
        // 3×2 image with 5-element rows; padding holds garbage that must never be read.
        let data = [1u16, 2, 3, 9999, 9999, 4, 5, 6];
        let img = DepthImage::new(&data, 3, 2, 10).unwrap();
        assert_eq!(img.get(2, 0), Some(3));
        assert_eq!(img.get(0, 1), Some(4));
        assert_eq!(img.get(2, 1), Some(6));
        assert_eq!(img.get(3, 1), None);
    }

    #[test]
    fn fronto_parallel_wall() {
        let k = phone_k();
        let data = render_plane(256, 192, &k, DVec3::new(0.0, 0.0, -1.0), -2.0);
        let img = DepthImage::new(&data, 256, 192, 512).unwrap();
        let s = sample_surface(
            &img,
            &k,
            DisplayRotation::Deg0,
            Convention::Arcore,
            &Pose::IDENTITY,
            None,
        )
        .unwrap();
        assert_eq!(s.pixel, [128, 96]);
        assert_eq!(s.depth_m, 2.0);
        let ray = k.ray(128.0, 96.0);
        assert!((s.distance_m - 2.0 * ray.length()).abs() < 1e-12);
        // ARCore camera looks along −Z: the point is in front, the normal points back (+Z).
        assert!((s.camera_point - DVec3::new(2.0 * ray.x, -2.0 * ray.y, -2.0)).length() < 1e-12);
        assert!(angle_deg(s.normal, DVec3::Z) < 1e-6);
    }

    /// Largest normal error (degrees) over tilt axes X, Y, X+Y and both signs.
    fn worst_tilt_error(dist: f64, pixel: (u32, u32)) -> f64 {
        let k = phone_k();
        let mut worst: f64 = 0.0;
        for axis in [DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0).normalize()] {
            for sign in [1.0, -1.0] {
                let n = DQuat::from_axis_angle(axis, sign * 30f64.to_radians()) * DVec3::NEG_Z;
                let data = render_plane(256, 192, &k, n, -dist);
                let img = DepthImage::new(&data, 256, 192, 512).unwrap();
                let (p, est) = img.optical_sample(&k, pixel.0, pixel.1).unwrap();
                // The point lies on the plane to within the rounding of its depth.
                assert!((n.dot(p) + dist).abs() <= 0.0005 * n.dot(p / p.z).abs() + 1e-12);
                worst = worst.max(angle_deg(est, n));
            }
        }
        worst
    }

    #[test]
    fn plane_tilted_30_degrees_gives_its_normal_within_half_a_degree() {
        // Camera facing the plane, sample at the centre. Below ~1.5 m the 1 mm quantisation
        // of a 256×192 image dominates (1.2° at 1 m); see README "Accuracy".
        for dist in [1.5, 2.0, 3.0, 4.0, 10.0] {
            let err = worst_tilt_error(dist, (128, 96));
            assert!(err < 0.5, "{dist} m: {err}°");
        }
    }

    #[test]
    fn off_centre_pixels_of_a_tilted_plane() {
        // Near the image corners the plane is seen more obliquely; quantisation costs more.
        for dist in [2.0, 3.0, 4.0] {
            for pixel in [(40, 30), (220, 170)] {
                let err = worst_tilt_error(dist, pixel);
                assert!(err < 1.1, "{dist} m {pixel:?}: {err}°");
            }
        }
        // Without quantisation (a far plane: sub-mm relative error) the estimate is exact to 0.05°.
        assert!(worst_tilt_error(30.0, (40, 30)) < 0.05);
    }

    #[test]
    fn invalid_depth_is_typed() {
        let k = phone_k();
        let mut data = vec![2000u16; 256 * 192];
        let idx = 96 * 256 + 128;
        data[idx] = 0;
        let img = DepthImage::new(&data, 256, 192, 512).unwrap();
        assert_eq!(
            img.optical_sample(&k, 128, 96),
            Err(InvalidDepth::NoDepth { x: 128, y: 96 })
        );
        assert_eq!(
            img.optical_sample(&k, 256, 0),
            Err(InvalidDepth::OutOfBounds { x: 256, y: 0 })
        );
        // Centre far from every neighbour (a pole in front of a wall): all rejected by the 20 % rule.
        data[idx] = 1000;
        let img = DepthImage::new(&data, 256, 192, 512).unwrap();
        assert_eq!(
            img.optical_sample(&k, 128, 96),
            Err(InvalidDepth::NoValidNeighbours { x: 128, y: 96 })
        );
        // 19 % off is kept.
        let mut data = vec![2000u16; 256 * 192];
        data[idx] = 1681; // 2000 is 19 % above 1681
        let img = DepthImage::new(&data, 256, 192, 512).unwrap();
        assert!(img.optical_sample(&k, 128, 96).is_ok());
        let err = sample_surface(
            &img,
            &Intrinsics { fx: 0.0, ..k },
            DisplayRotation::Deg0,
            Convention::Unity,
            &Pose::IDENTITY,
            None,
        );
        assert!(matches!(
            err,
            Err(Error::InvalidArgument {
                name: "intrinsics",
                ..
            })
        ));
    }

    #[test]
    fn outliers_in_the_window_are_ignored() {
        let k = phone_k();
        let n = DQuat::from_rotation_y(30f64.to_radians()) * DVec3::NEG_Z;
        let mut data = render_plane(256, 192, &k, n, -2.0);
        // A thin pole much closer than the wall covers one column of the window.
        for v in 94..=98 {
            data[v * 256 + 130] = 900;
        }
        let img = DepthImage::new(&data, 256, 192, 512).unwrap();
        let (_, est) = img.optical_sample(&k, 128, 96).unwrap();
        // The one-sided window costs some accuracy (quantisation no longer cancels), but the
        // pole (a 55 % jump) does not drag the normal (it would by tens of degrees).
        assert!(angle_deg(est, n) < 1.0, "{}", angle_deg(est, n));
    }

    #[test]
    fn each_display_rotation_and_convention_maps_the_ray_into_the_world() {
        // A wall 3 m in front of the camera, perpendicular to its view direction. A sensor
        // pixel right of the principal point lies, on the display, to the right (0°),
        // below (90°), left (180°) or above (270°) the centre.
        let k = Intrinsics {
            fx: 200.0,
            fy: 200.0,
            cx: 128.0,
            cy: 96.0,
        };
        let data = vec![3000u16; 256 * 192];
        let img = DepthImage::new(&data, 256, 192, 512).unwrap();
        let a = (148.0 - 128.0) / 200.0 * 3.0; // 0.3 m off-axis at 3 m
        for conv in [Convention::Unity, Convention::Arcore] {
            let fz = conv.camera_forward().z * 3.0;
            for (deg, expect) in [
                (0, DVec3::new(a, 0.0, fz)),
                (90, DVec3::new(0.0, -a, fz)),
                (180, DVec3::new(-a, 0.0, fz)),
                (270, DVec3::new(0.0, a, fz)),
            ] {
                let rot = DisplayRotation::from_degrees(deg).unwrap();
                let s =
                    sample_surface(&img, &k, rot, conv, &Pose::IDENTITY, Some((148, 96))).unwrap();
                assert!(
                    (s.point - expect).length() < 1e-12,
                    "{conv:?} {deg}: {} vs {expect}",
                    s.point
                );
                assert!(angle_deg(s.normal, -conv.camera_forward()) < 1e-9);
                assert!((s.distance_m - (9.0 + a * a).sqrt()).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn tilted_wall_seen_from_a_moved_camera() {
        // World wall (given in Unity coordinates): through (0, 0, 4), normal tilted 30° about
        // +Y, facing −Z. The camera stands at (0.5, 1.6, 0.3), turned 20° about +Y. The same
        // physical scene in ARCore coordinates must give the same sensor image and the same
        // (converted) answer, for every display rotation.
        let (u, a) = (Convention::Unity, Convention::Arcore);
        let wall_n_u = DQuat::from_rotation_y(30f64.to_radians()) * DVec3::NEG_Z;
        let wall_p_u = DVec3::new(0.0, 0.0, 4.0);
        let pose_u = Pose::new(
            DVec3::new(0.5, 1.6, 0.3),
            DQuat::from_rotation_y(20f64.to_radians()),
        );
        let k = phone_k();
        for rot in [
            DisplayRotation::Deg0,
            DisplayRotation::Deg90,
            DisplayRotation::Deg180,
            DisplayRotation::Deg270,
        ] {
            let mut images = Vec::new();
            let mut samples = Vec::new();
            for conv in [u, a] {
                let wall_n = u.convert_vector(wall_n_u, conv);
                let wall_d = wall_n.dot(u.convert_vector(wall_p_u, conv));
                let pose = u.convert_pose(pose_u, conv);
                // The plane in the sensor optical frame.
                let n_cam = pose.rotation.inverse() * wall_n;
                let n_sensor = rot.sensor_from_display(conv.optical_from_camera(n_cam));
                let d_sensor = wall_d - wall_n.dot(pose.position);
                let data = render_plane(256, 192, &k, n_sensor, d_sensor);
                let img = DepthImage::new(&data, 256, 192, 512).unwrap();
                let s = sample_surface(&img, &k, rot, conv, &pose, None).unwrap();
                let err = angle_deg(s.normal, wall_n);
                assert!(err < 0.5, "{conv:?} {rot:?}: {err}°");
                // On the plane to within the millimetre quantisation.
                assert!((wall_n.dot(s.point) - wall_d).abs() < 1e-3);
                // Along the centre pixel's ray from the camera.
                let ray = pose.transform_vector(
                    conv.camera_from_optical(rot.display_from_sensor(k.ray(128.0, 96.0))),
                );
                assert!(angle_deg(s.point - pose.position, ray) < 1e-9);
                images.push(data);
                samples.push(s);
            }
            assert_eq!(
                images[0], images[1],
                "{rot:?}: the physical camera sees one image"
            );
            assert!((u.convert_vector(samples[0].point, a) - samples[1].point).length() < 1e-9);
            assert!((u.convert_vector(samples[0].normal, a) - samples[1].normal).length() < 1e-9);
        }
    }
}
