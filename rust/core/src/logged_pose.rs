//! The poses a session logs (start, midpoints, endpoints) with their frame and path length:
//! what the session keeps, persists and draws.

use serde::{Deserialize, Serialize};

use crate::convention::Pose;

/// A logged pose: the start pose, a midpoint or an endpoint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LoggedPose {
    /// Timestamp (ns).
    pub t_ns: i64,
    /// Frame number counted from the start call (frame 0).
    pub frame: u32,
    /// World-from-camera pose.
    pub pose: Pose,
    /// Path length from the start through every frame up to this one (metres).
    pub path_m: f64,
}
