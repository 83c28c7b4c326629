//! What the phone's camera and IMU recorded, as the RANSAC tracker's front end sees it:
//! landmarks on the room's surfaces, per-frame feature matches (with pixel noise, wrong
//! matches, spurious corners and the glass pane's reflections) and the inertial increments.
//!
//! All of it is a function of the recording alone (its own RNG stream), exactly as a replayed
//! mp4 gives every playback trial the same images and IMU samples: trials differ only in the
//! tracker's own randomness.

use glam::{DMat3, DQuat, DVec2, DVec3};
use rand::seq::{IndexedRandom, SliceRandom};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, Poisson};

use crate::draws::uniform_direction;
use crate::models::RansacModel;
use crate::{Room, SurfaceKind, Trajectory};

/// RNG stream of the landmarks and observations (the walk uses 1, the shared drift 2).
const OBSERVATION_STREAM: u64 = 3;

/// Turns ARCore's camera frame (−Z forward, +Y up) into the computer-vision frame (+Z
/// forward, +Y down) and back: its own inverse.
pub(crate) const ARCORE_TO_CV: DMat3 = DMat3::from_diagonal(DVec3::new(1.0, -1.0, -1.0));

/// One feature match: the landmark the descriptor matched and where the feature was seen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Observation {
    /// Index into [`Observations::landmarks`]; for a wrong match, not the landmark seen.
    pub landmark: u32,
    /// Normalised image coordinates (x/z, y/z) in the computer-vision camera frame.
    pub normalised: DVec2,
}

/// The recorded inertial increment from the previous frame: the gyroscope's rotation
/// (camera frame, with its noise) and the true translation in the previous camera frame, to
/// which the tracker adds the accelerometer's bias as it integrates (see the tracker).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ImuStep {
    pub rotation: DQuat,
    pub translation: DVec3,
    /// Accelerometer white noise integrated over the frame (m, previous camera frame).
    pub noise: DVec3,
}

/// The front end's view of a whole recording.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Observations {
    /// Landmark positions (world) and the index of the surface each lies on.
    pub landmarks: Vec<(DVec3, usize)>,
    /// Per frame, the feature matches.
    pub frames: Vec<Vec<Observation>>,
    /// Per frame (entry 0 unused), the inertial increment from the previous frame.
    pub imu: Vec<ImuStep>,
    /// The accelerometer bias (m/s², camera frame) the recording's IMU has.
    pub accel_bias: DVec3,
}

/// Camera-from-world rotation (computer-vision frame) of an ARCore world-from-camera one.
pub(crate) fn camera_from_world(world_from_camera: DQuat) -> DMat3 {
    ARCORE_TO_CV * DMat3::from_quat(world_from_camera).transpose()
}

impl Observations {
    /// Everything the front end records along `ground_truth` in `room`, from `seed`.
    pub fn record(room: &Room, ground_truth: &Trajectory, model: &RansacModel, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(OBSERVATION_STREAM);
        let landmarks = scatter_landmarks(room, model.lighting, &mut rng);
        let unit = Normal::new(0.0, 1.0).expect("unit normal");
        // Noise in normalised units per pixel of standard deviation.
        let per_px = model.pixel_noise_scale / model.lighting / model.focal_px;
        let mut frames = Vec::with_capacity(ground_truth.len());
        let mut visible = Vec::new();
        for (position, orientation) in ground_truth
            .positions
            .iter()
            .zip(&ground_truth.orientations)
        {
            let rotation = camera_from_world(*orientation);
            let mut frame = Vec::new();
            visible.clear();
            for (index, &(point, surface)) in landmarks.iter().enumerate() {
                let Some(normalised) = model.project(rotation * (point - *position)) else {
                    continue;
                };
                let unoccluded = room
                    .raycast(*position, point - *position)
                    .is_some_and(|hit| {
                        hit.surface_index == surface
                            && (hit.distance - position.distance(point)).abs() < 0.02
                    });
                if unoccluded && rng.random_bool(model.detection_probability) {
                    visible.push((index as u32, normalised, room.surfaces[surface].kind));
                }
            }
            for &(index, normalised, kind) in &visible {
                let mismatched = rng.random_bool(kind.mismatch_probability());
                let landmark = if mismatched {
                    visible.choose(&mut rng).map_or(index, |v| v.0)
                } else {
                    index
                };
                let sigma = kind.feature_noise_px() * per_px;
                frame.push(Observation {
                    landmark,
                    normalised: normalised + gaussian2(&unit, &mut rng) * sigma,
                });
            }
            reflections(
                room, &landmarks, *position, rotation, model, &mut rng, &mut frame,
            );
            spurious(
                room,
                &landmarks,
                *position,
                *orientation,
                model,
                &mut rng,
                &mut frame,
            );
            // The detector's real-time budget: it keeps the same features of the same image
            // in every replay (a fixed subset per frame, chosen here once).
            if frame.len() > model.features_per_frame {
                frame.shuffle(&mut rng);
                frame.truncate(model.features_per_frame);
            }
            frames.push(frame);
        }
        let gyro = Normal::new(0.0, model.gyro_noise_deg.to_radians())
            .unwrap_or_else(|_| Normal::new(0.0, 0.0).expect("zero noise"));
        let accel = Normal::new(0.0, model.accel_noise_mps)
            .unwrap_or_else(|_| Normal::new(0.0, 0.0).expect("zero noise"));
        let mut imu = vec![ImuStep {
            rotation: DQuat::IDENTITY,
            translation: DVec3::ZERO,
            noise: DVec3::ZERO,
        }];
        for f in 1..ground_truth.len() {
            // Camera-frame (computer-vision) increments of the true motion.
            let (r0, r1) = (
                camera_from_world(ground_truth.orientations[f - 1]),
                camera_from_world(ground_truth.orientations[f]),
            );
            let relative = r1 * r0.transpose();
            let translation = r0 * (ground_truth.positions[f] - ground_truth.positions[f - 1]);
            let dt = (ground_truth.stamps[f] - ground_truth.stamps[f - 1]) as f64 * 1e-9;
            let gyro_error = DVec3::new(
                gyro.sample(&mut rng),
                gyro.sample(&mut rng),
                gyro.sample(&mut rng),
            );
            let accel_error = DVec3::new(
                accel.sample(&mut rng),
                accel.sample(&mut rng),
                accel.sample(&mut rng),
            );
            imu.push(ImuStep {
                rotation: DQuat::from_scaled_axis(gyro_error) * DQuat::from_mat3(&relative),
                translation,
                noise: accel_error * dt,
            });
        }
        let direction = uniform_direction(&mut rng);
        Self {
            landmarks,
            frames,
            imu,
            accel_bias: direction * model.accel_bias_mps2,
        }
    }
}

