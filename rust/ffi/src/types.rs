//! Plain `#[repr(C)]` structs that cross the C ABI (glam never does).

/// A pose: world-from-camera position (metres) and unit quaternion, in the
/// session's convention.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarPose {
    /// Position x.
    pub px: f64,
    /// Position y.
    pub py: f64,
    /// Position z.
    pub pz: f64,
    /// Quaternion x.
    pub qx: f64,
    /// Quaternion y.
    pub qy: f64,
    /// Quaternion z.
    pub qz: f64,
    /// Quaternion w.
    pub qw: f64,
}

/// Pinhole intrinsics of the depth image, in its pixels.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarIntrinsics {
    /// Focal length x.
    pub fx: f64,
    /// Focal length y.
    pub fy: f64,
    /// Principal point x.
    pub cx: f64,
    /// Principal point y.
    pub cy: f64,
}

/// What `stop` reports about the recording.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarSummary {
    /// Number of `frame` calls (start and stop are not frames).
    pub frames: u32,
    /// Midpoints reached.
    pub midpoints: u32,
    /// Completed sub-trajectories (endpoint reached).
    pub subtrajectories: u32,
    /// Midpoints with a valid depth sample.
    pub depth_samples: u32,
    /// Seconds from the start to the stop timestamp.
    pub duration_s: f64,
    /// Path length through start, every frame and stop pose (metres).
    pub length_m: f64,
    /// Mean distance along the ray of the valid depth samples (metres).
    pub mean_depth_m: f64,
}

/// A marker on a surface the camera faced in a bad sub-trajectory.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarMarker {
    /// Position x.
    pub px: f64,
    /// Position y.
    pub py: f64,
    /// Position z.
    pub pz: f64,
    /// Warning-sign rotation x (local +Y along the normal).
    pub qx: f64,
    /// Warning-sign rotation y.
    pub qy: f64,
    /// Warning-sign rotation z.
    pub qz: f64,
    /// Warning-sign rotation w.
    pub qw: f64,
    /// Surface normal x (towards the camera).
    pub nx: f64,
    /// Surface normal y.
    pub ny: f64,
    /// Surface normal z.
    pub nz: f64,
    /// 2 medium or 3 high.
    pub error_class: i32,
    /// Sub-trajectory number (from 0).
    pub subtrajectory: u32,
    /// Estimated error, in the results' unit (metres; degrees for `angle_deg`).
    pub error_m: f64,
}

/// A render-plan segment: a cylinder of `length` centred at `c`, local +Y along the path.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarSegment {
    /// Centre x.
    pub cx: f64,
    /// Centre y.
    pub cy: f64,
    /// Centre z.
    pub cz: f64,
    /// Rotation x.
    pub qx: f64,
    /// Rotation y.
    pub qy: f64,
    /// Rotation z.
    pub qz: f64,
    /// Rotation w.
    pub qw: f64,
    /// Length (metres).
    pub length: f64,
    /// Sub-trajectory number.
    pub subtrajectory: u32,
    /// Class of that sub-trajectory: 0 unknown, 1 low, 2 medium, 3 high.
    pub error_class: i32,
}

/// A render-plan joint (a sphere between segments).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarJoint {
    /// Position x.
    pub px: f64,
    /// Position y.
    pub py: f64,
    /// Position z.
    pub pz: f64,
    /// Sub-trajectory number.
    pub subtrajectory: u32,
    /// Class of that sub-trajectory: 0 unknown, 1 low, 2 medium, 3 high.
    pub error_class: i32,
}

/// A render-plan camera frustum (one per `frustum_spacing_m` of path).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarFrustum {
    /// Camera pose.
    pub pose: SitarPose,
    /// Sub-trajectory number.
    pub subtrajectory: u32,
    /// Class of that sub-trajectory: 0 unknown, 1 low, 2 medium, 3 high.
    pub error_class: i32,
}

/// The result of one sub-trajectory.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarSubtrajectoryResult {
    /// Estimated error in the results' unit (metres; degrees for `angle_deg`); NaN when no
    /// result window is near its start.
    pub error_m: f64,
    /// Sub-trajectory number (from 0).
    pub subtrajectory: u32,
    /// 0 unknown, 1 low, 2 medium, 3 high.
    pub error_class: i32,
}

