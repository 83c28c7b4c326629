//! Guidance to what is out of view: where a target is on the screen, or the point on an
//! ellipse inside the screen's edge in its direction (the paper's off-screen indicators).
//!
//! A target at `(x, y, z)` in the camera's frame (x right, y up, z along the view
//! direction) with `z > 0` projects to `(w/2 + f·x/z, h/2 − f·y/z)`, `f = (h/2) / tan(vfov/2)`
//! (square pixels; origin top-left, y down). On the screen it is shown there; otherwise it is
//! pinned to the ellipse with semi-axes `w/2 − margin` and `h/2 − margin` around the centre
//! in the direction `d = (f·x, −f·y)`, so a target behind the camera keeps its true side
//! (never mirrored). The angle is `atan2(d_y, d_x)` (0 right, positive clockwise on screen).

use glam::DVec3;

use crate::{Convention, Error, Pose};

/// Where one target is shown.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Guide {
    /// Whether the target projects onto the screen (in front of the camera).
    pub on_screen: bool,
    /// Pixel x (from the left): the projection, or the pinned point on the ellipse.
    pub x_px: f64,
    /// Pixel y (from the top).
    pub y_px: f64,
    /// `atan2(d_y, d_x)`, `d = (f·x, −f·y)`: 0 points right, positive clockwise on screen.
    pub angle_rad: f64,
    /// The target's distance from the camera (m).
    pub distance_m: f64,
}

/// A camera and its screen, checked once; [`ScreenView::guide`] is then pure arithmetic
/// (no allocation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScreenView {
    /// Camera-from-world.
    camera_from_world: Pose,
    /// −1 when the camera looks along its local −Z (ARCore), else 1.
    forward_sign: f64,
    f: f64,
    width: f64,
    height: f64,
    semi_x: f64,
    semi_y: f64,
}

impl ScreenView {
    /// `camera` is the display-oriented camera pose (world-from-camera in `convention`),
    /// `vfov_deg` the vertical field of view of the screen (0…180, exclusive), the screen
    /// `width_px` × `height_px` (> 0), `margin_px` the ellipse's distance from the edges
    /// (0 ≤ margin < half the shorter side). Errors name the argument.
    pub fn new(
        camera: Pose,
        convention: Convention,
        vfov_deg: f64,
        width_px: i32,
        height_px: i32,
        margin_px: f64,
    ) -> Result<Self, Error> {
        let camera = camera.validated("camera")?;
        if !(vfov_deg.is_finite() && vfov_deg > 0.0 && vfov_deg < 180.0) {
            return Err(Error::arg(
                "vfov_deg",
                format!("{vfov_deg} is not an angle between 0 and 180 degrees (exclusive)"),
            ));
        }
        if width_px <= 0 || height_px <= 0 {
            return Err(Error::arg(
                "width_px/height_px",
                format!("the screen is {width_px}x{height_px}; both must be positive"),
            ));
        }
        let (width, height) = (f64::from(width_px), f64::from(height_px));
        let half_short = 0.5 * width.min(height);
        if !(margin_px.is_finite() && margin_px >= 0.0 && margin_px < half_short) {
            return Err(Error::arg(
                "margin_px",
                format!("{margin_px} is not ≥ 0 and below half the shorter side ({half_short})"),
            ));
        }
        Ok(Self {
            camera_from_world: camera.inverse(),
            forward_sign: convention.camera_forward().z,
            f: 0.5 * height / (0.5 * vfov_deg.to_radians()).tan(),
            width,
            height,
            semi_x: 0.5 * width - margin_px,
            semi_y: 0.5 * height - margin_px,
        })
    }

    /// The focal length in pixels, `(height/2) / tan(vfov/2)`.
    pub fn focal_px(&self) -> f64 {
        self.f
    }

    /// A world point in the camera's frame of the module docs (x right, y up, z along the
    /// view direction).
    pub fn to_camera(&self, world: DVec3) -> DVec3 {
        let c = self.camera_from_world.transform_point(world);
        DVec3::new(c.x, c.y, self.forward_sign * c.z)
    }

