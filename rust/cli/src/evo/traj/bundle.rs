//! What `sitar traj` works on: the named trajectories, the reference and what a sync made of
//! them, and the format they were read in.

use std::collections::{BTreeMap, BTreeSet};

use sitar_estimator::Trajectory;

/// The format the files were read in (a bag's topics count as TUM).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    Tum,
    Euroc,
    Kitti,
}

/// The bundle: named trajectories (in the order given), the reference and, after a sync,
/// each trajectory's synchronised reference.
pub(super) struct Bundle {
    pub(super) trajectories: Vec<(String, Trajectory)>,
    pub(super) reference: Option<(String, Trajectory)>,
    pub(super) synced_refs: BTreeMap<String, Trajectory>,
    pub(super) synced: bool,
    /// Trajectories read with quaternions off unit norm (evo's check calls them invalid).
    pub(super) off_unit: BTreeSet<String>,
    /// The trajectories are a bag's topics (named by topic, never shortened).
    pub(super) from_bag: bool,
    /// A bag topic's frame (evo's `meta.frame_id`), by name.
    pub(super) frames: BTreeMap<String, String>,
}
