//! # sitar-scene: a session's scene as glTF 2.0 binary
//!
//! What the phone shows in AR — the trajectory as a tube coloured by the estimated error of
//! each sub-trajectory, the camera frustums, the start and stop, the markers (exclamation
//! points and surface-aligned warning signs) and the depth-sampled surface points — as one
//! `.glb` file that Blender, Unity (glTFast), three.js and any glTF viewer open.
//!
//! ```
//! use sitar_core::{Session, SessionConfig, Pose};
//! use glam::{DQuat, DVec3};
//!
//! let mut session = Session::new(SessionConfig::default());
//! let pose = |i: i64| Pose::new(DVec3::new(0.05 * i as f64, 1.5, 0.0), DQuat::IDENTITY);
//! session.start(0, pose(0))?;
//! for i in 1..=20 {
//!     session.frame(i * 33_333_333, pose(i))?;
//! }
//! session.stop(21 * 33_333_333, pose(21))?;
//! let parts = sitar_scene::SceneParts::from_session(&session);
//! let glb = sitar_scene::to_glb(&parts)?;
//! assert_eq!(&glb[..4], b"glTF");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## The scene graph
//!
//! One scene with one root node `sitar_session`, whose children are groups holding one node
//! per element of the [`sitar_core::RenderPlan`] (so counts match the plan exactly):
//!
//! | group | children | mesh |
//! |---|---|---|
//! | `trajectory` | one per segment | unit cylinder, Y scaled by the segment length |
//! | `joints` | one per joint | sphere |
//! | `frustums` | one per frustum | lines: apex, image plane, up tick |
//! | `markers` | one per marker, each with an `exclamation` and a `warning_sign` child | boxes / triangle plate |
//! | `start`, `stop` | — | sphere (green / black) |
//! | `surface_points` | — | points, one per valid depth sample |
//!
//! Materials are named by class (`low`, `medium`, `high`, `unknown`) with the report's
//! colours. Node `extras` carry the sub-trajectory (and for markers the error).
//!
//! ## Conventions
//!
//! glTF is right-handed, +Y up, metres, and cameras look along −Z: the ARCore convention.
//! `arcore` sessions are written as they are; `unity` sessions are converted with the
//! reflection `z → −z` (positions `S p`, rotations `S R S`), which is also what glTFast
//! applies on import, so the scene lands in Unity exactly where the session was recorded.
//!
//! ## A venue's map
//!
//! [`venue_to_glb`] writes a venue map ([`sitar_core::venue::VenueMap`], the backend's
//! `map.json`) the same way: root node `sitar_venue`, an `anchor` node at the venue origin,
//! groups `surface_cells` (translucent tiles coloured by class) and `path_cells` (small faint
//! boxes), one named node per cell with its numbers in `extras`.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod builder;
mod error;
mod parts;
mod shapes;
mod venue;

pub use builder::to_glb;
pub use error::Error;
pub use parts::SceneParts;
pub use venue::{PATH_BOX_SHARE, SURFACE_TILE_SHARE, venue_to_glb};
