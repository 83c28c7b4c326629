//! Ground truth for venue maps: what a point of the venue frame truly is, and how well a
//! map's problem cells match the room's hard surfaces.

use glam::{DQuat, DVec3};
use sitar_core::ErrorClass;
use sitar_core::venue::{CellKind, VenueMap, heading_of};

use crate::{Surface, SurfaceKind, Venue};

/// The surface nearest a point of the venue frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellTruth<'a> {
    /// The nearest surface of the room.
    pub surface: &'a Surface,
    /// How far the point is from it (m).
    pub distance_m: f64,
}

impl CellTruth<'_> {
    /// Whether tracking truly struggles facing it ([`SurfaceKind::is_hard`]).
    pub fn is_hard(&self) -> bool {
        self.surface.kind.is_hard()
    }

    /// The surface's name and what it is: `blank wall (hard)`, `painting (textured)`, …
    pub fn label(&self) -> String {
        let what = match self.surface.kind {
            kind if kind.is_hard() => "hard",
            SurfaceKind::Textured => "textured",
            SurfaceKind::Plain => "plain",
            _ => "other",
        };
        format!("{} ({what})", self.surface.name)
    }
}

/// A map's problem cells (surface cells classed high or medium) against the room's hard
/// surfaces; each surface cell is labelled by the surface nearest its centre.
#[derive(Debug, Clone, PartialEq)]
pub struct ProblemCellScore {
    /// Surface cells in the map.
    pub surface_cells: usize,
    /// Of those, high or medium.
    pub problem_cells: usize,
    /// Problem cells on a hard surface (true positives).
    pub problem_on_hard: usize,
    /// Surface cells on a hard surface.
    pub hard_cells: usize,
    /// The hard surfaces with at least one problem cell.
    pub hard_surfaces_found: Vec<String>,
    /// All hard surfaces of the room.
    pub hard_surfaces: Vec<String>,
    /// Problem cells not on a hard surface, by the surface they are on (name order).
    pub problem_elsewhere: std::collections::BTreeMap<String, usize>,
}

impl ProblemCellScore {
    /// Problem cells on hard surfaces / problem cells; `None` without problem cells.
    pub fn precision(&self) -> Option<f64> {
        (self.problem_cells > 0).then(|| self.problem_on_hard as f64 / self.problem_cells as f64)
    }

    /// Hard-surface cells flagged as problems / hard-surface cells in the map; `None` when
    /// the map has none.
    pub fn recall(&self) -> Option<f64> {
        (self.hard_cells > 0).then(|| self.problem_on_hard as f64 / self.hard_cells as f64)
    }
}

impl Venue {
    /// A point of the venue frame (ARCore convention, as the simulated phones record) in the
    /// room: through the anchor's centre and levelled +X.
    pub fn venue_to_room(&self, venue: DVec3) -> DVec3 {
        let heading = heading_of(self.anchor.pose.rotation).unwrap_or(0.0);
        self.anchor.pose.position + DQuat::from_rotation_y(heading) * venue
    }

    /// What the venue-frame point `venue` truly is: the room surface nearest it.
    pub fn truth_at(&self, venue: DVec3) -> Option<CellTruth<'_>> {
        self.room
            .nearest_surface(self.venue_to_room(venue))
            .map(|(surface, distance_m)| CellTruth {
                surface,
                distance_m,
            })
    }

    /// Scores `map`'s surface cells against the room's hard surfaces.
    pub fn score_problem_cells(&self, map: &VenueMap) -> ProblemCellScore {
        let mut score = ProblemCellScore {
            surface_cells: 0,
            problem_cells: 0,
            problem_on_hard: 0,
            hard_cells: 0,
            hard_surfaces_found: Vec::new(),
            problem_elsewhere: Default::default(),
            hard_surfaces: self
                .room
                .hard_surfaces()
                .iter()
                .map(|s| s.name.clone())
                .collect(),
        };
        for cell in map.cells.iter().filter(|c| c.kind == CellKind::Surface) {
            let Some(truth) = self.truth_at(DVec3::from_array(cell.center)) else {
                continue;
            };
            let problem = matches!(cell.class, ErrorClass::High | ErrorClass::Medium);
            score.surface_cells += 1;
            score.problem_cells += usize::from(problem);
            if truth.is_hard() {
                score.hard_cells += 1;
                if problem {
                    score.problem_on_hard += 1;
                    if !score.hard_surfaces_found.contains(&truth.surface.name) {
                        score.hard_surfaces_found.push(truth.surface.name.clone());
                    }
                }
            } else if problem {
                *score
                    .problem_elsewhere
                    .entry(truth.surface.name.clone())
                    .or_default() += 1;
            }
        }
        score.hard_surfaces_found.sort();
        score
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sitar_core::Convention;
    use sitar_core::venue::VenueCell;

    fn cell(center: DVec3, class: ErrorClass) -> VenueCell {
        VenueCell {
            center: center.to_array(),
            kind: CellKind::Surface,
            sessions: 1,
            subtrajectories: 1,
            error_m: 0.0,
            class,
            directions: [0; 8],
        }
    }

    #[test]
    fn cells_are_labelled_by_the_room_surface_and_scored() {
        let venue = Venue::demo(1, 4.0, 30.0, 1).unwrap();
        // The anchor's centre is the venue origin; venue +X is the room's +x here.
        let room_point = |p: DVec3| p - venue.anchor.pose.position;
        let blank = room_point(DVec3::new(2.45, 1.2, 0.0));
        let glass = room_point(DVec3::new(0.2, 1.45, 1.95));
        let painting = room_point(DVec3::new(-0.3, 1.5, -1.95));
        assert_eq!(venue.truth_at(blank).unwrap().label(), "blank wall (hard)");
        assert_eq!(venue.truth_at(glass).unwrap().label(), "glass pane (hard)");
        assert_eq!(
            venue.truth_at(painting).unwrap().label(),
            "painting (textured)"
        );
        assert_eq!(
            venue.truth_at(DVec3::ZERO).unwrap().label(),
            "printed anchor (textured)"
        );
        let map = VenueMap {
            id: "v0123456789abcdef".into(),
            name: "demo".into(),
            anchor: venue.anchor.id.clone(),
            cell_m: 0.25,
            convention: Convention::Arcore,
            unit: "m".into(),
            sessions: vec![],
            cells: vec![
                cell(blank, ErrorClass::High),
                cell(glass, ErrorClass::Low),
                cell(painting, ErrorClass::Medium),
                cell(painting + DVec3::X, ErrorClass::Low),
            ],
        };
        let score = venue.score_problem_cells(&map);
        assert_eq!(
            (
                score.surface_cells,
                score.problem_cells,
                score.problem_on_hard,
                score.hard_cells
            ),
            (4, 2, 1, 2)
        );
        assert_eq!(score.precision(), Some(0.5));
        assert_eq!(score.recall(), Some(0.5));
        assert_eq!(score.hard_surfaces_found, vec!["blank wall".to_owned()]);
        assert_eq!(
            score.problem_elsewhere.into_iter().collect::<Vec<_>>(),
            vec![("painting".to_owned(), 1)]
        );
    }
}
