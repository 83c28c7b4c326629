//! # sitar-core: what the phone does in SiTAR, as pure Rust
//!
//! SiTAR finds where AR pose tracking goes wrong. On the user's phone a session
//! records the device pose every fifth camera frame, samples the depth image at each
//! sub-trajectory midpoint, and — once the backend has estimated the error of each
//! 10-frame window — colours the trajectory and places markers on the surfaces the camera
//! faced where the error was high. This crate is that logic with no I/O besides the
//! explicit session-folder [`Session::save`]/[`Session::load`]; the C ABI / JNI bridge
//! (`sitar-ffi`) wraps [`Session`] one-to-one.
//!
//! ## A session
//!
//! ```
//! use sitar_core::{DepthImage, DisplayRotation, Intrinsics, Pose, Session, SessionConfig};
//! use glam::{DQuat, DVec3};
//!
//! let config = SessionConfig::from_json(r#"{"convention": "unity"}"#)?;
//! let mut session = Session::new(config);
//! let pose = |i: i64| Pose::new(DVec3::new(0.02 * i as f64, 1.5, 0.0), DQuat::IDENTITY);
//! let dt = 33_333_333; // 30 fps, in nanoseconds
//!
//! // A wall 2 m in front of the camera, as a 256×192 ARCore depth image (mm).
//! let wall = vec![2000u16; 256 * 192];
//! let image = DepthImage::new(&wall, 256, 192, 512)?;
//! let k = Intrinsics { fx: 211.0, fy: 211.0, cx: 128.0, cy: 96.0 };
//!
//! session.start(0, pose(0))?;
//! for i in 1..=40 {
//!     let flags = session.frame(i * dt, pose(i))?;
//!     if flags.is_midpoint() {
//!         session.depth(&image, &k, DisplayRotation::Deg0)?;
//!     }
//! }
//! let summary = session.stop(41 * dt, pose(41))?;
//! assert_eq!((summary.frames, summary.midpoints, summary.subtrajectories), (40, 4, 4));
//! assert_eq!(summary.mean_depth_m, 2.0);
//!
//! // The backend's answer, keyed by window start (legacy CSV, nanoseconds).
//! session.load_results("start,error\n0,0.02\n333333330,0.15\n666666660,0.01\n999999990,0.12\n")?;
//! let markers = session.markers()?;
//! assert_eq!(markers.len(), 1); // sub-trajectory 3 is within 0.5 m of 1: deduplicated
//! assert_eq!(markers[0].subtrajectory, 1);
//! assert!((markers[0].position - DVec3::new(0.3, 1.5, 2.0)).length() < 1e-9);
//! assert_eq!(session.render_plan().segments.len(), 8);
//! # Ok::<(), sitar_core::Error>(())
//! ```
//!
//! ## Conventions
//!
//! Time is `i64` nanoseconds. Poses are world-from-camera in the session's [`Convention`]
//! (`unity`: left-handed, camera looks +Z; `arcore`: right-handed, camera looks −Z; both +Y
//! up, +X right). [`Convention::to_optical`] gives the optical camera frame (x right, y down,
//! z forward). Depth images are ARCore's 16-bit millimetres in sensor orientation;
//! [`DisplayRotation`] is the clockwise turn from sensor image to display.
//!
//! ## Recorder cadence
//!
//! With `n = subtrajectory_frames` (10): [`Session::start`] is frame 0; [`Session::frame`]
//! returns [`FrameFlags::MIDPOINT`] at frames `k·n + n/2` (call [`Session::depth`]) and
//! [`FrameFlags::ENDPOINT`] at `k·n + n`, closing sub-trajectory `k`. A midpoint without a
//! usable depth sample keeps its slot, so indices never shift. Wrong-state calls return
//! [`Error::InvalidState`].
//!
//! ## Depth, markers, results, render plan
//!
//! * [`sample_surface`]: point at the sample pixel (default centre) and normal from the
//!   weighted mean depth gradient over a 5×5 window, neighbours more than 20 % off skipped.
//! * [`select_markers`]: thresholds cascade (10, 5, 2, 1 cm), time order, at most
//!   `max_regions`, never within `dedup_radius_m`; spatial hash for neighbour queries.
//! * [`Results::parse`]: legacy CSV `start,error` or JSON; [`Session::error_at`] finds the
//!   nearest window start within half the median frame interval.
//! * Window settings: results name their window length and [`PoseRelation`]
//!   (`trans_part` in metres or `angle_deg` in degrees); [`Session::load_results`] refuses
//!   results that do not fit the config's `subtrajectory_frames` and `pose_relation`, and
//!   classes and markers use the thresholds of the results' unit
//!   ([`SessionConfig::thresholds_for`]; degree defaults 2°/4° and markers `[4, 2, 0.8,
//!   0.4]`°, the metric ones at 40° per metre).
//! * Calibrated results name their calibration ([`Results::calibration`]) and give each
//!   window its uncalibrated value and an interval that holds the true error with the
//!   calibration's coverage ([`ResultWindow::raw`], [`ResultWindow::interval`]);
//!   [`Session::result_at`] returns them with the window. The config's `classify_by`
//!   ([`ClassifyBy`]) colours windows and places markers by the error or by the upper bound.
//! * [`RenderPlan`]: cylinders, joints, frustums every `frustum_spacing_m`, start/stop.
//! * [`PlaybackLogger`]: the playback device's per-frame TUM log.
//!
//! ## Persistence
//!
//! [`Session::save`] writes a folder (`config.json`, `trajectory.txt` TUM in integer ns,
//! `subtrajectories.csv` with depth/normal/error/class, `anchors.csv`, `results.json`,
//! `session.json`);
//! [`Session::load`] reads it back exactly. The formats are documented on [`Session::save`].
//!
//! ## Venues and guidance
//!
//! [`Session::anchor`] records observations of a venue's printed anchor image; [`venue::align`]
//! puts a session into the venue frame from its `full` observations (robust medians, with
//! their spread), the one estimate the phone and the backend share; [`VenueMap`] is the
//! backend's `map.json`, which [`Session::load_venue`] aligns to and [`Session::venue_cells`]
//! returns in the session's world frame. [`venue::Contribution::from_files`] turns a session's
//! uploaded files into what it brings to a venue (its samples in the venue frame), and
//! [`venue::build_map`] / [`venue::MapBuilder`] aggregate them into the map's cells.
//! [`ScreenView::guide`] places a target on the screen or on an ellipse inside its edge;
//! [`Session::guide_into`] does it for every marker and high venue cell without allocating.
//!
//! ## Errors
//!
//! Every fallible call returns [`Error`]; nothing panics on bad input. Calls in the wrong
//! state are [`Error::InvalidState`], bad numbers [`Error::InvalidArgument`] (naming the
//! parameter), malformed text [`Error::Parse`] (naming source, line and field), config
//! problems [`Error::Config`] (naming the key) and unusable depth [`Error::InvalidDepth`].
#![forbid(unsafe_code)]
#![deny(missing_docs)]