fn gaussian2(noise: &Normal<f64>, rng: &mut ChaCha8Rng) -> DVec2 {
    DVec2::new(noise.sample(rng), noise.sample(rng))
}

/// Landmarks scattered uniformly on every surface, as many as its texture and the light give.
fn scatter_landmarks(room: &Room, lighting: f64, rng: &mut ChaCha8Rng) -> Vec<(DVec3, usize)> {
    let mut landmarks = Vec::new();
    for (index, surface) in room.surfaces.iter().enumerate() {
        let expected = surface.kind.landmark_density_m2() * surface.area_m2() * lighting;
        let count = Poisson::new(expected).map_or(0, |p| p.sample(rng) as usize);
        let v = surface.axis_v();
        for _ in 0..count {
            let a: f64 = rng.random_range(-1.0..1.0);
            let b: f64 = rng.random_range(-1.0..1.0);
            landmarks.push((
                surface.centre + surface.axis_u * (a * surface.half_u) + v * (b * surface.half_v),
                index,
            ));
        }
    }
    landmarks
}

/// Farthest a landmark may be from a glass pane to be seen reflected in it (dimmer beyond).
const MAX_REFLECTED_M: f64 = 3.0;

/// Reflections in glass: a landmark's mirror image seen through the pane, matched to the real
/// landmark (the descriptor is the same). These wrong matches agree with each other — they
/// move with the mirrored scene — so they support one coherent, wrong pose.
fn reflections(
    room: &Room,
    landmarks: &[(DVec3, usize)],
    position: DVec3,
    rotation: DMat3,
    model: &RansacModel,
    rng: &mut ChaCha8Rng,
    frame: &mut Vec<Observation>,
) {
    for (glass_index, glass) in room.surfaces.iter().enumerate() {
        let reflectivity = glass.kind.reflectivity();
        if reflectivity <= 0.0 || (position - glass.centre).dot(glass.normal) <= 0.0 {
            continue;
        }
        for (index, &(point, surface)) in landmarks.iter().enumerate() {
            let height = (point - glass.centre).dot(glass.normal);
            if surface == glass_index || height <= 0.05 || height > MAX_REFLECTED_M {
                continue;
            }
            let mirrored = point - glass.normal * (2.0 * height);
            let Some(normalised) = model.project(rotation * (mirrored - position)) else {
                continue;
            };
            let towards = mirrored - position;
            let through_glass = room
                .raycast(position, towards)
                .is_some_and(|hit| hit.surface_index == glass_index);
            if through_glass
                && rng.random_bool((model.reflection_match_probability * reflectivity).min(1.0))
            {
                let jitter = DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
                    * (glass.kind.feature_noise_px() * model.pixel_noise_scale / model.focal_px);
                frame.push(Observation {
                    landmark: index as u32,
                    normalised: normalised + jitter,
                });
            }
        }
    }
}

/// Spurious corners: as many as the surfaces in view produce (more on blank and glass,
/// more in dim light), each at a random pixel and matched to a random landmark.
fn spurious(
    room: &Room,
    landmarks: &[(DVec3, usize)],
    position: DVec3,
    orientation: DQuat,
    model: &RansacModel,
    rng: &mut ChaCha8Rng,
    frame: &mut Vec<Observation>,
) {
    if landmarks.is_empty() {
        return;
    }
    // The share of each kind in view, on a coarse 5 × 4 grid of rays.
    let (cols, rows) = (5u32, 4u32);
    let mut expected = 0.0;
    for r in 0..rows {
        for c in 0..cols {
            let u = (f64::from(c) + 0.5) / f64::from(cols) * model.width_px;
            let v = (f64::from(r) + 0.5) / f64::from(rows) * model.height_px;
            let cv = DVec3::new(
                (u - model.width_px / 2.0) / model.focal_px,
                (v - model.height_px / 2.0) / model.focal_px,
                1.0,
            );
            let world = orientation * (ARCORE_TO_CV * cv);
            let kind = room
                .raycast(position, world)
                .map_or(SurfaceKind::Dark, |hit| hit.surface);
            expected += kind.spurious_per_view();
        }
    }
    expected *= model.spurious_scale / (f64::from(cols * rows) * model.lighting);
    let count = Poisson::new(expected).map_or(0, |p| p.sample(rng) as usize);
    for _ in 0..count {
        let u: f64 = rng.random_range(0.0..model.width_px);
        let v: f64 = rng.random_range(0.0..model.height_px);
        frame.push(Observation {
            landmark: rng.random_range(0..landmarks.len()) as u32,
            normalised: DVec2::new(
                (u - model.width_px / 2.0) / model.focal_px,
                (v - model.height_px / 2.0) / model.focal_px,
            ),
        });
    }
}
