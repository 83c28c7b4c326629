//! Coordinate conventions, poses and display rotation.
//!
//! * `unity`: left-handed, +Y up, the camera looks along its local +Z, +X right.
//! * `arcore`: right-handed (OpenGL), +Y up, the camera looks along its local −Z, +X right.
//! * optical (computer vision): camera x right, y down, z forward; right-handed.
//!
//! Unity and ARCore differ by the reflection `S = diag(1, 1, −1)` applied to both the
//! world and the camera frame (what AR Foundation does): a position `p` becomes `S p`
//! and a rotation `R` becomes `S R S`, i.e. the quaternion `(x, y, z, w)` becomes
//! `(−x, −y, z, w)`. A reflection is its own inverse, so the same formula converts both ways.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::Error;

/// A world-from-camera pose: where the camera is and how it is turned, in one convention.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Camera position in world coordinates (metres).
    pub position: DVec3,
    /// Rotation taking camera-frame vectors to world-frame vectors (unit quaternion).
    pub rotation: DQuat,
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    /// The camera at the origin, axes aligned with the world.
    pub const IDENTITY: Pose = Pose {
        position: DVec3::ZERO,
        rotation: DQuat::IDENTITY,
    };

    /// A pose from position and rotation.
    pub fn new(position: DVec3, rotation: DQuat) -> Self {
        Self { position, rotation }
    }

    /// Maps a point from the camera frame to the world frame.
    pub fn transform_point(&self, p: DVec3) -> DVec3 {
        self.rotation * p + self.position
    }

    /// Maps a direction from the camera frame to the world frame.
    pub fn transform_vector(&self, v: DVec3) -> DVec3 {
        self.rotation * v
    }

    /// The inverse pose (camera-from-world).
    pub fn inverse(&self) -> Pose {
        let r = self.rotation.inverse();
        Pose {
            position: -(r * self.position),
            rotation: r,
        }
    }

    /// Checks that every number is finite and the quaternion is non-zero, and returns
    /// the pose with a normalised quaternion. `name` is the argument named in the error.
    pub fn validated(self, name: &'static str) -> Result<Pose, Error> {
        if !self.position.is_finite() {
            return Err(Error::arg(name, "position is not finite"));
        }
        let len2 = self.rotation.length_squared();
        if !len2.is_finite() || len2 < 1e-12 {
            return Err(Error::arg(
                name,
                "rotation is not a finite non-zero quaternion",
            ));
        }
        // Only renormalise when needed: keeps the hot path branch-cheap and exact for unit input.
        let rotation = if (len2 - 1.0).abs() > 1e-12 {
            self.rotation * (1.0 / len2.sqrt())
        } else {
            self.rotation
        };
        Ok(Pose {
            position: self.position,
            rotation,
        })
    }
}

/// The coordinate convention of the poses a session receives and returns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Convention {
    /// Left-handed, +Y up, camera looks along local +Z, +X right.
    #[default]
    Unity,
    /// Right-handed (OpenGL), +Y up, camera looks along local −Z, +X right.
    Arcore,
}

/// The Unity↔ARCore reflection of a vector: `diag(1, 1, −1)`.
fn reflect_z(v: DVec3) -> DVec3 {
    DVec3::new(v.x, v.y, -v.z)
}

/// The Unity↔ARCore reflection of a rotation: `S R S` as a quaternion.
fn reflect_z_rotation(q: DQuat) -> DQuat {
    DQuat::from_xyzw(-q.x, -q.y, q.z, q.w)
}

