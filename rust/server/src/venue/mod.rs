//! Venues: places whose sessions share one frame through a printed image anchor (issue 24).
//! The typed row and its bounds (`record`), who may see and change one (`access`), and a
//! session's alignment to its venue's frame from the phone's `anchors.csv` (`alignment`),
//! and the venue's map from its sessions' kept contributions (`map`, kept as `kept` encodes
//! them).

mod access;
pub(crate) mod alignment;
pub(crate) mod kept;
pub(crate) mod map;

pub(crate) use access::Standing;
