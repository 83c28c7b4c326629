//! A handheld walk through a room: smooth ground-truth camera motion.

use std::f64::consts::{PI, TAU};

use glam::{DQuat, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sitar_estimator::{TimeUnit, Trajectory};

use crate::{Error, Room, Surface, SurfaceKind};

/// Timestamp of the first frame: ARCore stamps are nanoseconds since boot.
pub const FIRST_STAMP_NS: i64 = 1_000_000_000_000;

/// RNG stream of the walk (trials use other streams of the same seed).
pub(crate) const WALK_STREAM: u64 = 1;

/// Longest walk accepted, in frames (about 9 hours at 30 fps).
const MAX_FRAMES: f64 = 1e6;

/// A ground-truth handheld walk: one world-from-camera pose per camera frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Walk {
    /// Camera frame rate.
    pub fps: f64,
    /// Ground-truth poses in the ARCore convention (right-handed, +Y up, camera looks along
    /// −Z), integer-nanosecond stamps from [`FIRST_STAMP_NS`] at `1/fps` intervals.
    pub ground_truth: Trajectory,
}

/// World-from-camera rotation (ARCore convention: camera looks along −Z, +Y up) looking
/// along unit `forward` with `roll` radians about the viewing axis.
pub fn look_rotation(forward: DVec3, roll: f64) -> DQuat {
    let (yaw, pitch) = yaw_pitch(forward);
    DQuat::from_rotation_y(yaw) * DQuat::from_rotation_x(pitch) * DQuat::from_rotation_z(roll)
}

/// Yaw about +Y (0 = looking along −Z) and pitch (up positive) of a unit direction.
fn yaw_pitch(dir: DVec3) -> (f64, f64) {
    ((-dir.x).atan2(-dir.z), dir.y.clamp(-1.0, 1.0).asin())
}

/// Minimum-jerk blend 0 → 1: zero velocity and acceleration at both ends.
fn min_jerk(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)
}

/// Wraps an angle to (−π, π].
fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(TAU);
    if w > PI { w - TAU } else { w }
}

/// One stop of the walk: stand in front of a surface and sweep sideways while looking at it.
struct Stop {
    position: DVec3,
    gaze: DVec3,
    /// Sideways sweep (metres, signed) along the surface's horizontal axis.
    sweep: DVec3,
}

impl Stop {
    fn new(surface: &Surface, lo: DVec3, hi: DVec3, rng: &mut ChaCha8Rng) -> Self {
        let centre = (lo + hi) / 2.0;
        let gaze = surface.centre
            + surface.axis_u * (rng.random_range(-0.25..0.25) * surface.half_u)
            + surface.axis_v() * (rng.random_range(-0.1..0.1) * surface.half_v);
        let mut position = gaze + surface.normal * rng.random_range(1.0..1.3);
        // Stand a little towards the middle of the room: shorter walks between stops.
        position = position.lerp(centre, 0.25);
        position.y = rng.random_range(1.4..1.5);
        // Half a metre from the walls, plus room for the sideways sweep.
        let margin = 0.75;
        position.x = position.x.clamp(lo.x + margin, hi.x - margin);
        position.z = position.z.clamp(lo.z + margin, hi.z - margin);
        // Sweep along the horizontal in-plane direction.
        let horizontal = DVec3::new(-surface.normal.z, 0.0, surface.normal.x)
            .try_normalize()
            .unwrap_or(DVec3::X);
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let sweep = horizontal * (sign * rng.random_range(0.25..0.45));
        Self {
            position,
            gaze,
            sweep,
        }
    }

    /// Position and gaze direction at sweep parameter `s` ∈ [0, 1].
    fn at(&self, s: f64) -> (DVec3, DVec3) {
        let k = min_jerk(s) - 0.5;
        let p = self.position + self.sweep * k;
        let g = self.gaze + self.sweep * (0.6 * k);
        (p, (g - p).normalize_or(DVec3::NEG_Z))
    }
}

/// Small smooth handheld shake: a few sinusoids per degree of freedom.
struct Shake {
    /// (amplitude, frequency Hz, phase) per term, for x, y, z, yaw, pitch, roll.
    terms: [[(f64, f64, f64); 3]; 6],
}

impl Shake {
    fn new(rng: &mut ChaCha8Rng) -> Self {
        let mut terms = [[(0.0, 0.0, 0.0); 3]; 6];
        for (dof, row) in terms.iter_mut().enumerate() {
            for term in row.iter_mut() {
                // 1.5 mm per position term, 0.3 degrees per angle term.
                let amplitude = if dof < 3 { 0.0015 } else { 0.3f64.to_radians() };
                *term = (
                    amplitude * rng.random_range(0.5..1.0),
                    rng.random_range(0.3..2.5),
                    rng.random_range(0.0..TAU),
                );
            }
        }
        Self { terms }
    }

