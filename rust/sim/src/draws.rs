//! Random draws the trials share: a trial's own world frame and directions on the sphere.

use std::f64::consts::TAU;

use glam::{DQuat, DVec3};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A trial's own world frame (random yaw about +Y and offset), or the identity when not
/// `enabled`; separate SLAM runs start in frames of their own.
pub(crate) fn world_frame(enabled: bool, rng: &mut ChaCha8Rng) -> (DQuat, DVec3) {
    if !enabled {
        return (DQuat::IDENTITY, DVec3::ZERO);
    }
    let yaw: f64 = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
    let offset = DVec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-0.2..0.2),
        rng.random_range(-1.0..1.0),
    );
    (DQuat::from_rotation_y(yaw), offset)
}

/// A direction uniform on the unit sphere.
pub(crate) fn uniform_direction(rng: &mut ChaCha8Rng) -> DVec3 {
    let z: f64 = rng.random_range(-1.0..1.0);
    let phi: f64 = rng.random_range(0.0..TAU);
    let r = (1.0 - z * z).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}