/// What the camera saw at sub-trajectory `k`'s midpoint, how it moved, its depth, and the
/// likely causes of its error (`sitar_session_subtrajectory_evidence`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarEvidence {
    /// Sub-trajectory number (from 0).
    pub subtrajectory: u32,
    /// 1 when a camera image was given at its midpoint (else the image fields are 0).
    pub has_image: i32,
    /// Mean luminance (0…255).
    pub mean_brightness: f64,
    /// Luminance standard deviation.
    pub contrast_std: f64,
    /// Variance of the Laplacian (sharpness).
    pub laplacian_var: f64,
    /// FAST corners per 10 000 pixels (texture).
    pub corners_per_10k: f64,
    /// Share of saturated pixels (0…1).
    pub saturated_share: f64,
    /// Linear speed (m/s).
    pub linear_speed_m_s: f64,
    /// Angular speed (°/s).
    pub angular_speed_deg_s: f64,
    /// 1 when a depth image was given at its midpoint.
    pub depth_given: i32,
    /// 1 when the depth sample was valid.
    pub depth_valid: i32,
    /// Distance to the surface (m; 0 when not valid).
    pub distance_m: f64,
    /// Share of valid depth pixels in the 5×5 sample window (0…1).
    pub depth_valid_share: f64,
    /// Likely causes, a bit set: 1 low_texture, 2 dark, 4 overexposed, 8 blur, 16 fast_motion,
    /// 32 far_surface, 64 no_depth.
    pub causes: u32,
    /// Thumbnail width in display orientation (0 without an image).
    pub thumbnail_width: u32,
    /// Thumbnail height in display orientation (0 without an image).
    pub thumbnail_height: u32,
}

impl SitarEvidence {
    /// From the core's evidence and the thumbnail size.
    pub fn new(e: &sitar_core::Evidence, thumbnail: (u32, u32)) -> Self {
        let image = e.image.unwrap_or_default();
        Self {
            subtrajectory: e.index,
            has_image: i32::from(e.image.is_some()),
            mean_brightness: image.mean_brightness,
            contrast_std: image.contrast_std,
            laplacian_var: image.laplacian_var,
            corners_per_10k: image.corners_per_10k,
            saturated_share: image.saturated_share,
            linear_speed_m_s: e.motion.linear_speed_m_s,
            angular_speed_deg_s: e.motion.angular_speed_deg_s,
            depth_given: i32::from(e.depth.given),
            depth_valid: i32::from(e.depth.valid),
            distance_m: e.depth.distance_m,
            depth_valid_share: e.depth.valid_share,
            causes: e.causes.0,
            thumbnail_width: thumbnail.0,
            thumbnail_height: thumbnail.1,
        }
    }
}

/// Where a target is shown on the screen (`sitar_session_guide`): its projection, or, when it
/// is off the screen or behind the camera, the point on the ellipse inside the screen's edge
/// in its direction.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarGuide {
    /// 1 when the target projects onto the screen, else 0.
    pub on_screen: i32,
    /// Pixel x from the left.
    pub x_px: f64,
    /// Pixel y from the top.
    pub y_px: f64,
    /// `atan2(d_y, d_x)` with `d = (f·x, −f·y)`: 0 points right, positive clockwise on screen.
    pub angle_rad: f64,
    /// The target's distance from the camera (m).
    pub distance_m: f64,
}

impl From<sitar_core::Guide> for SitarGuide {
    fn from(g: sitar_core::Guide) -> Self {
        Self {
            on_screen: i32::from(g.on_screen),
            x_px: g.x_px,
            y_px: g.y_px,
            angle_rad: g.angle_rad,
            distance_m: g.distance_m,
        }
    }
}

/// A venue map cell in the current session's world frame (`sitar_session_venue_cells`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarVenueCell {
    /// Centre x.
    pub px: f64,
    /// Centre y.
    pub py: f64,
    /// Centre z.
    pub pz: f64,
    /// 0 path (where cameras were), 1 surface (what they looked at).
    pub kind: i32,
    /// 0 unknown, 1 low, 2 medium, 3 high.
    pub error_class: i32,
    /// Sessions with a sub-trajectory in the cell.
    pub sessions: u32,
    /// The cell's error: the 30 % trimmed mean of its sub-trajectories' errors (m).
    pub error_m: f64,
}

