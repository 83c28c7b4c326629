//! The two error models a recording carries: how the simulated SLAM system drifts
//! ([`DriftModel`], played by `trial`) and the RANSAC tracker's knobs ([`RansacModel`],
//! played by `ransac_tracker`).

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::checks;

/// How a simulated SLAM system errs. All magnitudes grow with the *difficulty* of the view
/// (0 = feature-rich, 1 = nothing to track; see [`crate::View`]), smoothed over
/// `difficulty_time_constant_s` because tracked features outlive the view they came from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriftModel {
    /// RMS translation error (m) a trial accumulates over `calibration_frames` frames while
    /// the camera sees a feature-rich view.
    pub window_error_m: f64,
    /// The window length `window_error_m` refers to (frames).
    pub calibration_frames: u32,
    /// Error gain at difficulty `d` is `1 + hard_gain·d²` (17× on a blank wall by default).
    pub hard_gain: f64,
    /// Frame-to-frame correlation of the translation error (AR(1) coefficient).
    pub correlation: f64,
    /// Degrees of freedom of the Student-t innovations (heavy tails; must exceed 2).
    pub tail_dof: f64,
    /// Per-frame rotation noise (degrees, per axis) on a feature-rich view.
    pub rotation_noise_deg: f64,
    /// Share (0–1, of standard deviation) of the error that every trial makes alike.
    pub shared_share: f64,
    /// Log-normal sigma of a per-trial quality factor: some runs are better than others.
    pub trial_quality_sigma: f64,
    /// Per-frame probability of a sudden jump (bad RANSAC hypothesis, relocalisation).
    pub jump_rate: f64,
    /// Additional jump probability per frame at difficulty 1 (scaled by `d²`).
    pub jump_rate_hard: f64,
    /// Additional jump probability per frame when the view is all glass (reflections).
    pub jump_rate_reflective: f64,
    /// Scale (m) of the Pareto-distributed jump size (shape 2, capped at 0.5 m).
    pub jump_scale_m: f64,
    /// Smoothing time constant of the difficulty seen by the tracker (s).
    pub difficulty_time_constant_s: f64,
    /// Give each trial its own random world frame (yaw and offset), as separate SLAM runs have.
    pub world_offset: bool,
}

impl Default for DriftModel {
    fn default() -> Self {
        Self {
            window_error_m: 0.006,
            calibration_frames: 10,
            hard_gain: 16.0,
            correlation: 0.8,
            tail_dof: 3.0,
            rotation_noise_deg: 0.02,
            shared_share: 0.3,
            trial_quality_sigma: 0.2,
            jump_rate: 0.0003,
            jump_rate_hard: 0.004,
            jump_rate_reflective: 0.006,
            jump_scale_m: 0.03,
            difficulty_time_constant_s: 0.25,
            world_offset: true,
        }
    }
}

impl DriftModel {
    /// Checks every parameter; the error names the field.
    pub fn validate(&self) -> Result<(), (String, String)> {
        checks::positive(&[
            ("window_error_m", self.window_error_m),
            ("jump_scale_m", self.jump_scale_m),
            (
                "difficulty_time_constant_s",
                self.difficulty_time_constant_s,
            ),
        ])?;
        checks::non_negative(&[
            ("hard_gain", self.hard_gain),
            ("rotation_noise_deg", self.rotation_noise_deg),
            ("trial_quality_sigma", self.trial_quality_sigma),
        ])?;
        checks::unit_range(&[
            ("correlation", self.correlation, 0.999),
            ("shared_share", self.shared_share, 1.0),
            ("jump_rate", self.jump_rate, 1.0),
            ("jump_rate_hard", self.jump_rate_hard, 1.0),
            ("jump_rate_reflective", self.jump_rate_reflective, 1.0),
        ])?;
        if !(self.tail_dof.is_finite() && self.tail_dof > 2.0) {
            return Err((
                "tail_dof".into(),
                format!("must exceed 2, got {}", self.tail_dof),
            ));
        }
        if self.calibration_frames == 0 {
            return Err(("calibration_frames".into(), "must be at least 1".into()));
        }
        Ok(())
    }

    /// Per-frame translation innovation scale (m) that makes an AR(1) error sum to an RMS 3D
    /// error of `window_error_m` over `calibration_frames` frames.
    pub(crate) fn frame_sigma(&self) -> f64 {
        let n = f64::from(self.calibration_frames);
        let rho = self.correlation;
        // Variance of a sum of n stationary AR(1) values with unit variance.
        let var_sum: f64 = n + 2.0
            * (1..self.calibration_frames)
                .map(|k| (n - f64::from(k)) * rho.powi(k as i32))
                .sum::<f64>();
        self.window_error_m / (3.0 * var_sum).sqrt()
    }

    /// Error gain at (smoothed) difficulty `d`.
    pub fn gain(&self, difficulty: f64) -> f64 {
        1.0 + self.hard_gain * difficulty * difficulty
    }

    /// Probability of a jump in one frame at difficulty `d` and reflectivity `r`.
    pub fn jump_probability(&self, difficulty: f64, reflectivity: f64) -> f64 {
        (self.jump_rate
            + self.jump_rate_hard * difficulty * difficulty
            + self.jump_rate_reflective * reflectivity)
            .min(1.0)
    }
}

