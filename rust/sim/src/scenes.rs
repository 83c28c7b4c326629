//! Sets of sequences for the paper's multi-sequence evaluation, and the scene where the
//! method is known to fail.

use glam::DVec3;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{Error, RansacModel, Recording, Room, Surface, SurfaceKind, Tracker, Walk};

/// RNG stream of a varied room (the walk uses 1, the trials' shared drift 2, observations 3).
const ROOM_STREAM: u64 = 4;

impl Room {
    /// A room like [`Room::demo`] with its size (4–6 × 3.2–4.8 × 2.4–3 m) and the walls that
    /// hold the painting, the blank wall, the glass pane and the bookshelf drawn from `seed`.
    /// Surface names are the demo's (`"blank wall"`, `"glass pane"`, …).
    pub fn varied(seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(ROOM_STREAM);
        let hx: f64 = rng.random_range(2.0..3.0);
        let hz: f64 = rng.random_range(1.6..2.4);
        let h: f64 = rng.random_range(2.4..3.0);
        let mut roles = ["painting", "blank wall", "glass pane", "bookshelf"];
        roles.shuffle(&mut rng);
        let walls = [
            ("north wall", DVec3::new(0.0, h / 2.0, -hz), DVec3::Z, hx),
            ("east wall", DVec3::new(hx, h / 2.0, 0.0), -DVec3::X, hz),
            ("south wall", DVec3::new(0.0, h / 2.0, hz), -DVec3::Z, hx),
            ("west wall", DVec3::new(-hx, h / 2.0, 0.0), DVec3::X, hz),
        ];
        let mut surfaces = vec![
            Surface::new(
                "floor",
                SurfaceKind::Textured,
                DVec3::ZERO,
                DVec3::Y,
                DVec3::X,
                hx,
                hz,
            ),
            Surface::new(
                "ceiling",
                SurfaceKind::Plain,
                DVec3::Y * h,
                -DVec3::Y,
                DVec3::X,
                hx,
                hz,
            ),
        ];
        for ((name, centre, normal, half_width), role) in walls.into_iter().zip(roles) {
            let axis_u = DVec3::Y.cross(normal);
            if role == "blank wall" {
                surfaces.push(Surface::new(
                    role,
                    SurfaceKind::Blank,
                    centre,
                    normal,
                    axis_u,
                    half_width,
                    h / 2.0,
                ));
                continue;
            }
            surfaces.push(Surface::new(
                name,
                SurfaceKind::Plain,
                centre,
                normal,
                axis_u,
                half_width,
                h / 2.0,
            ));
            let (kind, half_u, half_v, height) = match role {
                "painting" => (SurfaceKind::Textured, 0.6, 0.45, 1.5),
                "glass pane" => (SurfaceKind::Glass, 1.0, 0.7, 1.45),
                _ => (SurfaceKind::Textured, 0.9, 1.0, 1.1),
            };
            let slack = half_width - half_u - 0.2;
            let along = rng.random_range(-slack..=slack);
            let centre = DVec3::new(centre.x, height, centre.z) + axis_u * along + normal * 0.01;
            surfaces.push(Surface::new(
                role, kind, centre, normal, axis_u, half_u, half_v,
            ));
        }
        Self { surfaces }
    }

    /// The demo room with its blank wall unlit: a **dark wall** (`"dark wall"`,
    /// [`SurfaceKind::Dark`]) on which no feature at all is found.
    ///
    /// The method's known blind spot: facing it, every trial coasts on the same recorded
    /// inertial data, so every trial makes the *same* error — trials agree, and the estimate
    /// (their disagreement) is far below the true error, as the paper found for SenseTime A0.
    pub fn dark_wall() -> Self {
        let mut room = Self::demo();
        for s in &mut room.surfaces {
            if s.name == "blank wall" {
                s.name = "dark wall".into();
                s.kind = SurfaceKind::Dark;
            }
        }
        room
    }
}