impl From<&sitar_core::venue::WorldCell> for SitarVenueCell {
    fn from(c: &sitar_core::venue::WorldCell) -> Self {
        Self {
            px: c.position.x,
            py: c.position.y,
            pz: c.position.z,
            kind: c.kind as i32,
            error_class: c.class as i32,
            sessions: c.sessions,
            error_m: c.error_m,
        }
    }
}

crate::descriptors::c_enum! {
    /// States of a background upload job (`SitarJobProgress.state`).
    pub enum SitarJobState as kotlin UploadState, csharp UploadState {
        /// Creating the server session.
        SITAR_JOB_STARTING = 0,
        /// Sending the recording.
        SITAR_JOB_UPLOADING = 1,
        /// Playback trials running on the server.
        SITAR_JOB_PLAYING = 2,
        /// The server computes the final estimate.
        SITAR_JOB_ESTIMATING = 3,
        /// Fetching the final results.
        SITAR_JOB_DOWNLOADING = 4,
        /// Final results are loaded into the session.
        SITAR_JOB_DONE = 5,
        /// Failed: see `error_code` and `sitar_upload_message`.
        SITAR_JOB_FAILED = 6,
        /// Cancelled by `sitar_upload_cancel`.
        SITAR_JOB_CANCELLED = 7,
    }
}

/// A snapshot of a background upload job.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SitarJobProgress {
    /// A `SitarJobState` value.
    pub state: i32,
    /// 0, or the status code the job failed with.
    pub error_code: i32,
    /// Overall progress 0 … 1 (upload 20 %, server work 80 %).
    pub progress: f64,
    /// Seconds until done as the server estimates them; negative if unknown.
    pub eta_s: f64,
    /// Recording bytes sent so far.
    pub bytes_sent: u64,
    /// Recording size in bytes.
    pub bytes_total: u64,
    /// Playback trials finished on the server.
    pub trials_done: u32,
    /// Playback trials planned.
    pub trials_total: u32,
    /// Incremented each time (progressive or final) results are loaded into the session.
    pub results_revision: u32,
    /// Trials behind the results loaded last (0 = none yet).
    pub results_trials: u32,
}

impl SitarPose {
    /// The core pose (validated and normalised by `sitar-core`, which names the argument).
    pub fn to_core(&self) -> sitar_core::Pose {
        sitar_core::Pose {
            position: glam::DVec3::new(self.px, self.py, self.pz),
            rotation: glam::DQuat::from_xyzw(self.qx, self.qy, self.qz, self.qw),
        }
    }

    /// The C struct of a core pose.
    pub fn from_core(p: &sitar_core::Pose) -> Self {
        SitarPose {
            px: p.position.x,
            py: p.position.y,
            pz: p.position.z,
            qx: p.rotation.x,
            qy: p.rotation.y,
            qz: p.rotation.z,
            qw: p.rotation.w,
        }
    }
}

impl From<&sitar_core::Summary> for SitarSummary {
    fn from(s: &sitar_core::Summary) -> Self {
        SitarSummary {
            frames: s.frames,
            midpoints: s.midpoints,
            subtrajectories: s.subtrajectories,
            depth_samples: s.depth_samples,
            duration_s: s.duration_s,
            length_m: s.length_m,
            mean_depth_m: s.mean_depth_m,
        }
    }
}

impl From<&sitar_core::Marker> for SitarMarker {
    fn from(m: &sitar_core::Marker) -> Self {
        SitarMarker {
            px: m.position.x,
            py: m.position.y,
            pz: m.position.z,
            qx: m.rotation.x,
            qy: m.rotation.y,
            qz: m.rotation.z,
            qw: m.rotation.w,
            nx: m.normal.x,
            ny: m.normal.y,
            nz: m.normal.z,
            error_class: m.class as i32,
            subtrajectory: m.subtrajectory,
            error_m: m.error_m,
        }
    }
}

impl SitarIntrinsics {
    /// The core intrinsics.
    pub fn to_core(&self) -> sitar_core::Intrinsics {
        sitar_core::Intrinsics {
            fx: self.fx,
            fy: self.fy,
            cx: self.cx,
            cy: self.cy,
        }
    }
}
