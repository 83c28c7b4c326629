//! The pose messages evo reads from bags, as both serializations decode them (CDR for
//! ROS 2 in [`crate::rosbag`], the ROS 1 serialization in [`crate::ros1`]), and the messages
//! of one topic as a bag's reader hands them over.

use glam::{DQuat, DVec3};
use serde::Deserialize;

/// A pose message type evo reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoseMessage {
    /// `geometry_msgs/msg/PoseStamped`.
    PoseStamped,
    /// `geometry_msgs/msg/PoseWithCovarianceStamped`.
    PoseWithCovarianceStamped,
    /// `geometry_msgs/msg/TransformStamped`.
    TransformStamped,
    /// `geometry_msgs/msg/PointStamped` (no rotation: the unit quaternion, as evo).
    PointStamped,
    /// `nav_msgs/msg/Odometry` (its pose).
    Odometry,
}

impl PoseMessage {
    /// The message type of a ROS 2 type name (`geometry_msgs/msg/PoseStamped`; the ROS 1
    /// spelling without `msg/` too); `None` for a type evo does not read.
    pub fn from_type_name(name: &str) -> Option<Self> {
        match name.replace("/msg/", "/").as_str() {
            "geometry_msgs/PoseStamped" => Some(Self::PoseStamped),
            "geometry_msgs/PoseWithCovarianceStamped" => Some(Self::PoseWithCovarianceStamped),
            "geometry_msgs/TransformStamped" => Some(Self::TransformStamped),
            "geometry_msgs/PointStamped" => Some(Self::PointStamped),
            "nav_msgs/Odometry" => Some(Self::Odometry),
            _ => None,
        }
    }
}

/// How a bag's messages are serialized.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Encoding {
    /// ROS 2: CDR with its 4-byte encapsulation header.
    #[default]
    Cdr,
    /// ROS 1: little-endian, unaligned, no header; `std_msgs/Header` has a `seq`.
    Ros1,
}

#[derive(Deserialize)]
pub(crate) struct Time {
    pub(crate) sec: i32,
    pub(crate) nanosec: u32,
}

impl Time {
    /// The stamp in nanoseconds (`sec` as evo reads it: signed).
    pub(crate) fn ns(&self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }
}

#[derive(Deserialize)]
pub(crate) struct Header {
    pub(crate) stamp: Time,
    pub(crate) frame_id: String,
}

#[derive(Deserialize)]
pub(crate) struct Vector {
    pub(crate) x: f64,
    pub(crate) y: f64,
    pub(crate) z: f64,
}

#[derive(Deserialize)]
pub(crate) struct Quaternion {
    pub(crate) x: f64,
    pub(crate) y: f64,
    pub(crate) z: f64,
    pub(crate) w: f64,
}

#[derive(Deserialize)]
pub(crate) struct Pose {
    pub(crate) position: Vector,
    pub(crate) orientation: Quaternion,
}

pub(crate) fn vector(v: Vector) -> DVec3 {
    DVec3::new(v.x, v.y, v.z)
}

pub(crate) fn quaternion(q: Quaternion) -> DQuat {
    DQuat::from_xyzw(q.x, q.y, q.z, q.w)
}

/// `PoseStamped`, and the leading fields of `PoseWithCovarianceStamped` (its covariance
/// follows the pose and is not read).
#[derive(Deserialize)]
pub(crate) struct StampedPose {
    pub(crate) header: Header,
    pub(crate) pose: Pose,
}

#[derive(Deserialize)]
pub(crate) struct StampedTransform {
    pub(crate) header: Header,
    pub(crate) child_frame_id: String,
    pub(crate) translation: Vector,
    pub(crate) rotation: Quaternion,
}

#[derive(Deserialize)]
pub(crate) struct StampedPoint {
    pub(crate) header: Header,
    pub(crate) point: Vector,
}

/// The leading fields of `nav_msgs/msg/Odometry` (covariance and twist follow).
#[derive(Deserialize)]
pub(crate) struct Odometry {
    pub(crate) header: Header,
    pub(crate) _child_frame_id: String,
    pub(crate) pose: Pose,
}

/// One decoded pose message.
#[derive(Debug, Clone, PartialEq)]
pub struct StampedPoseValue {
    /// The header's stamp (ns).
    pub stamp_ns: i64,
    /// The position.
    pub position: DVec3,
    /// The orientation, as written (not normalised).
    pub orientation: DQuat,
    /// The header's frame.
    pub frame_id: String,
}

/// The messages of one topic of a bag: its type name and each message's CDR bytes, in the
/// bag's order.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TopicMessages {
    /// The ROS type name (`geometry_msgs/msg/PoseStamped`).
    pub type_name: String,
    /// How the messages are serialized.
    pub encoding: Encoding,
    /// The messages' bytes.
    pub messages: Vec<Vec<u8>>,
}
