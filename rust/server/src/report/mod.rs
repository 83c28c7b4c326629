//! What the report draws: the page (`page`, from `templates`), its charts (`charts`), the
//! problem regions and their evidence (`regions`, `region_evidence`), the 3-D scene
//! (`scene`, `scene_view`; a walk from the phone's own log in `phone_log_scene`, its depth
//! samples from `flat_depth`) and the helpers for long walks (`thinning`, `index_ranges`).

pub(crate) mod charts;
mod flat_depth;
pub(crate) mod index_ranges;
pub(crate) mod page;
pub(crate) mod phone_log_scene;
pub(crate) mod region_evidence;
pub(crate) mod regions;
pub(crate) mod scene;
pub(crate) mod scene_view;
pub(crate) mod templates;
pub(crate) mod thinning;
pub(crate) mod venue_page;
pub(crate) mod venue_view;