/// Every knob of the RANSAC tracker and of the camera and IMU it replays
/// ([`crate::Recording::with_ransac_model`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RansacModel {
    /// Focal length of the tracking camera (pixels).
    pub focal_px: f64,
    /// Image width (pixels).
    pub width_px: f64,
    /// Image height (pixels).
    pub height_px: f64,
    /// Scale of every surface's feature noise ([`crate::SurfaceKind::feature_noise_px`]).
    pub pixel_noise_scale: f64,
    /// Light level, 1 = normal: landmark density scales with it, noise and spurious corners
    /// with its inverse.
    pub lighting: f64,
    /// Scale of every surface's spurious corners ([`crate::SurfaceKind::spurious_per_view`]).
    pub spurious_scale: f64,
    /// Probability that a visible landmark is detected in a frame.
    pub detection_probability: f64,
    /// Probability that a reflection in glass is matched to the real landmark it mirrors.
    pub reflection_match_probability: f64,
    /// The detector's real-time budget: at most this many features are matched per frame, a
    /// fixed subset of the recording when more are detected (every replay sees the same).
    pub features_per_frame: usize,
    /// RANSAC iterations per frame: the fixed real-time budget. Where the inlier share is low
    /// (blank walls, reflections) so few iterations often miss the largest consensus, and the
    /// trials disagree; a large budget finds it every time.
    pub ransac_hypotheses: usize,
    /// Inlier threshold (pixels).
    pub inlier_threshold_px: f64,
    /// Fewest inliers for a visual pose; with fewer the frame rides on the inertial prior.
    pub min_inliers: usize,
    /// Inlier count at which vision and the inertial prior weigh the same in the fusion.
    pub prior_weight_inliers: f64,
    /// Smallest angle (degrees) between two rays to triangulate a new landmark.
    pub min_parallax_deg: f64,
    /// Farthest a visual pose may be from the prior (metres) right after a visual fix; the
    /// gate widens by this much again every `gate_growth_frames` frames without one, so the
    /// tracker relocalises after coasting.
    pub gate_m: f64,
    /// Largest rotation (degrees) a visual pose may be from the prior, widening likewise.
    pub gate_deg: f64,
    /// Frames without a visual fix over which the gate widens by its own size.
    pub gate_growth_frames: f64,
    /// Gyroscope noise per frame (degrees per axis).
    pub gyro_noise_deg: f64,
    /// Accelerometer white noise, as a velocity error per frame (m/s).
    pub accel_noise_mps: f64,
    /// Magnitude of the accelerometer bias (m/s²): while vision is lost the velocity error
    /// grows by it every second, the same in every trial.
    pub accel_bias_mps2: f64,
    /// Give each trial its own random world frame (yaw and offset), as separate SLAM runs have.
    pub world_offset: bool,
}

impl Default for RansacModel {
    fn default() -> Self {
        Self {
            focal_px: 500.0,
            width_px: 640.0,
            height_px: 480.0,
            pixel_noise_scale: 1.0,
            lighting: 1.0,
            spurious_scale: 1.0,
            detection_probability: 0.85,
            reflection_match_probability: 0.3,
            features_per_frame: 40,
            ransac_hypotheses: 16,
            inlier_threshold_px: 5.0,
            min_inliers: 4,
            prior_weight_inliers: 20.0,
            min_parallax_deg: 4.0,
            gate_m: 0.08,
            gate_deg: 4.0,
            gate_growth_frames: 15.0,
            gyro_noise_deg: 0.03,
            accel_noise_mps: 0.01,
            accel_bias_mps2: 0.03,
            world_offset: true,
        }
    }
}

impl RansacModel {
    /// Checks every parameter; the error names the field.
    pub fn validate(&self) -> Result<(), (String, String)> {
        checks::positive(&[
            ("focal_px", self.focal_px),
            ("width_px", self.width_px),
            ("height_px", self.height_px),
            ("lighting", self.lighting),
            ("inlier_threshold_px", self.inlier_threshold_px),
            ("prior_weight_inliers", self.prior_weight_inliers),
            ("gate_m", self.gate_m),
            ("gate_deg", self.gate_deg),
            ("gate_growth_frames", self.gate_growth_frames),
        ])?;
        checks::non_negative(&[
            ("pixel_noise_scale", self.pixel_noise_scale),
            ("spurious_scale", self.spurious_scale),
            ("min_parallax_deg", self.min_parallax_deg),
            ("gyro_noise_deg", self.gyro_noise_deg),
            ("accel_noise_mps", self.accel_noise_mps),
            ("accel_bias_mps2", self.accel_bias_mps2),
        ])?;
        checks::unit_range(&[
            ("detection_probability", self.detection_probability, 1.0),
            (
                "reflection_match_probability",
                self.reflection_match_probability,
                1.0,
            ),
        ])?;
        if self.lighting > 10.0 || self.width_px > 1e5 || self.height_px > 1e5 {
            return Err((
                "lighting".into(),
                "lighting must be at most 10 and the image at most 100 000 pixels wide".into(),
            ));
        }
        let counts = [
            ("features_per_frame", self.features_per_frame, 3, 256),
            ("ransac_hypotheses", self.ransac_hypotheses, 1, 100_000),
            ("min_inliers", self.min_inliers, 3, 256),
        ];
        for (name, v, lo, hi) in counts {
            if !(lo..=hi).contains(&v) {
                return Err((name.into(), format!("must be in [{lo}, {hi}], got {v}")));
            }
        }
        Ok(())
    }

    /// Normalised image coordinates of a camera-frame (computer-vision) point, if it is in
    /// front, within 6 m and inside the image.
    pub(crate) fn project(&self, p: DVec3) -> Option<glam::DVec2> {
        if p.z <= 0.1 || p.length_squared() > 36.0 {
            return None;
        }
        let (x, y) = (p.x / p.z, p.y / p.z);
        let (u, v) = (
            x * self.focal_px + self.width_px / 2.0,
            y * self.focal_px + self.height_px / 2.0,
        );
        ((0.0..self.width_px).contains(&u) && (0.0..self.height_px).contains(&v))
            .then_some(glam::DVec2::new(x, y))
    }
}
