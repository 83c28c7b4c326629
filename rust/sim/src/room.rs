//! Rooms made of planar rectangles, and ray casting against them.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::Error;

/// What a surface looks like to a visual-inertial SLAM front end.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum SurfaceKind {
    /// Rich texture (a painting, a bookshelf, a patterned floor): many stable features.
    Textured,
    /// An ordinary painted wall or ceiling: a few features (edges, switches, stains).
    Plain,
    /// A featureless blank wall: almost nothing to track.
    Blank,
    /// A glass pane: few features of its own and reflections that move with the camera.
    Glass,
    /// An unlit wall or doorway: nothing at all to detect, so a tracker coasts on its
    /// inertial sensors alone (see the crate docs: the consistently-wrong scene).
    Dark,
}

impl SurfaceKind {
    /// How little there is to track, from 0 (feature-rich) to 1 (nothing).
    pub fn feature_poverty(self) -> f64 {
        match self {
            Self::Textured => 0.0,
            Self::Plain => 0.3,
            Self::Blank => 1.0,
            Self::Glass => 0.85,
            Self::Dark => 1.0,
        }
    }

    /// How much the surface reflects (false, moving features), from 0 to 1.
    pub fn reflectivity(self) -> f64 {
        match self {
            Self::Glass => 1.0,
            _ => 0.0,
        }
    }

    /// Whether SLAM is expected to struggle when the camera faces this surface.
    pub fn is_hard(self) -> bool {
        matches!(self, Self::Blank | Self::Glass | Self::Dark)
    }

    /// Landmarks (trackable corners) per square metre at normal lighting: what the RANSAC
    /// tracker's feature density follows.
    pub fn landmark_density_m2(self) -> f64 {
        match self {
            Self::Textured => 60.0,
            Self::Plain => 5.0,
            Self::Blank => 12.0,
            Self::Glass => 4.0,
            Self::Dark => 0.0,
        }
    }

    /// Spurious detections (unstable corners in image noise, matched to some unrelated
    /// landmark) per frame when this surface fills the view, at normal lighting.
    pub fn spurious_per_view(self) -> f64 {
        match self {
            Self::Textured => 1.0,
            Self::Plain => 3.0,
            Self::Blank => 10.0,
            Self::Glass => 8.0,
            Self::Dark => 0.0,
        }
    }

    /// Standard deviation (pixels, at normal lighting) of where a feature on this surface is
    /// found: sharp corners on texture, weak blobs on a blank wall or behind glass.
    pub fn feature_noise_px(self) -> f64 {
        match self {
            Self::Textured => 0.6,
            Self::Plain => 1.0,
            Self::Blank => 3.0,
            Self::Glass => 2.5,
            Self::Dark => 0.0,
        }
    }

    /// Probability that a real feature on this surface is matched to the wrong landmark
    /// (similar-looking corners).
    pub fn mismatch_probability(self) -> f64 {
        match self {
            Self::Textured => 0.05,
            Self::Plain => 0.1,
            Self::Blank | Self::Glass => 0.2,
            Self::Dark => 0.0,
        }
    }
}

/// A planar rectangle: `centre ± half_u·axis_u ± half_v·axis_v`, facing along `normal`.
///
/// `axis_v` is `normal × axis_u`. Rays hit both sides; the reported normal faces the ray.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Surface {
    /// Unique name, e.g. `"glass pane"`.
    pub name: String,
    /// What the surface looks like to SLAM.
    pub kind: SurfaceKind,
    /// Centre of the rectangle (world, metres).
    pub centre: DVec3,
    /// Unit normal, pointing into the room.
    pub normal: DVec3,
    /// Unit in-plane axis, perpendicular to `normal`.
    pub axis_u: DVec3,
    /// Half the extent along `axis_u` (metres).
    pub half_u: f64,
    /// Half the extent along `axis_v` (metres).
    pub half_v: f64,
}

impl Surface {
    /// A rectangle named `name` (geometry is checked by [`Room::new`]).
    pub fn new(
        name: &str,
        kind: SurfaceKind,
        centre: DVec3,
        normal: DVec3,
        axis_u: DVec3,
        half_u: f64,
        half_v: f64,
    ) -> Self {
        Self {
            name: name.to_owned(),
            kind,
            centre,
            normal,
            axis_u,
            half_u,
            half_v,
        }
    }

