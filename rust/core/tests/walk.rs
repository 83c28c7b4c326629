//! The estimate from one walk on the phone: a calibration colours the walk when it stops,
//! offline, from the walk's own motion; the backend's results replace it; the session folder
//! keeps the walk and the calibration.

use glam::{DQuat, DVec3};
use sitar_core::calibration::{
    CALIBRATION_FORMAT, Calibration, CalibrationModel, Feature, FittedOn, IntervalModel, RunCount,
    Target,
};
use sitar_core::{ErrorClass, Pose, Session, SessionConfig};

/// A one-run model: error = 0.05 m × (path / 0.1 m) over a window, interval ×0.5 … ×2.
fn calibration(window_frames: usize) -> Calibration {
    let offset = Feature::PathM.offset();
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
        informative: true,
        models: vec![CalibrationModel {
            target: Target::Live,
            runs: RunCount::One,
            kind: "log_linear".into(),
            features: vec![Feature::PathM],
            offsets: vec![offset],
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
            informative: true,
            scores: None,
        }],
    }
}

/// 40 frames at 30 fps: slow (5 mm a frame) for the first 20, fast (3 cm) after.
fn walk(session: &mut Session) {
    let dt = 33_333_333;
    let mut x = 0.0;
    session
        .start(0, Pose::new(DVec3::ZERO, DQuat::IDENTITY))
        .unwrap();
    for i in 1..=40 {
        x += if i <= 20 { 0.005 } else { 0.03 };
        session
            .frame(i * dt, Pose::new(DVec3::new(x, 0.0, 0.0), DQuat::IDENTITY))
            .unwrap();
    }
    session
        .stop(41 * dt, Pose::new(DVec3::new(x, 0.0, 0.0), DQuat::IDENTITY))
        .unwrap();
}

#[test]
fn the_walk_is_coloured_when_it_stops() {
    let mut session = Session::new(SessionConfig::default());
    session.set_calibration(&calibration(10).to_json()).unwrap();
    walk(&mut session);
    assert_eq!(session.walk_len(), 41);
    let results = session.results().expect("coloured at stop");
    assert_eq!(results.source.as_deref(), Some("walk"));
    assert_eq!(results.target.as_deref(), Some("live"));
    assert_eq!((results.runs, results.informative), (Some(1), Some(true)));
    // One window per start frame: 41 poses, windows of 10 frames.
    assert_eq!(results.windows.len(), 31);
    // Sub-trajectory 0 walked 5 cm: 0.05 × (0.05 + 0.001)/0.1 m; sub-trajectory 2 walked 30 cm.
    let slow = session.subtrajectory_error(0).unwrap();
    assert!((slow - 0.05 * 0.051 / 0.1).abs() < 1e-12, "{slow}");
    assert_eq!(session.subtrajectory_class(0), ErrorClass::Low);
    assert_eq!(session.subtrajectory_class(2), ErrorClass::High);
    let window = session.subtrajectory_window(2).unwrap();
    let interval = window.interval.unwrap();
    assert!((interval.upper / window.error - 2.0).abs() < 1e-12);
    // The backend's results replace the walk's.
    session
        .load_results("start,error\n0,0.01\n333333330,0.01\n666666660,0.01\n")
        .unwrap();
    assert_eq!(session.subtrajectory_class(2), ErrorClass::Low);
    assert_eq!(session.results().unwrap().source, None);
    // A calibration given after them keeps them: only the walk's own estimate is redone.
    session.set_calibration(&calibration(10).to_json()).unwrap();
    assert_eq!(session.subtrajectory_class(2), ErrorClass::Low);
    assert_eq!(session.results().unwrap().calibration, None);
}

#[test]
fn a_calibration_after_the_stop_colours_at_once_and_the_folder_keeps_it() {
    let mut session = Session::new(SessionConfig::default());
    walk(&mut session);
    assert!(session.results().is_none());
    session.set_calibration(&calibration(10).to_json()).unwrap();
    assert_eq!(session.subtrajectory_class(2), ErrorClass::High);
    let dir = std::env::temp_dir().join(format!("sitar-walk-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    session.save(&dir).unwrap();
    let walk_text = std::fs::read_to_string(dir.join("walk.txt")).unwrap();
    assert_eq!(walk_text.lines().count(), 41);
    let back = Session::load(&dir).unwrap();
    assert_eq!(back, session);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_calibration_that_does_not_fit_is_refused_and_changes_nothing() {
    let mut session = Session::new(SessionConfig::default());
    let err = session
        .set_calibration(&calibration(20).to_json())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("20 window frames") && err.contains("10 window frames"),
        "{err}"
    );
    let err = session
        .set_calibration("{\"format\": 1")
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("invalid") || err.contains("calibration"),
        "{err}"
    );
    // A version-1 file has no model for one run.
    let mut expected_only = calibration(10);
    expected_only.models[0].target = Target::Expected;
    expected_only.models[0].runs = RunCount::Several;
    let err = session
        .set_calibration(&expected_only.to_json())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("no model for the live error from 1 run"),
        "{err}"
    );
    walk(&mut session);
    assert!(session.results().is_none() && session.calibration().is_none());
}
