//! Relative error at sub-trajectory lengths (`relative_errors`) and rpg's pairing and
//! alignment (`rpg_associate`, `rpg_align`) against an independent numpy implementation of
//! rpg_trajectory_evaluation's definitions (`scripts/golden/make_relative_golden.py`): a
//! synthetic pair with a stop, missing poses, scale and drift, in every alignment, and the
//! real EuRoC runs of `../shared/data/real-runs`.

use std::path::{Path, PathBuf};

use serde_json::Value;
use sitar_estimator::{
    RPG_MAX_DIFF_NS, RpgAlignment, Statistics, absolute_translation_errors, cumulative_path_length,
    lengths_from_percents, read_tum, relative_errors, rpg_align, rpg_associate,
};

/// Tolerance against numpy, relative to the value (absolute below 1).
const TOLERANCE: f64 = 1e-9;

/// A path in the golden file is relative to the repository root.
fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn assert_close(what: &str, got: f64, want: f64) {
    assert!(
        (got - want).abs() <= TOLERANCE * want.abs().max(1.0),
        "{what}: got {got}, numpy {want} (difference {:e})",
        got - want
    );
}

fn statistic(s: &Statistics, name: &str) -> f64 {
    match name {
        "rmse" => s.rmse,
        "mean" => s.mean,
        "median" => s.median,
        "std" => s.std,
        "min" => s.min,
        "max" => s.max,
        other => panic!("unknown statistic {other}"),
    }
}

fn check(case: &Value) {
    let name = case["name"].as_str().unwrap();
    let reference = read_tum(&repo(case["reference"].as_str().unwrap())).unwrap();
    let estimate = read_tum(&repo(case["estimate"].as_str().unwrap())).unwrap();
    let pairs = rpg_associate(&estimate, &reference, RPG_MAX_DIFF_NS);
    assert_eq!(
        pairs.len() as u64,
        case["pairs"].as_u64().unwrap(),
        "{name}"
    );
    for (k, want) in case["first_pairs"].as_array().unwrap().iter().enumerate() {
        let want = (want[0].as_u64().unwrap(), want[1].as_u64().unwrap());
        assert_eq!(
            (pairs[k].0 as u64, pairs[k].1 as u64),
            want,
            "{name} pair {k}"
        );
    }
    let est = estimate.reduce_to_ids(&pairs.iter().map(|p| p.0).collect::<Vec<_>>());
    let gt = reference.reduce_to_ids(&pairs.iter().map(|p| p.1).collect::<Vec<_>>());
    let alignment = RpgAlignment {
        align_type: case["align_type"].as_str().unwrap().parse().unwrap(),
        num_frames: case["align_num_frames"].as_i64().unwrap(),
    };
    let transform = rpg_align(&est, &gt, alignment).unwrap();
    assert_close(&format!("{name} scale"), transform.scale, f(&case["scale"]));
    for i in 0..3 {
        assert_close(
            &format!("{name} t[{i}]"),
            transform.translation[i],
            f(&case["translation"][i]),
        );
        for j in 0..3 {
            assert_close(
                &format!("{name} R[{i}][{j}]"),
                transform.rotation.col(j)[i],
                f(&case["rotation"][i][j]),
            );
        }
    }
    let ape = Statistics::from_errors(&absolute_translation_errors(&est, &gt, &transform));
    assert_close(&format!("{name} APE"), ape.rmse, f(&case["ape_rmse_m"]));
    let path = cumulative_path_length(&reference);
    assert_close(&format!("{name} path"), path, f(&case["path_length_m"]));
    let lengths: Vec<f64> = match case["percents"].as_array() {
        Some(p) => lengths_from_percents(path, &p.iter().map(f).collect::<Vec<_>>()),
        None => case["lengths"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| f(&l["length_m"]))
            .collect(),
    };
    let got = relative_errors(&gt, &est, transform.scale, &lengths).unwrap();
    for (at, want) in got.iter().zip(case["lengths"].as_array().unwrap()) {
        // Truncated to centimetres on both sides: equal, not merely close.
        assert_eq!(at.length_m, f(&want["length_m"]), "{name}");
        let what = format!("{name} at {} m", at.length_m);
        assert_eq!(
            at.samples.len() as u64,
            want["count"].as_u64().unwrap(),
            "{what}"
        );
        let metric = |s: &sitar_estimator::RelativeSample, m: &str| match m {
            "trans_m" => s.trans_m,
            "trans_percent" => s.trans_percent,
            "rot_deg" => s.rot_deg,
            "rot_deg_per_m" => s.rot_deg_per_m,
            "yaw_deg" => s.yaw_deg,
            "roll_pitch_deg" => s.roll_pitch_deg,
            other => panic!("unknown metric {other}"),
        };
        if let Some(stats) = want["stats"].as_object() {
            for (m, wanted) in stats {
                let values: Vec<f64> = at.samples.iter().map(|s| metric(s, m)).collect();
                let s = Statistics::from_errors(&values);
                for (k, v) in wanted.as_object().unwrap() {
                    assert_close(&format!("{what} {m} {k}"), statistic(&s, k), f(v));
                }
            }
        }
        for (k, w) in want["samples"].as_array().unwrap().iter().enumerate() {
            let s = &at.samples[k * 37];
            assert_eq!(s.start as u64, w["start"].as_u64().unwrap(), "{what}");
            assert_eq!(s.end as u64, w["end"].as_u64().unwrap(), "{what}");
            for m in [
                "trans_m",
                "trans_percent",
                "rot_deg",
                "rot_deg_per_m",
                "yaw_deg",
                "roll_pitch_deg",
            ] {
                assert_close(
                    &format!("{what} sample {} {m}", s.start),
                    metric(s, m),
                    f(&w[m]),
                );
            }
        }
    }
}

#[test]
fn relative_errors_equal_numpy_on_synthetic_and_real_runs() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/golden_relative.json");
    let golden: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let cases = golden["cases"].as_array().unwrap();
    assert!(cases.len() >= 12);
    for case in cases {
        check(case);
    }
}

#[test]
fn bad_lengths_and_unpaired_trajectories_are_errors() {
    let gt = read_tum(&repo("rust/estimator/tests/data/relative/synthetic_gt.txt")).unwrap();
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = relative_errors(&gt, &gt, 1.0, &[bad]).unwrap_err();
        assert!(e.to_string().contains("lengths"), "{e}");
    }
    let shorter = gt.reduce_to_ids(&[0, 1, 2]);
    let e = relative_errors(&gt, &shorter, 1.0, &[1.0]).unwrap_err();
    assert!(e.to_string().contains("equal length"), "{e}");
    // Against itself every error is zero, at every length that fits.
    let at = relative_errors(&gt, &gt, 1.0, &[1.0, 5.0]).unwrap();
    assert!(at.iter().all(|a| !a.samples.is_empty()));
    assert!(
        at.iter()
            .flat_map(|a| &a.samples)
            .all(|s| s.trans_m < 1e-12 && s.rot_deg < 1e-5)
    );
}