impl Recording {
    /// Sequence `index` of a multi-sequence set from `seed`: sequence 0 walks the demo room,
    /// the others a [`Room::varied`] room each, with their own walk, seed and (for the RANSAC
    /// tracker) light level between 0.6 and 1.2. The same arguments give the same sequence.
    pub fn sequence(
        index: u32,
        seconds: f64,
        fps: f64,
        seed: u64,
        tracker: Tracker,
    ) -> Result<Self, Error> {
        let own_seed = seed
            .wrapping_mul(1_000_003)
            .wrapping_add(u64::from(index) * 7919);
        let room = if index == 0 {
            Room::demo()
        } else {
            Room::varied(own_seed)
        };
        let walk = Walk::handheld(&room, seconds, fps, own_seed)?;
        let rec = Self::new(room, walk, own_seed);
        Ok(match tracker {
            Tracker::Model => rec,
            Tracker::Ransac => {
                let mut rng = ChaCha8Rng::seed_from_u64(own_seed);
                rng.set_stream(ROOM_STREAM);
                let lighting = if index == 0 {
                    1.0
                } else {
                    rng.random_range(0.6..1.2)
                };
                rec.with_ransac_model(RansacModel {
                    lighting,
                    ..RansacModel::default()
                })?
            }
        })
    }

    /// The consistently-wrong scene ([`Room::dark_wall`]) walked for `seconds` from `seed`,
    /// played by the RANSAC tracker.
    pub fn dark_wall(seconds: f64, fps: f64, seed: u64) -> Result<Self, Error> {
        let room = Room::dark_wall();
        let walk = Walk::handheld(&room, seconds, fps, seed)?;
        Self::new(room, walk, seed).with_ransac_model(RansacModel::default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varied_rooms_are_valid_distinct_and_keep_the_surfaces_of_interest() {
        let mut layouts = std::collections::BTreeSet::new();
        for seed in 0..20 {
            let room = Room::varied(seed);
            room.validate().unwrap();
            for name in ["painting", "blank wall", "glass pane", "bookshelf"] {
                assert!(room.surface(name).is_some(), "seed {seed}: {name}");
            }
            let blank = room.surface("blank wall").unwrap();
            layouts.insert(format!("{:?}", blank.normal.to_array()));
            // Decorations lie on their wall, inside it.
            let (lo, hi) = room.bounds();
            for s in &room.surfaces {
                for c in s.corners() {
                    assert!(
                        c.cmpge(lo - 1e-9).all() && c.cmple(hi + 1e-9).all(),
                        "{}",
                        s.name
                    );
                }
            }
            // Every room can be walked.
            Walk::handheld(&room, 15.0, 30.0, seed).unwrap();
        }
        assert!(layouts.len() >= 3, "{layouts:?}");
    }

    #[test]
    fn sequences_differ_and_repeat() {
        let a = Recording::sequence(1, 4.0, 30.0, 7, Tracker::Ransac).unwrap();
        let b = Recording::sequence(2, 4.0, 30.0, 7, Tracker::Ransac).unwrap();
        assert_ne!(a.room(), b.room());
        assert_ne!(a.ransac_model(), b.ransac_model());
        assert_eq!(
            a,
            Recording::sequence(1, 4.0, 30.0, 7, Tracker::Ransac).unwrap()
        );
        let first = Recording::sequence(0, 4.0, 30.0, 7, Tracker::Model).unwrap();
        assert_eq!(first.room(), &Room::demo());
        assert_eq!(first.tracker(), Tracker::Model);
    }

    #[test]
    fn the_dark_wall_is_hard_and_has_no_landmarks() {
        let room = Room::dark_wall();
        let dark = room.surface("dark wall").unwrap();
        assert_eq!(dark.kind, SurfaceKind::Dark);
        assert!(dark.kind.is_hard());
        assert_eq!(dark.kind.landmark_density_m2(), 0.0);
        assert!(room.surface("blank wall").is_none());
    }
}
