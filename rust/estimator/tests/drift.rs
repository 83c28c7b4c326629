//! The KITTI drift metric (`drift`) against an independent numpy implementation of the
//! devkit's formulas (`scripts/golden/make_drift_goldens.py`: a synthetic KITTI pair with a
//! known drift, and a real EuRoC run read from `../shared/data/real-runs`), and against
//! closed forms (a constant scale error, a constant yaw-rate error).

use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use serde_json::Value;
use sitar_estimator::{
    Drift, DriftOptions, ReadOptions, SegmentDuration, TimeUnit, Trajectory,
    associate_trajectories, drift, read_kitti, read_tum_with,
};

/// Relative tolerance against numpy.
const TOLERANCE: f64 = 1e-9;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// `../shared/data` beside the repository (real runs are not copied into it).
fn shared(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(name)
}

fn cases() -> Vec<Value> {
    let text = std::fs::read_to_string(data("golden_drift.json")).unwrap();
    serde_json::from_str::<Value>(&text)
        .unwrap()
        .as_array()
        .unwrap()
        .clone()
}

fn case(name: &str) -> Value {
    cases()
        .into_iter()
        .find(|c| c["name"] == name)
        .unwrap_or_else(|| panic!("no case {name}"))
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn assert_close(what: &str, got: f64, want: f64) {
    assert!(
        (got - want).abs() <= TOLERANCE * want.abs(),
        "{what}: got {got}, numpy {want} (relative {:e})",
        ((got - want) / want).abs()
    );
}

fn options(case: &Value) -> DriftOptions {
    let lengths_m = case["lengths_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(f)
        .collect();
    let duration = match case["duration"].as_str().unwrap() {
        "frames" => SegmentDuration::Frames {
            interval_s: f(&case["interval_s"]),
        },
        _ => SegmentDuration::Stamps,
    };
    DriftOptions {
        lengths_m,
        step: case["step"].as_u64().unwrap() as usize,
        duration,
        ..DriftOptions::default()
    }
    .with_speed_step(f(&case["speed_step_m_s"]))
}

/// The averages and bins of `got` equal the golden's to [`TOLERANCE`].
fn assert_averages(name: &str, got: &Drift, want: &Value) {
    assert_eq!(
        got.segments.len() as u64,
        want["segments"].as_u64().unwrap()
    );
    assert_close(
        &format!("{name} t_err"),
        got.t_err_percent,
        f(&want["t_err_percent"]),
    );
    assert_close(
        &format!("{name} r_err"),
        got.r_err_deg_per_m,
        f(&want["r_err_deg_per_m"]),
    );
    for (key, centre, bins) in [
        ("by_length", "length_m", &got.by_length),
        ("by_speed", "speed_m_s", &got.by_speed),
    ] {
        let expected = want[key].as_array().unwrap();
        assert_eq!(bins.len(), expected.len(), "{name} {key}");
        for (bin, w) in bins.iter().zip(expected) {
            let at = format!("{name} {key} {}", bin.centre);
            assert_eq!(bin.centre, f(&w[centre]), "{at}");
            assert_eq!(bin.segments as u64, w["segments"].as_u64().unwrap(), "{at}");
            assert_close(&at, bin.t_err_percent, f(&w["t_err_percent"]));
            assert_close(&at, bin.r_err_deg_per_m, f(&w["r_err_deg_per_m"]));
        }
    }
}

#[test]
fn synthetic_kitti_pair_equals_numpy() {
    let case = case("kitti_synthetic");
    let reference = read_kitti(&data(case["reference"].as_str().unwrap())).unwrap();
    let estimate = read_kitti(&data(case["estimate"].as_str().unwrap())).unwrap();
    let result = drift(&reference, &estimate, &options(&case)).unwrap();
    assert_averages("kitti", &result, &case);
    let segments = case["segment_list"].as_array().unwrap();
    assert_eq!(result.segments.len(), segments.len());
    for (got, want) in result.segments.iter().zip(segments) {
        let at = format!("segment {}..{}", got.first, got.last);
        assert_eq!(got.first as u64, want["first"].as_u64().unwrap(), "{at}");
        assert_eq!(got.last as u64, want["last"].as_u64().unwrap(), "{at}");
        assert_eq!(got.length_m, f(&want["length_m"]), "{at}");
        assert_close(&at, got.speed_m_s, f(&want["speed_m_s"]));
        assert_close(&at, got.t_err_percent, f(&want["t_err_percent"]));
        assert_close(&at, got.r_err_deg_per_m, f(&want["r_err_deg_per_m"]));
    }
    // The drift put in: 1.5 % scale, 0.005 deg/m of yaw (plus noise).
    assert!(
        (result.t_err_percent - 1.5).abs() < 1.0,
        "{}",
        result.t_err_percent
    );
    assert!((result.r_err_deg_per_m - 0.005).abs() < 0.002);
    // Every length has segments; the devkit's speed bins 20, 22 and 24 m/s are filled.
    assert_eq!(result.by_length.len(), 8);
    let speeds: Vec<f64> = result.by_speed.iter().map(|b| b.centre).collect();
    assert_eq!(speeds, [20.0, 22.0, 24.0]);
}

#[test]
fn real_euroc_run_equals_numpy() {
    let root = shared("real-runs");
    if !root.is_dir() {
        eprintln!(
            "SKIPPED real_euroc_run_equals_numpy: {} is missing",
            root.display()
        );
        return;
    }
    let first = case("euroc_mh04_run0");
    let read = |key: &str| {
        let path = shared(first[key].as_str().unwrap());
        read_tum_with(&path, &ReadOptions::EVO).unwrap().0
    };
    let (reference, estimate) =
        associate_trajectories(&read("reference"), &read("estimate"), 0.01, 0.0).unwrap();
    assert_eq!(
        reference.len() as u64,
        first["associated_poses"].as_u64().unwrap()
    );
    for name in ["euroc_mh04_run0", "euroc_mh04_run0_speed_0.2"] {
        let case = case(name);
        let result = drift(&reference, &estimate, &options(&case)).unwrap();
        assert_averages(name, &result, &case);
        if let Some(segments) = case["segment_list"].as_array() {
            let got: Vec<[u64; 2]> = result
                .segments
                .iter()
                .map(|s| [s.first as u64, s.last as u64])
                .collect();
            let want: Vec<[u64; 2]> = segments
                .iter()
                .map(|s| [s[0].as_u64().unwrap(), s[1].as_u64().unwrap()])
                .collect();
            assert_eq!(got, want, "{name}: segment poses");
        }
    }
}

/// Poses along x, `spacing` apart (10 Hz stamps); the estimate's body turns by
/// `yaw_deg_per_m` (about z) per metre of path and moves `scale` times as far per step.
fn walk(n: usize, spacing: f64, scale: f64, yaw_deg_per_m: f64) -> Trajectory {
    let mut positions = vec![DVec3::ZERO];
    let mut orientations = vec![DQuat::IDENTITY];
    for k in 1..n {
        let (p, q) = (positions[k - 1], orientations[k - 1]);
        positions.push(p + q * DVec3::new(spacing * scale, 0.0, 0.0));
        orientations.push(q * DQuat::from_rotation_z((yaw_deg_per_m * spacing).to_radians()));
    }
    Trajectory {
        stamps: (0..n as i64).map(|i| i * 100_000_000).collect(),
        positions,
        orientations,
        time_unit: TimeUnit::Nanoseconds,
    }
}

#[test]
fn a_constant_scale_error_gives_that_share_of_every_segment() {
    // A pose every 5 cm; an estimate 4 % too long (and one 3 % too short).
    let reference = walk(2001, 0.05, 1.0, 0.0);
    let options = DriftOptions {
        lengths_m: vec![10.0, 20.0, 50.0],
        ..DriftOptions::default()
    };
    for scale in [1.04, 0.97] {
        let estimate = walk(2001, 0.05, scale, 0.0);
        let result = drift(&reference, &estimate, &options).unwrap();
        let distances = reference.distances();
        for s in &result.segments {
            // The devkit divides by the nominal length L; the segment's path is the first
            // pose beyond L, so the error is |s − 1|·path/L: |s − 1| when poses are dense.
            let path = distances[s.last] - distances[s.first];
            let want = (scale - 1.0f64).abs() * 100.0 * path / s.length_m;
            assert!((s.t_err_percent - want).abs() < 1e-9, "{s:?}: want {want}");
            assert!((s.t_err_percent - (scale - 1.0f64).abs() * 100.0).abs() < 0.021);
            assert_eq!(s.r_err_deg_per_m, 0.0);
        }
        assert_eq!(result.by_length.len(), 3);
        assert!((result.t_err_percent - (scale - 1.0f64).abs() * 100.0).abs() < 0.021);
    }
}

#[test]
fn a_constant_yaw_rate_error_gives_that_rate() {
    // The estimate turns 0.5 deg per metre of path; the truth goes straight.
    let reference = walk(1001, 0.1, 1.0, 0.0);
    let estimate = walk(1001, 0.1, 1.0, 0.5);
    let options = DriftOptions {
        lengths_m: vec![2.0, 5.0, 10.0],
        ..DriftOptions::default()
    };
    let result = drift(&reference, &estimate, &options).unwrap();
    let distances = reference.distances();
    for s in &result.segments {
        let path = distances[s.last] - distances[s.first];
        // The error pose turns by the estimate's heading change over the path.
        let want = 0.5 * path / s.length_m;
        assert!(
            (s.r_err_deg_per_m - want).abs() < 1e-9,
            "{s:?}: want {want}"
        );
        // A turning estimate also ends elsewhere: its k steps of 0.1 m, each turned by
        // 0.05° more, against the straight path.
        let step = (0.5f64 * 0.1).to_radians();
        let (x, y) = (0..s.last - s.first).fold((0.0, 0.0), |(x, y), j| {
            let heading = j as f64 * step;
            (x + 0.1 * heading.cos(), y + 0.1 * heading.sin())
        });
        let want_t = 100.0 * (x - path).hypot(y) / s.length_m;
        assert!(
            (s.t_err_percent - want_t).abs() < 1e-9 * want_t,
            "{s:?}: want {want_t}"
        );
    }
    assert!((result.r_err_deg_per_m - 0.5).abs() < 0.03);
}

#[test]
fn speed_comes_from_frames_or_stamps() {
    // 1 m per pose, 10 Hz stamps, L = 10 m: the segment ends 11 poses on (11 m of path).
    // From the stamps, 10 m in 1.1 s; from the devkit's frame count, 10 m in 12 frames of
    // 0.1 s.
    let reference = walk(101, 1.0, 1.0, 0.0);
    let frames = DriftOptions {
        lengths_m: vec![10.0],
        ..DriftOptions::default()
    };
    let stamps = DriftOptions {
        duration: SegmentDuration::Stamps,
        ..frames.clone()
    };
    let by_frames = drift(&reference, &reference, &frames).unwrap();
    let by_stamps = drift(&reference, &reference, &stamps).unwrap();
    for (a, b) in by_frames.segments.iter().zip(&by_stamps.segments) {
        assert_eq!(a.last - a.first, 11);
        assert!((a.speed_m_s - 10.0 / (0.1 * 12.0)).abs() < 1e-12);
        assert!((b.speed_m_s - 10.0 / 1.1).abs() < 1e-9);
        assert_eq!((a.t_err_percent, a.r_err_deg_per_m), (0.0, 0.0));
    }
    // Speeds of 8.3 and 9.1 m/s: the devkit's bins 8 and 10 m/s (± 2) take every segment.
    let centres: Vec<f64> = by_frames.by_speed.iter().map(|b| b.centre).collect();
    assert_eq!(centres, [8.0, 10.0]);
}

#[test]
fn a_rigid_transform_of_the_estimate_changes_nothing() {
    let reference = walk(600, 0.1, 1.0, 0.0);
    let mut estimate = walk(600, 0.1, 1.02, 0.3);
    let options = DriftOptions {
        lengths_m: vec![5.0, 10.0],
        ..DriftOptions::default()
    };
    let before = drift(&reference, &estimate, &options).unwrap();
    estimate.transform(
        DQuat::from_euler(glam::EulerRot::ZYX, 0.7, -0.2, 1.1),
        DVec3::new(3.0, -4.0, 5.0),
        1.0,
    );
    let after = drift(&reference, &estimate, &options).unwrap();
    for (a, b) in before.segments.iter().zip(&after.segments) {
        assert!((a.t_err_percent - b.t_err_percent).abs() < 1e-9);
        assert!((a.r_err_deg_per_m - b.r_err_deg_per_m).abs() < 1e-9);
    }
}
