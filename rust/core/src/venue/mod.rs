//! Venues: the printed image anchor a place shares, its observations, a session's alignment
//! to the venue frame, and the venue map (`GET /v1/venues/{id}/map.json`).
//!
//! **The venue frame**: origin at the anchor's centre, +Y world up (both conventions' world
//! frames are gravity-aligned), +X the image's +X levelled onto the horizontal plane, the
//! third axis completing the session convention's handedness. A session's world frame and
//! the venue frame therefore differ by a translation and a heading (a turn about +Y):
//! `p_world = R_y(heading) · p_venue + translation`, where `R_y(α)` is the matrix
//! `[[cos α, 0, sin α], [0, 1, 0], [−sin α, 0, cos α]]` — the same numbers in either
//! convention, so the third axis is `+X × +Y`'s mirror in Unity's left-handed world and the
//! right-handed one in ARCore's (a physical point has venue coordinates `(x, y, z)` in a
//! Unity session and `(x, y, −z)` in an ARCore session, as its world coordinates do).
//!
//! [`align`] is the one estimate of that alignment, used by the phone (`Session`) and the
//! backend: from the `full` observations only, a median position and a median heading,
//! observations far from them rejected as outliers, then the medians of the rest, with
//! their spread (RMS position deviation in metres, RMS heading deviation in degrees).
//!
//! From the sessions' files, [`Contribution::from_files`] computes what one session brings
//! to the map (its alignment and, in the venue frame, each sub-trajectory's midpoint, camera
//! heading, surface point and error); [`build_map`] and the incremental [`MapBuilder`]
//! aggregate contributions into cells.

mod alignment;
mod anchors;
mod builder;
mod contribution;
mod map;
#[cfg(test)]
mod map_tests;
#[cfg(test)]
pub(crate) mod tests;
mod trim_mean;

pub use alignment::{
    Alignment, NotAligned, OUTLIER_FLOOR_DEG, OUTLIER_FLOOR_M, OUTLIER_SIGMAS, align, heading_of,
};
#[cfg(test)]
use alignment::{median, wrap};
pub use anchors::{
    ANCHORS_HEADER, AnchorObservation, MAX_ANCHOR_ID_BYTES, Tracking, anchors_csv, check_anchor_id,
    parse_anchors_csv,
};
pub use builder::{MapBuilder, VenueSpec, build_map, cell_centre, cell_index};
pub use contribution::{Contribution, Sample, SessionFiles, heading_seen_from_above, sector_of};
pub use map::{CellKind, VenueCell, VenueMap, VenueSession, WorldCell, world_cells};
pub use trim_mean::{CELL_TRIM, trim_mean};
