//! A calibration for the estimate from one walk, built in code so the binding tests know
//! every number it gives: the one-run model says error = 0.05 m × (path + 1 mm) / 0.1 m over
//! a window, interval ×0.5 … ×2. Shared by the C ABI test here and the Kotlin and C# host
//! tests (`tests/tests/bindings_*.rs` write it where the host tests read it).
#![allow(dead_code)] // each test uses some of it

// One glob: the 2021 (sitar-ffi) and 2024 (sitar-tests) styles sort a list differently.
use sitar_core::calibration::*;

/// The calibration for windows of `window_frames` frames; `informative` as the file says.
pub fn walk_calibration(window_frames: usize, informative: bool) -> Calibration {
    Calibration {
        format: CALIBRATION_FORMAT.into(),
        version: 2,
        fitted_on: FittedOn {
            sequences: Vec::new(),
            setting: "trim_mean_30".into(),
            window_frames,
            pose_relation: "trans_part".into(),
            unit: "m".into(),
            coverage: 0.8,
            t_max_diff_s: 0.01,
        },
        informative,
        models: vec![CalibrationModel {
            target: Target::Live,
            runs: RunCount::One,
            kind: "log_linear".into(),
            features: vec![Feature::PathM],
            offsets: vec![Feature::PathM.offset()],
            smoothing_windows: 0,
            coefficients: vec![0.05f64.ln() - 0.1f64.ln(), 1.0],
            spread_match: 0.0,
            center: 0.0,
            stretch: 1.0,
            interval: IntervalModel {
                method: "in_sample".into(),
                log_lower: 0.5f64.ln(),
                log_upper: 2.0f64.ln(),
                residuals: 100,
            },
            informative,
            scores: None,
        }],
    }
}

/// The same with only a model for the expected error from several runs: no model for one
/// run, so the phone must refuse it.
pub fn expected_only_calibration() -> Calibration {
    let mut c = walk_calibration(10, true);
    c.models[0].target = Target::Expected;
    c.models[0].runs = RunCount::Several;
    c
}

/// Frames of the test walk after the start: 40 at 30 fps, 5 mm a frame for the first 20, 3 cm
/// for the next 10 and 6 cm for the last 10, along +x; a depth sample (a wall 2 m ahead) at
/// every midpoint. Its sub-trajectories 0 and 1 are low, 2 and 3 high; one marker, at sub 2.
pub const WALK_FRAMES: i64 = 40;
/// The walk's frame interval (ns).
pub const WALK_FRAME_NS: i64 = 33_333_333;

/// The walk's x position at frame `i` (0 = start; the stop, frame 41, is where frame 40 is).
pub fn walk_x(i: i64) -> f64 {
    let i = i.min(WALK_FRAMES);
    let slow = i.min(20) as f64 * 0.005;
    let fast = (i.min(30) - 20).max(0) as f64 * 0.03;
    let faster = (i - 30).max(0) as f64 * 0.06;
    slow + fast + faster
}

/// The error the calibration gives the window of 10 frames from frame `start`.
pub fn walk_error(start: i64) -> f64 {
    let path = walk_x(start + 10) - walk_x(start);
    0.05 * (path + Feature::PathM.offset()) / 0.1
}
