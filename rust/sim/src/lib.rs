//! Synthetic but honest test material for SiTAR, with ground truth.
//!
//! * A [`Room`] of planar rectangles — walls, a textured painting and bookshelf, a **blank
//!   wall** and a **glass pane** ([`Room::demo`]) — with [`Room::raycast`] and a phone-like
//!   depth renderer ([`Room::render_depth_mm`], ARCore's 16-bit millimetres, 0 = no depth).
//! * A handheld [`Walk`] (15 s at 30 fps by default, any length) whose camera turns to face
//!   each surface of interest, the hard ones included.
//! * A [`Recording`] — what a phone would upload — that plays back into repeated SLAM-like
//!   trials ([`play_trial`], [`simulate_trials`]): ground truth plus locally accumulated drift
//!   whose magnitude *and* trial-to-trial spread grow where the camera faces hard surfaces,
//!   with heavy-tailed outliers and a different world frame per trial. So the paper's
//!   observation — trials disagree most where the true error is high — holds by construction.
//!
//! * Or, with [`Tracker::Ransac`] ([`Recording::with_tracker`], [`RansacModel`]), trials from
//!   a mechanistic visual-inertial tracker: landmarks on the surfaces with a density that
//!   follows their texture, feature noise, wrong matches, spurious corners and the glass
//!   pane's reflections (recorded once per recording, shared by every trial, as a replayed
//!   mp4 is), then per trial an inertial prior, RANSAC over P3P hypotheses with a fixed
//!   real-time iteration budget (the only randomness a trial has, as the paper explains),
//!   Gauss–Newton refinement and a map triangulated from the trial's own estimated poses.
//!   The P3P solver is written here (Lambda Twist, from Persson & Nordberg's equations) because
//!   the `lambda-twist` crate pins nalgebra 0.21 through `cv-core`, incompatible with the
//!   workspace's nalgebra 0.34.
//! * Multi-sequence sets ([`Recording::sequence`], [`Room::varied`]: other rooms, walks, light
//!   and seeds) and the scene where the method fails ([`Room::dark_wall`],
//!   [`Recording::dark_wall`]): facing an unlit wall every trial coasts on the same IMU data,
//!   all trials agree, and the estimate falls far below the true error.
//!
//! * A [`Venue`]: the demo room with a [`PrintedAnchor`] on a wall, walked by several users,
//!   each phone in its own world frame, observing the anchor through an [`AnchorSensor`]
//!   (frustum, range, view angle, occlusion; `full`/`limited`; noise growing with distance
//!   and angle), with each user's truth ([`VenueTruth`]) and the room surface under any
//!   venue-frame point ([`Venue::truth_at`], [`Venue::score_problem_cells`]).
//!
//! Everything is deterministic from a seed (ChaCha8 streams: one for the walk, one for the
//! error all trials share, one for the RANSAC front end's observations, one per trial index).
//!
//! **Convention**: world and poses are ARCore's: right-handed, +Y up, metres; poses are
//! world-from-camera with the camera looking along −Z and +X to the right, display-oriented
//! as ARCore reports them; depth images are in the sensor orientation, turned on screen by
//! the display rotation ([`Room::render_depth_mm_rotated`]; [`Room::render_depth_mm`] is
//! rotation 0). Timestamps are integer nanoseconds.
//!
//! ```
//! use sitar_sim::{play_trial, DepthCamera, Recording};
//!
//! let rec = Recording::demo(15.0, 30.0, 42)?;
//! assert_eq!(rec.frames(), 450);
//! let trial = play_trial(&rec, 0);
//! assert_eq!(trial.len(), 450);
//!
//! // The phone's depth image at the first frame.
//! let gt = &rec.walk().ground_truth;
//! let camera = DepthCamera::phone();
//! let depth = rec.room().render_depth_mm(gt.positions[0], gt.orientations[0], &camera);
//! assert_eq!(depth.len(), 160 * 120);
//! // The walk starts facing the glass pane, where phone depth is only a speckle.
//! let with_depth = depth.iter().filter(|&&d| d > 0).count();
//! assert!(with_depth > 0 && with_depth < 160 * 120);
//!
//! // Upload format.
//! let back = Recording::from_bytes(&rec.to_bytes())?;
//! assert_eq!(play_trial(&back, 0), trial);
//! # Ok::<(), sitar_sim::Error>(())
//! ```
#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod anchor;
mod camera;
mod checks;
mod draws;
mod error;
mod luma;
mod models;
mod noise;
mod observations;
mod p3p;
mod phone;
mod pnp;
mod ransac_tracker;
mod recording;
mod room;
mod scenes;
mod trial;
mod venue_session;
mod venue_truth;
mod venue_users;
mod walk;

pub use anchor::{ANCHOR_SURFACE, AnchorSensor, DEMO_ANCHOR_ID, PrintedAnchor, Sighting};
pub use camera::{DepthCamera, Intrinsics, View};
pub use error::Error;
pub use luma::LumaCamera;
pub use models::{DriftModel, RansacModel};
pub use recording::{RECORDING_MAGIC, RECORDING_VERSION, Recording, Tracker};
pub use room::{Hit, Room, Surface, SurfaceKind};
pub use trial::{TrialOptions, play_trial, play_trial_with, simulate_trials};
pub use venue_truth::{CellTruth, ProblemCellScore};
pub use venue_users::{MAX_VENUE_USERS, Venue, VenueTruth, VenueUser};
pub use walk::{FIRST_STAMP_NS, Walk, look_rotation};

/// The trajectory type of the trials and the ground truth (from `sitar-estimator`).
pub use sitar_estimator::{TimeUnit, Trajectory};