// Modules lowest first: each uses only modules listed above it (the workspace's `tests/tests/layout.rs` checks that
// no import cycle exists among them).
// error                 — the crate's one error type
// relation              — what the results measure (pose relation) and in which unit
// classes               — the one error-class rule and the defaults every crate shares
// convention            — coordinate conventions, poses, display rotation
// csv_rows              — the rows of the session folder's comma-separated tables
// subtrajectory_columns — the columns of `subtrajectories.csv`, for persist and venue
// image                 — the camera's luminance plane and what is measured on it
// results               — error-estimation results: parsing, lookup, classes
// calibration           — calibration files, the walk's own motion, the estimate from one walk
// config                — the session configuration
// depth                 — from an ARCore depth image to a surface point and normal
// tum                   — TUM trajectory text with integer-nanosecond stamps
// logged_pose           — the poses a session logs, with frame and path length
// evidence              — what the camera saw and how it moved; the likely causes
// thumbnail             — a midpoint's display-oriented thumbnail (greyscale JPEG)
// guide                 — where an out-of-view target is on the screen or at its edge
// markers               — where the warning markers go
// render                — the render plan
// playback              — the playback device's per-frame TUM log
// venue                 — anchors, alignment, the venue map, contributions and the map builder
// session               — the on-device session: cadence, depth, results, markers, venue
// session_walk          — the estimate from one walk: a calibration colours the walk at stop
// evidence_table        — the session folder's `evidence.csv` and `thumbnails/`
// persist               — the session folder: `Session::save` and `Session::load`
pub mod calibration;
mod classes;
mod config;
mod convention;
mod csv_rows;
mod depth;
mod error;
mod evidence;
mod evidence_table;
mod guide;
mod image;
mod logged_pose;
mod markers;
mod persist;
mod playback;
mod relation;
mod render;
mod results;
mod session;
mod session_walk;
mod subtrajectory_columns;
mod thumbnail;
mod tum;
pub mod venue;

pub use classes::{DEFAULT_SETTING, ErrorClass, Thresholds};
pub use config::{ClassifyBy, SessionConfig};
pub use convention::{Convention, DisplayRotation, Pose};
pub use depth::{DepthImage, DepthSample, Intrinsics, sample_surface};
pub use error::{Error, InvalidDepth};
pub use evidence::{
    BLUR_LAPLACIAN_VAR, BLUR_MIN_CONTRAST, BLUR_RELATIVE, Causes, DARK_MEAN, DepthProperties,
    Evidence, FAR_SURFACE_M, FAST_ANGULAR_DEG_S, FAST_LINEAR_M_S, FAST_RELATIVE,
    LOW_TEXTURE_CEILING, LOW_TEXTURE_CORNERS, LOW_TEXTURE_RELATIVE, MotionProperties,
    NO_DEPTH_VALID_SHARE, OVEREXPOSED_SHARE, SessionMedians, likely_causes,
};
pub use evidence_table::EVIDENCE_HEADER;
pub use guide::{Guide, ScreenView};
pub use image::{
    FAST_THRESHOLD, ImageProperties, LumaImage, MAX_FAST_WIDTH, SATURATED_LUMA, fast_corners,
};
pub use logged_pose::LoggedPose;
pub use markers::{Marker, MarkerCandidate, select_markers, warning_sign_rotation};
pub use playback::PlaybackLogger;
pub use relation::{ErrorUnit, PoseRelation};
pub use render::{Frustum, Joint, RenderPlan, Segment};
pub use results::{ErrorInterval, ResultWindow, Results};
pub use session::{
    DepthStatus, FrameFlags, MidpointInput, Session, SessionState, SubTrajectory, Summary,
};
pub use session_walk::ON_DEVICE_CALIBRATION;
pub use thumbnail::{THUMBNAIL_QUALITY, downsample_rotated, encode_jpeg, thumbnail_size};
pub use tum::{parse_tum_ns, to_tum};
pub use venue::{Alignment, AnchorObservation, Tracking, VenueMap};
