//! What goes into a scene, taken from a recorded session.

use glam::DVec3;
use sitar_core::{Convention, ErrorClass, Marker, RenderPlan, Session};

/// Everything the scene shows, in the session's convention: the render plan, the class of
/// each sub-trajectory, the markers and the depth-sampled surface points.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneParts {
    /// The convention of every pose and point below.
    pub convention: Convention,
    /// Segments, joints, frustums, start and stop.
    pub plan: RenderPlan,
    /// The class of sub-trajectory `k` at index `k` (missing entries are unknown).
    pub classes: Vec<ErrorClass>,
    /// The estimated error of sub-trajectory `k` at index `k`, in the results' unit.
    pub errors: Vec<Option<f64>>,
    /// The markers (empty without results).
    pub markers: Vec<Marker>,
    /// The surface point each midpoint's depth sample hit, with its sub-trajectory.
    pub surface_points: Vec<(u32, DVec3)>,
}

impl SceneParts {
    /// The parts of `session`: its render plan, and classes and markers once results are loaded.
    pub fn from_session(session: &Session) -> SceneParts {
        let markers = session.markers().unwrap_or_default();
        let subs = session.subtrajectories();
        SceneParts {
            convention: session.config().convention,
            plan: session.render_plan(),
            classes: subs
                .iter()
                .map(|s| session.subtrajectory_class(s.index))
                .collect(),
            errors: session.subtrajectory_errors(),
            markers,
            surface_points: subs
                .iter()
                .filter_map(|s| s.depth.sample().map(|d| (s.index, d.point)))
                .collect(),
        }
    }

    /// The class of sub-trajectory `k` (unknown when there is none).
    pub fn class_of(&self, k: u32) -> ErrorClass {
        self.classes
            .get(k as usize)
            .copied()
            .unwrap_or(ErrorClass::Unknown)
    }
}
