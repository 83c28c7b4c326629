//! Deterministic synthetic trials for benches and `scripts/bench-vs-evo` (no RNG crate needed).

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use sitar_estimator::{TimeUnit, Trajectory, write_tum};

/// xorshift64* – enough randomness for benchmark data.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Roughly normal (sum of uniforms).
    pub fn normal(&mut self) -> f64 {
        (0..4).map(|_| self.next_f64()).sum::<f64>() * 3f64.sqrt() - 2.0 * 3f64.sqrt()
    }
}

/// `count` trials of `poses` poses at 20 Hz (TUM VI-like) with drift and their own world
/// frames; with `drops`, every third trial loses about 1 % of its frames (so those pairs need
/// a real association).
pub fn trials(count: usize, poses: usize, seed: u64, drops: bool) -> Vec<Trajectory> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|index| {
            let world = DQuat::from_euler(
                glam::EulerRot::YXZ,
                rng.normal(),
                rng.normal() * 0.3,
                rng.normal() * 0.3,
            );
            let shift = DVec3::new(rng.normal(), rng.normal(), rng.normal());
            let (mut drift_t, mut drift_r) = (DVec3::ZERO, DVec3::ZERO);
            let mut stamps = Vec::with_capacity(poses);
            let mut positions = Vec::with_capacity(poses);
            let mut orientations = Vec::with_capacity(poses);
            for k in 0..poses {
                let t = k as f64 / 20.0;
                let hard = (k / 300) % 3 == 1;
                let sigma = if hard { 0.003 } else { 0.0003 };
                drift_t += DVec3::new(rng.normal(), rng.normal(), rng.normal()) * sigma;
                drift_r += DVec3::new(rng.normal(), rng.normal(), rng.normal()) * sigma * 0.5;
                let drop = drops && index % 3 == 2 && rng.next_f64() < 0.01 && k > 0;
                if drop {
                    continue;
                }
                let p = DVec3::new(
                    1.5 * (0.2 * t).sin(),
                    0.3 * (0.5 * t).sin() + 1.4,
                    1.2 * (0.15 * t).cos(),
                );
                let q = DQuat::from_rotation_y(0.6 * (0.1 * t).sin())
                    * DQuat::from_rotation_x(0.1 * (0.4 * t).sin());
                let d = DQuat::from_scaled_axis(drift_r);
                stamps.push(1_403_636_579_763_555_584 + k as i64 * 50_000_000);
                positions.push(world * (d * p + drift_t) + shift);
                orientations.push((world * d * q).normalize());
            }
            Trajectory {
                stamps,
                positions,
                orientations,
                time_unit: TimeUnit::Nanoseconds,
            }
        })
        .collect()
}

/// Writes `trials(count, poses, seed, drops)` as `trial_NNN.txt` into `dir`; returns the paths.
pub fn write_trials(
    dir: &Path,
    count: usize,
    poses: usize,
    seed: u64,
    drops: bool,
) -> Vec<PathBuf> {
    std::fs::create_dir_all(dir).expect("create bench data dir");
    trials(count, poses, seed, drops)
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let path = dir.join(format!("trial_{i:03}.txt"));
            let mut file =
                std::io::BufWriter::new(std::fs::File::create(&path).expect("create trial"));
            write_tum(t, &mut file).expect("write trial");
            path
        })
        .collect()
}