    /// The second in-plane axis, `normal × axis_u`.
    pub fn axis_v(&self) -> DVec3 {
        self.normal.cross(self.axis_u)
    }

    /// Width × height of the rectangle in square metres.
    pub fn area_m2(&self) -> f64 {
        4.0 * self.half_u * self.half_v
    }

    /// The four corners.
    pub fn corners(&self) -> [DVec3; 4] {
        let u = self.axis_u * self.half_u;
        let v = self.axis_v() * self.half_v;
        [
            self.centre - u - v,
            self.centre + u - v,
            self.centre + u + v,
            self.centre - u + v,
        ]
    }

    /// Distance along `dir` (unit) from `origin` to the rectangle, if the ray hits it in front.
    pub(crate) fn intersect(&self, origin: DVec3, dir: DVec3) -> Option<f64> {
        let denom = dir.dot(self.normal);
        if denom.abs() < 1e-12 {
            return None;
        }
        let t = (self.centre - origin).dot(self.normal) / denom;
        // Also rejects NaN from degenerate input.
        if t.is_nan() || t <= 1e-9 {
            return None;
        }
        let local = origin + dir * t - self.centre;
        let inside = local.dot(self.axis_u).abs() <= self.half_u
            && local.dot(self.axis_v()).abs() <= self.half_v;
        inside.then_some(t)
    }

    /// Distance from `point` to the closest point of the rectangle.
    pub fn distance_to(&self, point: DVec3) -> f64 {
        let local = point - self.centre;
        let u = local.dot(self.axis_u).clamp(-self.half_u, self.half_u);
        let v = local.dot(self.axis_v()).clamp(-self.half_v, self.half_v);
        let closest = self.centre + self.axis_u * u + self.axis_v() * v;
        point.distance(closest)
    }

    fn validate(&self, index: usize) -> Result<(), Error> {
        let field = |f: &str| format!("room.surfaces[{index}].{f}");
        let bad = |f: &str, m: &str| Error::InvalidRecording {
            field: field(f),
            message: m.to_owned(),
        };
        if self.name.is_empty() {
            return Err(bad("name", "empty"));
        }
        for (name, v) in [
            ("centre", self.centre),
            ("normal", self.normal),
            ("axis_u", self.axis_u),
        ] {
            if !v.is_finite() {
                return Err(bad(name, "not finite"));
            }
        }
        if (self.normal.length() - 1.0).abs() > 1e-6 {
            return Err(bad("normal", "not a unit vector"));
        }
        if (self.axis_u.length() - 1.0).abs() > 1e-6 {
            return Err(bad("axis_u", "not a unit vector"));
        }
        if self.normal.dot(self.axis_u).abs() > 1e-6 {
            return Err(bad("axis_u", "not perpendicular to normal"));
        }
        for (name, h) in [("half_u", self.half_u), ("half_v", self.half_v)] {
            if !(h.is_finite() && h > 0.0) {
                return Err(bad(name, "must be a positive number"));
            }
        }
        Ok(())
    }
}

/// Where a ray hits a room.
#[derive(Debug, Clone, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray, metres.
    pub distance: f64,
    /// The hit point (world).
    pub point: DVec3,
    /// Unit surface normal, facing the ray origin.
    pub normal: DVec3,
    /// What the surface looks like to SLAM.
    pub surface: SurfaceKind,
    /// The surface's name.
    pub surface_name: String,
    /// Index of the surface in [`Room::surfaces`].
    pub surface_index: usize,
}

/// A room: a set of planar rectangles in a right-handed, +Y-up world (metres).
///
/// Decorations (painting, glass pane, shelf) sit a centimetre in front of their wall so the
/// nearest hit is the decoration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Room {
    /// The surfaces; names are unique.
    pub surfaces: Vec<Surface>,
}

/// Gap between a decoration and the wall behind it.
const DECORATION_OFFSET_M: f64 = 0.01;

impl Room {
    /// A room from surfaces; names must be unique and geometry valid.
    pub fn new(surfaces: Vec<Surface>) -> Result<Self, Error> {
        let room = Self { surfaces };
        room.validate().map_err(|e| match e {
            Error::InvalidRecording { field, message } => {
                Error::InvalidArgument(format!("{field}: {message}"))
            }
            other => other,
        })?;
        Ok(room)
    }