impl Convention {
    /// The convention's name as used in the session config (`"unity"` or `"arcore"`).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Unity => "unity",
            Self::Arcore => "arcore",
        }
    }

    /// The direction the camera looks along, in its own frame: +Z (Unity) or −Z (ARCore).
    pub fn camera_forward(&self) -> DVec3 {
        match self {
            Self::Unity => DVec3::Z,
            Self::Arcore => DVec3::NEG_Z,
        }
    }

    /// The world's up direction (+Y in both conventions).
    pub fn world_up(&self) -> DVec3 {
        DVec3::Y
    }

    /// Converts a point or direction from this convention to `to`.
    pub fn convert_vector(&self, v: DVec3, to: Convention) -> DVec3 {
        if *self == to { v } else { reflect_z(v) }
    }

    /// Converts a rotation (world-from-camera or world-from-object) from this convention to `to`.
    pub fn convert_rotation(&self, q: DQuat, to: Convention) -> DQuat {
        if *self == to {
            q
        } else {
            reflect_z_rotation(q)
        }
    }

    /// Converts a world-from-camera pose from this convention to `to`.
    pub fn convert_pose(&self, pose: Pose, to: Convention) -> Pose {
        Pose {
            position: self.convert_vector(pose.position, to),
            rotation: self.convert_rotation(pose.rotation, to),
        }
    }

    /// Maps a vector given in the optical camera frame (x right, y down, z forward)
    /// to this convention's camera frame.
    pub fn camera_from_optical(&self, v: DVec3) -> DVec3 {
        match self {
            Self::Unity => DVec3::new(v.x, -v.y, v.z),
            Self::Arcore => DVec3::new(v.x, -v.y, -v.z),
        }
    }

    /// Maps a vector given in this convention's camera frame to the optical camera frame.
    pub fn optical_from_camera(&self, v: DVec3) -> DVec3 {
        // Both maps are diagonal sign flips, hence their own inverses.
        self.camera_from_optical(v)
    }

    /// The world-from-optical-camera pose (camera x right, y down, z forward).
    ///
    /// The optical frame is right-handed, so the world frame of the result must be too:
    /// for `arcore` it is the ARCore world unchanged; for `unity` it is the Unity world
    /// with Z negated (which is the ARCore world). The camera's position is therefore
    /// `Convention::Unity.convert_vector(p, Arcore)` for Unity poses.
    pub fn to_optical(&self, pose: Pose) -> Pose {
        let arcore = self.convert_pose(pose, Convention::Arcore);
        // ARCore camera (x right, y up, z back) → optical (x right, y down, z forward) is Rx(π).
        Pose {
            position: arcore.position,
            rotation: arcore.rotation * DQuat::from_xyzw(1.0, 0.0, 0.0, 0.0),
        }
    }

    /// The inverse of [`Convention::to_optical`].
    pub fn from_optical(&self, optical: Pose) -> Pose {
        let arcore = Pose {
            position: optical.position,
            rotation: optical.rotation * DQuat::from_xyzw(-1.0, 0.0, 0.0, 0.0),
        };
        Convention::Arcore.convert_pose(arcore, *self)
    }
}

/// Clockwise rotation (degrees) from the depth sensor image to the display.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub enum DisplayRotation {
    /// Sensor image and display agree.
    #[default]
    Deg0,
    /// The display is the sensor image turned 90° clockwise.
    Deg90,
    /// The display is the sensor image turned 180°.
    Deg180,
    /// The display is the sensor image turned 270° clockwise (90° counter-clockwise).
    Deg270,
}

impl DisplayRotation {
    /// Parses 0, 90, 180 or 270 degrees.
    pub fn from_degrees(degrees: i32) -> Result<Self, Error> {
        match degrees {
            0 => Ok(Self::Deg0),
            90 => Ok(Self::Deg90),
            180 => Ok(Self::Deg180),
            270 => Ok(Self::Deg270),
            other => Err(Error::arg(
                "display_rotation",
                format!("{other} is not one of 0, 90, 180, 270"),
            )),
        }
    }

    /// The rotation in degrees.
    pub fn degrees(&self) -> i32 {
        match self {
            Self::Deg0 => 0,
            Self::Deg90 => 90,
            Self::Deg180 => 180,
            Self::Deg270 => 270,
        }
    }

    /// Maps a vector from the sensor's optical frame to the display-oriented optical frame.
    ///
    /// Turning the image clockwise by θ on screen (x right, y down) maps `(x, y)` to
    /// `(x cos θ − y sin θ, x sin θ + y cos θ)`: e.g. at 90° the sensor's right becomes the
    /// display's down. Depth (z) is unchanged. Exact (no trigonometry) for the four angles.
    pub fn display_from_sensor(&self, v: DVec3) -> DVec3 {
        match self {
            Self::Deg0 => v,
            Self::Deg90 => DVec3::new(-v.y, v.x, v.z),
            Self::Deg180 => DVec3::new(-v.x, -v.y, v.z),
            Self::Deg270 => DVec3::new(v.y, -v.x, v.z),
        }
    }