    fn eval(&self, t: f64) -> [f64; 6] {
        self.terms.map(|row| {
            row.iter()
                .map(|(a, f, phase)| a * (TAU * f * t + phase).sin())
                .sum()
        })
    }
}

impl Walk {
    /// A handheld walk of `seconds` at `fps` through `room`, deterministic from `seed`.
    ///
    /// The walker goes round the room's vertical surfaces of interest (every non-plain wall
    /// surface: in [`Room::demo`] the painting, the blank wall, the glass pane and the
    /// bookshelf), stopping about 1.3 m in front of each, sweeping sideways while
    /// looking at it, then turning to the next with minimum-jerk motion; a 15 s walk visits
    /// four surfaces, longer walks keep going round. On top comes a smooth handheld shake
    /// (millimetres, fractions of a degree) and a walking bob. There are
    /// `round(seconds·fps)` frames.
    pub fn handheld(room: &Room, seconds: f64, fps: f64, seed: u64) -> Result<Self, Error> {
        if !(seconds.is_finite() && seconds > 0.0) {
            return Err(Error::InvalidArgument(format!(
                "walk duration must be a positive number of seconds, got {seconds}"
            )));
        }
        if !(fps.is_finite() && fps > 0.0 && fps <= 1000.0) {
            return Err(Error::InvalidArgument(format!(
                "frame rate must be in (0, 1000] fps, got {fps}"
            )));
        }
        let frames = (seconds * fps).round();
        if !(2.0..=MAX_FRAMES).contains(&frames) {
            return Err(Error::InvalidArgument(format!(
                "a walk needs 2 to {MAX_FRAMES} frames, {seconds} s at {fps} fps gives {frames}"
            )));
        }
        let frames = frames as usize;
        let mut targets: Vec<&Surface> = room
            .surfaces
            .iter()
            .filter(|s| s.normal.y.abs() < 0.1 && s.kind != SurfaceKind::Plain)
            .collect();
        if targets.len() < 2 {
            targets = room
                .surfaces
                .iter()
                .filter(|s| s.normal.y.abs() < 0.1)
                .collect();
        }
        if targets.is_empty() {
            return Err(Error::InvalidArgument(
                "the room has no vertical surface to walk along".into(),
            ));
        }
        let (lo, hi) = room.bounds();
        let centre = (lo + hi) / 2.0;
        // Go round the room: sort by azimuth around its centre.
        let azimuth = |s: &Surface| (s.centre.z - centre.z).atan2(s.centre.x - centre.x);
        targets.sort_by(|a, b| azimuth(a).total_cmp(&azimuth(b)));

        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(WALK_STREAM);
        let duration = frames as f64 / fps;
        let n_stops = ((duration / 3.75).round() as usize).max(2);
        let first = rng.random_range(0..targets.len());
        let step = if rng.random_bool(0.5) {
            1
        } else {
            targets.len() - 1
        };
        let stops: Vec<Stop> = (0..n_stops)
            .map(|i| {
                Stop::new(
                    targets[(first + i * step) % targets.len()],
                    lo,
                    hi,
                    &mut rng,
                )
            })
            .collect();
        let shake = Shake::new(&mut rng);
        // Dwell at each stop, with transitions 1.2 times as long between stops.
        let dwell = duration / (n_stops as f64 + 1.2 * (n_stops - 1) as f64);
        let transition = 1.2 * dwell;
        let period = dwell + transition;

        let smooth_pose = |t: f64| -> (DVec3, f64, f64) {
            let i = ((t / period).floor().max(0.0) as usize).min(n_stops - 1);
            let local = t - i as f64 * period;
            let (p, dir) = if local <= dwell || i + 1 == n_stops {
                stops[i].at(local / dwell)
            } else {
                let s = min_jerk((local - dwell) / transition);
                let (p0, d0) = stops[i].at(1.0);
                let (p1, d1) = stops[i + 1].at(0.0);
                let (yaw0, pitch0) = yaw_pitch(d0);
                let (yaw1, pitch1) = yaw_pitch(d1);
                let p = p0.lerp(p1, s);
                let yaw = yaw0 + wrap(yaw1 - yaw0) * s;
                let pitch = pitch0 + (pitch1 - pitch0) * s;
                return (p, yaw, pitch);
            };
            let (yaw, pitch) = yaw_pitch(dir);
            (p, yaw, pitch)
        };

        let mut stamps = Vec::with_capacity(frames);
        let mut positions = Vec::with_capacity(frames);
        let mut orientations = Vec::with_capacity(frames);
        for f in 0..frames {
            let t = f as f64 / fps;
            let (p, yaw, pitch) = smooth_pose(t);
            // Walking bob: vertical, 1 cm at walking speed (0.8 m/s) and above.
            let h = 0.02;
            let (p_next, _, _) = smooth_pose(t + h);
            let speed = ((p_next - p) * DVec3::new(1.0, 0.0, 1.0)).length() / h;
            let bob = 0.01 * (speed / 0.8).min(1.0) * (TAU * 1.8 * t).sin();
            let [sx, sy, sz, syaw, spitch, sroll] = shake.eval(t);
            positions.push(p + DVec3::new(sx, sy + bob, sz));
            let mut q = (DQuat::from_rotation_y(yaw + syaw)
                * DQuat::from_rotation_x(pitch + spitch)
                * DQuat::from_rotation_z(sroll))
            .normalize();
            // Keep the quaternion sign continuous (q and −q are the same rotation).
            if orientations
                .last()
                .is_some_and(|prev: &DQuat| q.dot(*prev) < 0.0)
            {
                q = -q;
            }
            orientations.push(q);
            stamps.push(FIRST_STAMP_NS + (f as f64 * 1e9 / fps).round() as i64);
        }
        let ground_truth = Trajectory {
            stamps,
            positions,
            orientations,
            time_unit: TimeUnit::Nanoseconds,
        };
        Ok(Self { fps, ground_truth })
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.ground_truth.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_rotation_points_the_camera() {
        for dir in [
            DVec3::X,
            -DVec3::X,
            DVec3::Z,
            DVec3::new(1.0, -1.0, 2.0).normalize(),
        ] {
            let q = look_rotation(dir, 0.0);
            assert!((q * -DVec3::Z - dir).length() < 1e-12, "{dir}");
            // No roll: the camera's x axis stays horizontal.
            assert!((q * DVec3::X).y.abs() < 1e-12);
        }
    }

    #[test]
    fn default_walk_has_450_frames_and_is_deterministic() {
        let room = Room::demo();
        let a = Walk::handheld(&room, 15.0, 30.0, 7).unwrap();
        let b = Walk::handheld(&room, 15.0, 30.0, 7).unwrap();
        let c = Walk::handheld(&room, 15.0, 30.0, 8).unwrap();
        assert_eq!(a, b);
        assert_ne!(a.ground_truth.positions, c.ground_truth.positions);
        assert_eq!(a.frames(), 450);
        let gt = &a.ground_truth;
        assert_eq!(gt.stamps[0], FIRST_STAMP_NS);
        assert_eq!(gt.stamps[1] - gt.stamps[0], 33_333_333);
        assert_eq!(gt.stamps[449], FIRST_STAMP_NS + 14_966_666_667);
    }

    #[test]
    fn walk_stays_inside_and_moves_smoothly() {
        let room = Room::demo();
        let (lo, hi) = room.bounds();
        for seed in 0..20 {
            let walk = Walk::handheld(&room, 30.0, 30.0, seed).unwrap();
            let gt = &walk.ground_truth;
            for w in 0..gt.len() {
                let p = gt.positions[w];
                assert!(p.cmpgt(lo + 0.3).all() && p.cmplt(hi - 0.3).all(), "{p}");
            }
            for w in gt.positions.windows(2) {
                // A person scanning a room with a phone held up does not run (< 1.7 m/s).
                assert!((w[1] - w[0]).length() * 30.0 < 1.7, "seed {seed}");
            }
            for w in gt.orientations.windows(2) {
                assert!(w[0].dot(w[1]) > 0.0, "quaternion sign flips");
                // Nor turn faster than 120 degrees per second.
                assert!(w[0].angle_between(w[1]).to_degrees() * 30.0 < 120.0);
            }
        }
    }

    #[test]
    fn a_fifteen_second_walk_faces_every_surface_of_interest() {
        let room = Room::demo();
        for seed in 0..10 {
            let walk = Walk::handheld(&room, 15.0, 30.0, seed).unwrap();
            let gt = &walk.ground_truth;
            let mut seen = std::collections::BTreeMap::new();
            for (p, q) in gt.positions.iter().zip(&gt.orientations) {
                if let Some(name) = room.view(*p, *q).facing {
                    *seen.entry(name).or_insert(0) += 1;
                }
            }
            for name in ["painting", "blank wall", "glass pane", "bookshelf"] {
                assert!(
                    seen.get(name).copied().unwrap_or(0) >= 30,
                    "seed {seed}: {seen:?}"
                );
            }
        }
    }

    #[test]
    fn rejects_bad_arguments() {
        let room = Room::demo();
        assert!(Walk::handheld(&room, 0.0, 30.0, 1).is_err());
        assert!(Walk::handheld(&room, f64::NAN, 30.0, 1).is_err());
        assert!(Walk::handheld(&room, 15.0, -1.0, 1).is_err());
        assert!(Walk::handheld(&room, 0.01, 30.0, 1).is_err());
        assert!(Walk::handheld(&room, 1e9, 30.0, 1).is_err());
        let empty = Room {
            surfaces: vec![room.surfaces[0].clone()],
        };
        assert!(Walk::handheld(&empty, 15.0, 30.0, 1).is_err());
    }
}