    /// The demo room, 5 m (x) × 4 m (z) × 2.7 m (y), floor at y = 0, centred on the origin:
    ///
    /// * north wall (z = −2) with a textured **painting** (1.2 × 0.9 m),
    /// * east wall (x = +2.5) entirely **blank** (`"blank wall"`),
    /// * south wall (z = +2) with a 2 × 1.4 m **glass pane**,
    /// * west wall (x = −2.5) with a textured **bookshelf**,
    /// * a textured floor (a patterned rug) and a plain ceiling.
    pub fn demo() -> Self {
        let (hx, hz, h) = (2.5, 2.0, 2.7);
        let x = DVec3::X;
        let y = DVec3::Y;
        let z = DVec3::Z;
        let s = Surface::new;
        let surfaces = vec![
            s("floor", SurfaceKind::Textured, DVec3::ZERO, y, x, hx, hz),
            s("ceiling", SurfaceKind::Plain, y * h, -y, x, hx, hz),
            s(
                "north wall",
                SurfaceKind::Plain,
                DVec3::new(0.0, h / 2.0, -hz),
                z,
                x,
                hx,
                h / 2.0,
            ),
            s(
                "blank wall",
                SurfaceKind::Blank,
                DVec3::new(hx, h / 2.0, 0.0),
                -x,
                z,
                hz,
                h / 2.0,
            ),
            s(
                "south wall",
                SurfaceKind::Plain,
                DVec3::new(0.0, h / 2.0, hz),
                -z,
                -x,
                hx,
                h / 2.0,
            ),
            s(
                "west wall",
                SurfaceKind::Plain,
                DVec3::new(-hx, h / 2.0, 0.0),
                x,
                -z,
                hz,
                h / 2.0,
            ),
            s(
                "painting",
                SurfaceKind::Textured,
                DVec3::new(-0.3, 1.5, -hz + DECORATION_OFFSET_M),
                z,
                x,
                0.6,
                0.45,
            ),
            s(
                "glass pane",
                SurfaceKind::Glass,
                DVec3::new(0.2, 1.45, hz - DECORATION_OFFSET_M),
                -z,
                -x,
                1.0,
                0.7,
            ),
            s(
                "bookshelf",
                SurfaceKind::Textured,
                DVec3::new(-hx + DECORATION_OFFSET_M, 1.1, 0.3),
                x,
                -z,
                0.9,
                1.0,
            ),
        ];
        Self { surfaces }
    }

    /// The nearest surface hit by the ray from `origin` along `dir` (need not be unit).
    pub fn raycast(&self, origin: DVec3, dir: DVec3) -> Option<Hit> {
        let dir = dir.try_normalize()?;
        if !origin.is_finite() {
            return None;
        }
        let (index, distance) = self
            .surfaces
            .iter()
            .enumerate()
            .filter_map(|(i, s)| s.intersect(origin, dir).map(|t| (i, t)))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        let surface = &self.surfaces[index];
        let normal = if dir.dot(surface.normal) > 0.0 {
            -surface.normal
        } else {
            surface.normal
        };
        Some(Hit {
            distance,
            point: origin + dir * distance,
            normal,
            surface: surface.kind,
            surface_name: surface.name.clone(),
            surface_index: index,
        })
    }

    /// The surfaces SLAM struggles with (blank or glass).
    pub fn hard_surfaces(&self) -> Vec<&Surface> {
        self.surfaces.iter().filter(|s| s.kind.is_hard()).collect()
    }

    /// The surface with this name.
    pub fn surface(&self, name: &str) -> Option<&Surface> {
        self.surfaces.iter().find(|s| s.name == name)
    }

    /// The surface closest to `point` and its distance; decorations win ties with their wall.
    ///
    /// Used to say which surface a marker placed at `point` landed on.
    pub fn nearest_surface(&self, point: DVec3) -> Option<(&Surface, f64)> {
        self.surfaces
            .iter()
            .map(|s| (s, s.distance_to(point)))
            // A decoration lies 1 cm in front of its wall; prefer it within that gap.
            .min_by(|a, b| {
                let bias = |s: &Surface, d: f64| {
                    if s.kind == SurfaceKind::Plain {
                        d + DECORATION_OFFSET_M + 1e-3
                    } else {
                        d
                    }
                };
                bias(a.0, a.1).total_cmp(&bias(b.0, b.1))
            })
    }

