//! The mechanistic tracker: a small feature-based visual-inertial odometry that replays a
//! recording's observations, so trials differ only by the tracker's own randomness.
//!
//! Per frame: an inertial prior (the recorded gyroscope rotation and motion, plus the
//! accelerometer bias integrated since the last visual fix), RANSAC over P3P hypotheses
//! within a gate around the prior with a fixed iteration budget (the trial's only source of
//! randomness), Gauss–Newton refinement on the inliers, a fusion with the prior weighted by
//! the inlier count, and triangulation of new landmarks from the trial's *estimated* poses
//! (two views, confirmed by a third, then refined by every later ray in which the point was
//! an inlier), so an error made once stays in the map and a different consensus chosen in one
//! frame changes the trial from then on. Map points that keep failing as outliers are dropped
//! and triangulated again.

use glam::{DMat3, DQuat, DVec3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sitar_estimator::Trajectory;

use crate::Recording;
use crate::draws::world_frame;
use crate::models::RansacModel;
use crate::observations::{ARCORE_TO_CV, Observations, camera_from_world};
use crate::p3p::CameraPose;
use crate::pnp::{Gate, LocateOptions, Match, locate};

/// RNG stream of the RANSAC trial `i` is `RANSAC_STREAM_BASE + i`.
const RANSAC_STREAM_BASE: u64 = 3 << 32;

/// The trial's growing map: per landmark index, its point once confirmed, the candidate a
/// two-view triangulation gave, the first ray seen, and how often in a row it failed as an
/// outlier.
struct Map {
    points: Vec<Option<DVec3>>,
    candidates: Vec<Option<DVec3>>,
    first_ray: Vec<Option<(DVec3, DVec3)>>,
    misses: Vec<u8>,
    /// Per map point, the normal equations Σ(I − ddᵀ)·p = Σ(I − ddᵀ)·c of its rays so far:
    /// every ray of a frame in which it was an inlier refines it (multi-view triangulation).
    rays: Vec<(DMat3, DVec3)>,
    /// Per landmark, whether it was an inlier of the current frame's pose.
    inlier_now: Vec<bool>,
}

/// Rays whose normal equations have a smaller determinant are too close to parallel to
/// place a point (two rays 4° apart give about 0.01).
const MIN_RAY_DETERMINANT: f64 = 1e-4;

/// Outlier verdicts in a row after which a map point is dropped and triangulated anew.
const MAX_MISSES: u8 = 3;

impl Map {
    fn new(landmarks: usize) -> Self {
        Self {
            points: vec![None; landmarks],
            candidates: vec![None; landmarks],
            first_ray: vec![None; landmarks],
            misses: vec![0; landmarks],
            rays: vec![(DMat3::ZERO, DVec3::ZERO); landmarks],
            inlier_now: vec![false; landmarks],
        }
    }

    /// Adds the ray of an observation to an unmapped landmark: the first one is kept, a later
    /// one with enough parallax triangulates a candidate (midpoint of the closest approach),
    /// and a third ray that passes within `tolerance` (radians) of the candidate confirms it
    /// — a wrong match rarely does, so one wrong ray cannot put a point in the map.
    fn observe(
        &mut self,
        landmark: usize,
        centre: DVec3,
        direction: DVec3,
        min_cos: f64,
        tolerance: f64,
    ) {
        if self.points[landmark].is_some() {
            if std::mem::take(&mut self.inlier_now[landmark]) {
                self.add_ray(landmark, centre, direction);
                let (a, b) = self.rays[landmark];
                if a.determinant() > MIN_RAY_DETERMINANT {
                    self.points[landmark] = Some(a.inverse() * b);
                }
            }
            return;
        }
        if let Some(candidate) = self.candidates[landmark] {
            let seen = (candidate - centre).normalize_or_zero();
            if seen.dot(direction) > tolerance.cos() {
                self.points[landmark] = Some(candidate);
                self.rays[landmark] = (DMat3::ZERO, DVec3::ZERO);
                if let Some((c0, d0)) = self.first_ray[landmark] {
                    self.add_ray(landmark, c0, d0);
                }
                self.add_ray(landmark, centre, direction);
            } else {
                self.candidates[landmark] = None;
                self.first_ray[landmark] = Some((centre, direction));
            }
            return;
        }
        let Some((c0, d0)) = self.first_ray[landmark] else {
            self.first_ray[landmark] = Some((centre, direction));
            return;
        };
        if d0.dot(direction) > min_cos {
            return;
        }
        // Closest points c0 + s·d0 and centre + t·direction.
        let w = c0 - centre;
        let b = d0.dot(direction);
        let denominator = 1.0 - b * b;
        if denominator < 1e-9 {
            return;
        }
        let (d, e) = (d0.dot(w), direction.dot(w));
        let s = (b * e - d) / denominator;
        let t = (e - b * d) / denominator;
        let gap = (c0 + d0 * s - centre - direction * t).length();
        if s > 0.1 && t > 0.1 && s < 10.0 && t < 10.0 && gap < tolerance * t {
            self.candidates[landmark] = Some((c0 + d0 * s + centre + direction * t) / 2.0);
        } else {
            // Rays that do not meet in front: start again from this one.
            self.first_ray[landmark] = Some((centre, direction));
        }
    }

    fn add_ray(&mut self, landmark: usize, centre: DVec3, direction: DVec3) {
        let projector = DMat3::IDENTITY
            - DMat3::from_cols(
                direction * direction.x,
                direction * direction.y,
                direction * direction.z,
            );
        let (a, b) = &mut self.rays[landmark];
        *a += projector;
        *b += projector * centre;
    }

    fn verdict(&mut self, landmark: usize, inlier: bool) {
        self.inlier_now[landmark] = inlier;
        if inlier {
            self.misses[landmark] = 0;
            return;
        }
        self.misses[landmark] += 1;
        if self.misses[landmark] >= MAX_MISSES {
            self.points[landmark] = None;
            self.candidates[landmark] = None;
            self.first_ray[landmark] = None;
            self.misses[landmark] = 0;
        }
    }
}

/// World-from-camera ARCore pose of a camera-from-world computer-vision one.
fn to_arcore(pose: &CameraPose) -> (DVec3, DQuat) {
    let world_from_camera = pose.rotation.transpose() * ARCORE_TO_CV;
    (
        pose.centre(),
        DQuat::from_mat3(&world_from_camera).normalize(),
    )
}

/// The camera-from-world pose of an ARCore world-from-camera one.
fn from_arcore(position: DVec3, orientation: DQuat) -> CameraPose {
    let rotation = camera_from_world(orientation);
    CameraPose {
        rotation,
        translation: -(rotation * position),
    }
}

/// Plays trial `trial_index` of `rec` with the RANSAC tracker over `observations`.
pub(crate) fn play(
    rec: &Recording,
    model: &RansacModel,
    observations: &Observations,
    trial_index: u32,
) -> Trajectory {
    let gt = &rec.walk().ground_truth;
    let n = gt.len();
    let mut rng = ChaCha8Rng::seed_from_u64(rec.seed());
    rng.set_stream(RANSAC_STREAM_BASE + u64::from(trial_index));
    let (world_rotation, world_offset) = world_frame(model.world_offset, &mut rng);
    let mut options = LocateOptions {
        hypotheses: model.ransac_hypotheses,
        threshold: model.inlier_threshold_px / model.focal_px,
        gate: Gate {
            distance_m: model.gate_m,
            angle_rad: model.gate_deg.to_radians(),
        },
    };
    let min_cos = model.min_parallax_deg.to_radians().cos();
    let mut map = Map::new(observations.landmarks.len());
    // The tracker runs in the ground truth's frame and reports in the trial's own: the same
    // geometry, without rounding differences between trials that are not the tracker's.
    let mut pose = from_arcore(gt.positions[0], gt.orientations[0]);
    let mut velocity_error = DVec3::ZERO;
    let mut frames_lost = 0.0;
    let mut positions = Vec::with_capacity(n);
    let mut orientations: Vec<DQuat> = Vec::with_capacity(n);
    let mut matches = Vec::with_capacity(model.features_per_frame);
    let mut matched = Vec::with_capacity(model.features_per_frame);
    for f in 0..n {
        let frame = &observations.frames[f];
        if f > 0 {
            let step = &observations.imu[f];
            let dt = (gt.stamps[f] - gt.stamps[f - 1]) as f64 * 1e-9;
            // Prior: rotate by the gyroscope, move by the recorded motion, the white noise and
            // the velocity error the bias has built up since the last visual fix.
            let turn = DMat3::from_quat(step.rotation);
            velocity_error += observations.accel_bias * dt;
            let translation_step = step.translation + step.noise + velocity_error * dt;
            let prior = CameraPose {
                rotation: turn * pose.rotation,
                translation: turn * (pose.translation - translation_step),
            };
            matches.clear();
            matched.clear();
            for o in frame {
                if let Some(world) = map.points[o.landmark as usize] {
                    matches.push(Match {
                        world,
                        normalised: o.normalised,
                    });
                    matched.push(o.landmark as usize);
                }
            }
            pose = prior;
            let widen = 1.0 + frames_lost / model.gate_growth_frames;
            options.gate = Gate {
                distance_m: model.gate_m * widen,
                angle_rad: (model.gate_deg * widen).min(90.0).to_radians(),
            };
            frames_lost += 1.0;
            if matches.len() >= model.min_inliers
                && let Some((visual, inliers)) = locate(&matches, &prior, &options, &mut rng)
                && inliers >= model.min_inliers
            {
                pose = fuse(
                    &prior,
                    &visual,
                    inliers as f64 / (inliers as f64 + model.prior_weight_inliers),
                );
                velocity_error = DVec3::ZERO;
                frames_lost = 0.0;
                for (m, &landmark) in matches.iter().zip(&matched) {
                    let p = visual.apply(m.world);
                    let inlier = p.z > 1e-6
                        && (glam::DVec2::new(p.x / p.z, p.y / p.z) - m.normalised).length()
                            < options.threshold;
                    map.verdict(landmark, inlier);
                }
            }
        }
        let world_from_camera = pose.rotation.transpose();
        let centre = pose.centre();
        for o in frame {
            let direction = (world_from_camera * o.normalised.extend(1.0)).normalize();
            map.observe(
                o.landmark as usize,
                centre,
                direction,
                min_cos,
                2.0 * options.threshold,
            );
        }
        let (position, orientation) = to_arcore(&pose);
        let (position, mut orientation) = (
            world_rotation * position + world_offset,
            (world_rotation * orientation).normalize(),
        );
        if orientations
            .last()
            .is_some_and(|q| q.dot(orientation) < 0.0)
        {
            orientation = -orientation;
        }
        positions.push(position);
        orientations.push(orientation);
    }
    Trajectory {
        stamps: gt.stamps.clone(),
        positions,
        orientations,
        time_unit: gt.time_unit,
    }
}

/// The prior moved towards the visual pose by `weight` (0 = prior, 1 = vision).
fn fuse(prior: &CameraPose, visual: &CameraPose, weight: f64) -> CameraPose {
    let (qp, qv) = (
        DQuat::from_mat3(&prior.rotation).normalize(),
        DQuat::from_mat3(&visual.rotation).normalize(),
    );
    let rotation = DMat3::from_quat(qp.slerp(qv, weight).normalize());
    let centre = prior.centre().lerp(visual.centre(), weight);
    CameraPose {
        rotation,
        translation: -(rotation * centre),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Recording, Tracker, play_trial};

    fn recording(seed: u64, model: RansacModel) -> Recording {
        Recording::demo(6.0, 30.0, seed)
            .unwrap()
            .with_ransac_model(model)
            .unwrap()
    }

    /// Frame-to-frame translation error of `trial` against the ground truth, per frame.
    fn step_errors(rec: &Recording, trial: &Trajectory) -> Vec<f64> {
        let gt = &rec.walk().ground_truth;
        (1..gt.len())
            .map(|f| {
                let rel = |t: &Trajectory| {
                    t.orientations[f - 1].inverse() * (t.positions[f] - t.positions[f - 1])
                };
                (rel(gt) - rel(trial)).length()
            })
            .collect()
    }

    #[test]
    fn trials_are_deterministic_distinct_and_in_their_own_frame() {
        let rec = recording(5, RansacModel::default());
        assert_eq!(rec.tracker(), Tracker::Ransac);
        let a = play_trial(&rec, 0);
        assert_eq!(a, play_trial(&rec, 0));
        assert_eq!(a.stamps, rec.walk().ground_truth.stamps);
        assert_ne!(a.positions, play_trial(&rec, 1).positions);
        // Its own world frame: far from the ground truth in absolute terms.
        assert!((a.positions[0] - rec.walk().ground_truth.positions[0]).length() > 1e-3);
        assert!(a.orientations.windows(2).all(|w| w[0].dot(w[1]) > 0.0));
        // The recording carries the tracker: bytes round-trip to the same trials.
        let back = Recording::from_bytes(&rec.to_bytes()).unwrap();
        assert_eq!(back.tracker(), Tracker::Ransac);
        assert_eq!(play_trial(&back, 3), play_trial(&rec, 3));
    }

    #[test]
    fn a_clean_camera_and_imu_track_the_ground_truth_closely() {
        let clean = RansacModel {
            pixel_noise_scale: 1e-3,
            gyro_noise_deg: 0.0,
            accel_noise_mps: 0.0,
            accel_bias_mps2: 0.0,
            world_offset: false,
            ..RansacModel::default()
        };
        let noisy = RansacModel {
            world_offset: false,
            ..RansacModel::default()
        };
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let rec = recording(2, clean);
        let clean_error = median(step_errors(&rec, &play_trial(&rec, 0)));
        let rec = recording(2, noisy);
        let noisy_error = median(step_errors(&rec, &play_trial(&rec, 0)));
        assert!(clean_error < 1e-3, "clean: {clean_error} m per frame");
        assert!(noisy_error > clean_error, "{noisy_error} vs {clean_error}");
    }

    #[test]
    fn bad_settings_name_the_field() {
        let bad = RansacModel {
            ransac_hypotheses: 0,
            ..RansacModel::default()
        };
        let err = Recording::demo(2.0, 30.0, 1)
            .unwrap()
            .with_ransac_model(bad)
            .unwrap_err()
            .to_string();
        assert!(err.contains("ransac.ransac_hypotheses"), "{err}");
        let bytes = recording(1, RansacModel::default()).to_bytes();
        let text = String::from_utf8(bytes[12..].to_vec()).unwrap();
        let edited = text.replace("\"lighting\":1.0", "\"lighting\":-1.0");
        let mut b = bytes[..12].to_vec();
        b.extend_from_slice(edited.as_bytes());
        let err = Recording::from_bytes(&b).unwrap_err().to_string();
        assert!(err.contains("ransac.lighting"), "{err}");
    }
}