    /// Where `target` (a world point) is shown.
    pub fn guide(&self, target: DVec3) -> Guide {
        let c = self.to_camera(target);
        let distance_m = c.length();
        let (cx, cy) = (0.5 * self.width, 0.5 * self.height);
        let (mut dx, mut dy) = (self.f * c.x, -self.f * c.y);
        if c.z > 0.0 {
            let (u, v) = (cx + dx / c.z, cy + dy / c.z);
            if (0.0..=self.width).contains(&u) && (0.0..=self.height).contains(&v) {
                return Guide {
                    on_screen: true,
                    x_px: u,
                    y_px: v,
                    angle_rad: dy.atan2(dx),
                    distance_m,
                };
            }
        }
        if dx == 0.0 && dy == 0.0 {
            // On the view axis (straight behind, or at the camera): no side; point down.
            dy = 1.0;
            dx = 0.0;
        }
        let s = 1.0 / ((dx / self.semi_x).powi(2) + (dy / self.semi_y).powi(2)).sqrt();
        Guide {
            on_screen: false,
            x_px: cx + s * dx,
            y_px: cy + s * dy,
            angle_rad: dy.atan2(dx),
            distance_m,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use proptest::prelude::*;
    use std::f64::consts::FRAC_PI_2;

    const CONVENTIONS: [Convention; 2] = [Convention::Unity, Convention::Arcore];

    /// A world point at camera-frame `(x, y, z)` (z along the view) for a camera `pose`.
    fn world_of(pose: &Pose, convention: Convention, c: DVec3) -> DVec3 {
        let local = DVec3::new(c.x, c.y, convention.camera_forward().z * c.z);
        pose.transform_point(local)
    }

    fn view(pose: Pose, convention: Convention) -> ScreenView {
        ScreenView::new(pose, convention, 60.0, 1080, 1920, 40.0).unwrap()
    }

    #[test]
    fn straight_ahead_is_the_centre_and_the_focal_length_is_analytic() {
        for convention in CONVENTIONS {
            let pose = Pose::new(DVec3::new(1.0, 1.5, -2.0), DQuat::from_rotation_y(0.7));
            let v = view(pose, convention);
            assert!((v.focal_px() - 960.0 / (30f64).to_radians().tan()).abs() < 1e-9);
            let g = v.guide(world_of(&pose, convention, DVec3::new(0.0, 0.0, 3.0)));
            assert!(g.on_screen);
            assert!((g.x_px - 540.0).abs() < 1e-9 && (g.y_px - 960.0).abs() < 1e-9);
            assert!((g.distance_m - 3.0).abs() < 1e-12);
            // Up in the camera is up on the screen (smaller y), right is right.
            let up = v.guide(world_of(&pose, convention, DVec3::new(0.1, 0.2, 3.0)));
            assert!(up.on_screen && up.y_px < 960.0 && up.x_px > 540.0);
            assert!((up.x_px - (540.0 + v.focal_px() * 0.1 / 3.0)).abs() < 1e-9);
            assert!((up.y_px - (960.0 - v.focal_px() * 0.2 / 3.0)).abs() < 1e-9);
        }
    }

    #[test]
    fn a_target_to_the_right_out_of_view_is_pinned_at_the_right_end_of_the_ellipse() {
        for convention in CONVENTIONS {
            let v = view(Pose::IDENTITY, convention);
            let g = v.guide(world_of(
                &Pose::IDENTITY,
                convention,
                DVec3::new(5.0, 0.0, 1.0),
            ));
            assert!(!g.on_screen);
            assert!((g.x_px - (1080.0 - 40.0)).abs() < 1e-9);
            assert!((g.y_px - 960.0).abs() < 1e-9);
            assert_eq!(g.angle_rad, 0.0);
            // Straight above, behind the camera: still at the top, angle −π/2.
            let g = v.guide(world_of(
                &Pose::IDENTITY,
                convention,
                DVec3::new(0.0, 1.0, -4.0),
            ));
            assert!(!g.on_screen);
            assert!((g.x_px - 540.0).abs() < 1e-9 && (g.y_px - 40.0).abs() < 1e-9);
            assert!((g.angle_rad + FRAC_PI_2).abs() < 1e-12);
            // Straight behind: pointing down.
            let g = v.guide(world_of(
                &Pose::IDENTITY,
                convention,
                DVec3::new(0.0, 0.0, -2.0),
            ));
            assert!(!g.on_screen && (g.y_px - (1920.0 - 40.0)).abs() < 1e-9);
        }
    }

    #[test]
    fn bad_arguments_name_the_argument() {
        let name = |r: Result<ScreenView, Error>| match r {
            Err(Error::InvalidArgument { name, .. }) => name,
            other => panic!("{other:?}"),
        };
        let p = Pose::IDENTITY;
        let c = Convention::Unity;
        assert_eq!(name(ScreenView::new(p, c, 0.0, 10, 10, 0.0)), "vfov_deg");
        assert_eq!(
            name(ScreenView::new(p, c, f64::NAN, 10, 10, 0.0)),
            "vfov_deg"
        );
        assert_eq!(name(ScreenView::new(p, c, 180.0, 10, 10, 0.0)), "vfov_deg");
        assert_eq!(
            name(ScreenView::new(p, c, 60.0, 0, 10, 0.0)),
            "width_px/height_px"
        );
        assert_eq!(name(ScreenView::new(p, c, 60.0, 10, 10, 5.0)), "margin_px");
        assert_eq!(name(ScreenView::new(p, c, 60.0, 10, 10, -1.0)), "margin_px");
        let bad = Pose::new(DVec3::new(f64::INFINITY, 0.0, 0.0), DQuat::IDENTITY);
        assert_eq!(name(ScreenView::new(bad, c, 60.0, 10, 10, 0.0)), "camera");
    }

    fn arb_pose() -> impl Strategy<Value = Pose> {
        (
            prop::array::uniform3(-5.0..5.0f64),
            prop::array::uniform4(-1.0..1.0f64),
        )
            .prop_filter("non-zero quaternion", |(_, q)| {
                q.iter().map(|v| v * v).sum::<f64>() > 0.01
            })
            .prop_map(|(p, q)| {
                Pose::new(
                    DVec3::from_array(p),
                    DQuat::from_xyzw(q[0], q[1], q[2], q[3]).normalize(),
                )
            })
    }

    proptest! {
        /// Unprojecting a pixel at a depth and projecting it back gives the pixel.
        #[test]
        fn projection_round_trip(pose in arb_pose(), arcore in any::<bool>(),
            u in 0.0..1080.0f64, v in 0.0..1920.0f64, z in 0.1..50.0f64) {
            let convention = CONVENTIONS[usize::from(arcore)];
            let view = view(pose, convention);
            let f = view.focal_px();
            let c = DVec3::new((u - 540.0) * z / f, -(v - 960.0) * z / f, z);
            let g = view.guide(world_of(&pose, convention, c));
            prop_assert!(g.on_screen);
            prop_assert!((g.x_px - u).abs() < 1e-6 && (g.y_px - v).abs() < 1e-6);
            prop_assert!((g.distance_m - c.length()).abs() < 1e-9 * (1.0 + c.length()));
        }

        /// Behind the camera, a target keeps its side: right stays right, up stays up, and
        /// the angle is that of (x, −y).
        #[test]
        fn behind_the_camera_keeps_its_side(pose in arb_pose(), arcore in any::<bool>(),
            x in -10.0..10.0f64, y in -10.0..10.0f64, z in -10.0..-0.01f64) {
            prop_assume!(x.abs() > 1e-3 && y.abs() > 1e-3);
            let convention = CONVENTIONS[usize::from(arcore)];
            let view = view(pose, convention);
            let g = view.guide(world_of(&pose, convention, DVec3::new(x, y, z)));
            prop_assert!(!g.on_screen);
            prop_assert_eq!(g.x_px > 540.0, x > 0.0);
            prop_assert_eq!(g.y_px < 960.0, y > 0.0);
            let expected = (-y).atan2(x);
            prop_assert!((g.angle_rad - expected).abs() < 1e-6);
        }

        /// An off-screen target lies on the ellipse, in the direction of d.
        #[test]
        fn off_screen_targets_are_pinned_to_the_ellipse(pose in arb_pose(),
            arcore in any::<bool>(), c in prop::array::uniform3(-20.0..20.0f64),
            margin in 0.0..500.0f64) {
            let convention = CONVENTIONS[usize::from(arcore)];
            let view = ScreenView::new(pose, convention, 60.0, 1080, 1920, margin).unwrap();
            let c = DVec3::from_array(c);
            prop_assume!(c.x.abs() + c.y.abs() > 1e-3);
            let g = view.guide(world_of(&pose, convention, c));
            let f = view.focal_px();
            let on = c.z > 0.0 && {
                let (u, v) = (540.0 + f * c.x / c.z, 960.0 - f * c.y / c.z);
                (0.0..=1080.0).contains(&u) && (0.0..=1920.0).contains(&v)
            };
            prop_assert_eq!(g.on_screen, on);
            if !on {
                let (ex, ey) = ((g.x_px - 540.0) / (540.0 - margin), (g.y_px - 960.0) / (960.0 - margin));
                prop_assert!((ex * ex + ey * ey - 1.0).abs() < 1e-9);
                // Parallel to d = (f·x, −f·y), same sense.
                let (dx, dy) = (f * c.x, -f * c.y);
                let (px, py) = (g.x_px - 540.0, g.y_px - 960.0);
                prop_assert!((px * dy - py * dx).abs() <= 1e-6 * (dx.hypot(dy) * px.hypot(py)));
                prop_assert!(px * dx + py * dy > 0.0);
            }
            prop_assert!((g.angle_rad - (-c.y).atan2(c.x)).abs() < 1e-6);
        }
    }
}