    /// Axis-aligned bounds `(min, max)` of all surfaces.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.surfaces
            .iter()
            .flat_map(Surface::corners)
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p), hi.max(p))
            })
    }

    pub(crate) fn validate(&self) -> Result<(), Error> {
        if self.surfaces.is_empty() {
            return Err(Error::InvalidRecording {
                field: "room.surfaces".into(),
                message: "a room needs at least one surface".into(),
            });
        }
        for (i, s) in self.surfaces.iter().enumerate() {
            s.validate(i)?;
            if self.surfaces[..i].iter().any(|o| o.name == s.name) {
                return Err(Error::InvalidRecording {
                    field: format!("room.surfaces[{i}].name"),
                    message: format!("duplicate surface name {:?}", s.name),
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demo_room_is_valid_and_has_the_hard_surfaces() {
        let room = Room::demo();
        room.validate().unwrap();
        let hard: Vec<_> = room
            .hard_surfaces()
            .iter()
            .map(|s| s.name.clone())
            .collect();
        assert_eq!(hard, ["blank wall", "glass pane"]);
        let (lo, hi) = room.bounds();
        assert_eq!(lo, DVec3::new(-2.5, 0.0, -2.0));
        assert_eq!(hi, DVec3::new(2.5, 2.7, 2.0));
    }

    #[test]
    fn raycast_hits_walls_at_analytic_distances() {
        let room = Room::demo();
        let eye = DVec3::new(0.0, 1.5, 0.0);
        let hit = room.raycast(eye, DVec3::X).unwrap();
        assert_eq!(hit.surface_name, "blank wall");
        assert!((hit.distance - 2.5).abs() < 1e-12);
        assert_eq!(hit.normal, -DVec3::X);
        // Straight at the painting: it is 1 cm in front of the north wall.
        let hit = room.raycast(eye, -DVec3::Z).unwrap();
        assert_eq!(hit.surface_name, "painting");
        assert!((hit.distance - 1.99).abs() < 1e-12);
        // Oblique ray to the floor: 1.5 m down, 45 degrees.
        let hit = room.raycast(eye, DVec3::new(1.0, -1.0, 0.0)).unwrap();
        assert_eq!(hit.surface_name, "floor");
        assert!((hit.distance - 1.5 * 2f64.sqrt()).abs() < 1e-12);
        assert!((hit.point - DVec3::new(1.5, 0.0, 0.0)).length() < 1e-12);
        // Into the glass pane.
        let hit = room.raycast(eye, DVec3::Z).unwrap();
        assert_eq!(hit.surface, SurfaceKind::Glass);
        assert!((hit.distance - 1.99).abs() < 1e-12);
    }

    #[test]
    fn raycast_rejects_degenerate_rays_and_misses_outside() {
        let room = Room::demo();
        assert!(room.raycast(DVec3::ZERO, DVec3::ZERO).is_none());
        assert!(
            room.raycast(DVec3::new(f64::NAN, 0.0, 0.0), DVec3::X)
                .is_none()
        );
        // From outside, looking away from the room.
        assert!(room.raycast(DVec3::new(10.0, 1.0, 0.0), DVec3::X).is_none());
    }

    #[test]
    fn nearest_surface_prefers_decorations() {
        let room = Room::demo();
        let (s, d) = room.nearest_surface(DVec3::new(0.2, 1.45, 1.99)).unwrap();
        assert_eq!(s.name, "glass pane");
        assert!(d < 1e-12);
        // On the wall right behind the pane, 1 cm away from it: still the pane.
        let (s, _) = room.nearest_surface(DVec3::new(0.2, 1.45, 2.0)).unwrap();
        assert_eq!(s.name, "glass pane");
        let (s, _) = room.nearest_surface(DVec3::new(2.45, 1.0, 0.5)).unwrap();
        assert_eq!(s.name, "blank wall");
    }

    #[test]
    fn new_rejects_bad_geometry() {
        let mut room = Room::demo();
        room.surfaces[2].normal = DVec3::new(0.0, 0.0, 2.0);
        let err = Room::new(room.surfaces).unwrap_err().to_string();
        assert!(err.contains("surfaces[2].normal"), "{err}");
        let mut room = Room::demo();
        room.surfaces[3].name = "floor".into();
        let err = Room::new(room.surfaces).unwrap_err().to_string();
        assert!(err.contains("duplicate surface name"), "{err}");
        assert!(Room::new(vec![]).is_err());
    }
}