    /// The inverse of [`DisplayRotation::display_from_sensor`].
    pub fn sensor_from_display(&self, v: DVec3) -> DVec3 {
        match self {
            Self::Deg0 => v,
            Self::Deg90 => DVec3::new(v.y, -v.x, v.z),
            Self::Deg180 => DVec3::new(-v.x, -v.y, v.z),
            Self::Deg270 => DVec3::new(-v.y, v.x, v.z),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn arb_pose() -> impl Strategy<Value = Pose> {
        (
            prop::array::uniform3(-100.0f64..100.0),
            prop::array::uniform4(-1.0f64..1.0),
        )
            .prop_filter_map("non-zero quaternion", |(p, q)| {
                let q = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
                (q.length() > 0.1).then(|| Pose::new(DVec3::from_array(p), q.normalize()))
            })
    }

    fn close_pose(a: Pose, b: Pose) -> bool {
        (a.position - b.position).length() < 1e-9 && a.rotation.dot(b.rotation).abs() > 1.0 - 1e-12
    }

    #[test]
    fn unity_forward_is_arcore_forward_after_conversion() {
        // A Unity camera rotated 90° about +Y (left-handed: +Z turns to +X) looks along world +X.
        let unity = Pose::new(
            DVec3::new(1.0, 2.0, 3.0),
            DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2),
        );
        let fwd_unity = unity.transform_vector(Convention::Unity.camera_forward());
        assert!((fwd_unity - DVec3::X).length() < 1e-12);
        let arcore = Convention::Unity.convert_pose(unity, Convention::Arcore);
        assert_eq!(arcore.position, DVec3::new(1.0, 2.0, -3.0));
        let fwd_arcore = arcore.transform_vector(Convention::Arcore.camera_forward());
        // The same physical direction, expressed in the ARCore world.
        assert!(
            (fwd_arcore - Convention::Unity.convert_vector(fwd_unity, Convention::Arcore)).length()
                < 1e-12
        );
        // Up stays up and right stays right.
        let up = arcore.transform_vector(DVec3::Y);
        assert!((up - DVec3::Y).length() < 1e-12);
    }

    #[test]
    fn optical_axes() {
        for conv in [Convention::Unity, Convention::Arcore] {
            let opt = conv.to_optical(Pose::IDENTITY);
            // Optical z is the camera's forward, optical y is down.
            let fwd = opt.transform_vector(DVec3::Z);
            let down = opt.transform_vector(DVec3::Y);
            let expect_fwd = conv.convert_vector(conv.camera_forward(), Convention::Arcore);
            assert!((fwd - expect_fwd).length() < 1e-12, "{conv:?}");
            assert!((down - DVec3::NEG_Y).length() < 1e-12);
            assert!((conv.camera_from_optical(DVec3::Z) - conv.camera_forward()).length() < 1e-12);
            assert_eq!(conv.camera_from_optical(DVec3::X), DVec3::X);
            assert_eq!(conv.camera_from_optical(DVec3::Y), DVec3::NEG_Y);
        }
    }

    #[test]
    fn display_rotation_90_maps_sensor_right_to_display_down() {
        let r = DisplayRotation::from_degrees(90).unwrap();
        assert_eq!(r.display_from_sensor(DVec3::X), DVec3::Y);
        assert_eq!(r.display_from_sensor(DVec3::Y), DVec3::NEG_X);
        assert!(DisplayRotation::from_degrees(45).is_err());
        for deg in [0, 90, 180, 270] {
            let r = DisplayRotation::from_degrees(deg).unwrap();
            assert_eq!(r.degrees(), deg);
            // Agrees with a rotation about optical z by +deg.
            let v = DVec3::new(0.3, -0.7, 1.9);
            let q = DQuat::from_rotation_z((deg as f64).to_radians());
            assert!((r.display_from_sensor(v) - q * v).length() < 1e-12);
        }
    }

    proptest! {
        #[test]
        fn convention_round_trip(pose in arb_pose()) {
            for (a, b) in [(Convention::Unity, Convention::Arcore), (Convention::Arcore, Convention::Unity)] {
                let back = b.convert_pose(a.convert_pose(pose, b), a);
                prop_assert!(close_pose(back, pose));
            }
        }

        #[test]
        fn optical_round_trip(pose in arb_pose()) {
            for conv in [Convention::Unity, Convention::Arcore] {
                prop_assert!(close_pose(conv.from_optical(conv.to_optical(pose)), pose));
            }
        }

        #[test]
        fn conversion_preserves_geometry(pose in arb_pose(), v in prop::array::uniform3(-5.0f64..5.0)) {
            // Transforming then converting equals converting then transforming.
            let v = DVec3::from_array(v);
            let u = Convention::Unity;
            let a = Convention::Arcore;
            let world = u.convert_vector(pose.transform_point(v), a);
            let converted = u.convert_pose(pose, a).transform_point(u.convert_vector(v, a));
            prop_assert!((world - converted).length() < 1e-9);
            // An optical-frame point maps to the same world point both ways.
            for conv in [u, a] {
                let via_camera = conv.convert_vector(pose.transform_point(conv.camera_from_optical(v)), a);
                let via_optical = conv.to_optical(pose).transform_point(v);
                prop_assert!((via_camera - via_optical).length() < 1e-9);
            }
        }

        #[test]
        fn display_rotation_round_trip(v in prop::array::uniform3(-5.0f64..5.0), k in 0i32..4) {
            let r = DisplayRotation::from_degrees(k * 90).unwrap();
            let v = DVec3::from_array(v);
            prop_assert_eq!(r.sensor_from_display(r.display_from_sensor(v)), v);
        }
    }
}
