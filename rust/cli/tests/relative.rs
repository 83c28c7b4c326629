//! `sitar relative`: rpg_trajectory_evaluation's relative error at sub-trajectory lengths on
//! the real EuRoC runs of `../shared/data/real-runs`, against the estimator's numpy golden
//! (`scripts/golden/make_relative_golden.py`); runs and `across_trials`; CSV; box plots.

mod support;

use std::path::{Path, PathBuf};

use serde_json::Value;
use support::run::ok;

fn real() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/real-runs/euroc-vio/MH_04");
    if dir.join("ground_truth.txt").is_file() {
        Some(dir)
    } else {
        eprintln!("SKIPPED: {} is missing", dir.display());
        None
    }
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn one_run_equals_numpy_and_runs_summarise() {
    let Some(dir) = real() else { return };
    let gt = dir.join("ground_truth.txt");
    let (run0, run7) = (dir.join("runs/run0.txt"), dir.join("runs/run7.txt"));
    let (gt, run0, run7) = (
        gt.to_str().unwrap(),
        run0.to_str().unwrap(),
        run7.to_str().unwrap(),
    );
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../estimator/tests/data/golden_relative.json");
    let golden: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let case = |name: &str| {
        golden["cases"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["name"] == name)
            .unwrap()
            .clone()
    };
    // evo's pairing (0.01 s) pairs these runs as rpg's does (stamps within 5 ms); posyaw has
    // no scale, so the errors are rpg's.
    let doc: Value = serde_json::from_str(&ok(&[
        "relative",
        "tum",
        gt,
        run0,
        "-a",
        "--yaw_only",
        "--format",
        "json",
    ]))
    .unwrap();
    let want = case("MH_04_run0_posyaw");
    assert_eq!(doc["metric"], "relative");
    for (got, want) in doc["by_length"]
        .as_array()
        .unwrap()
        .iter()
        .zip(want["lengths"].as_array().unwrap())
    {
        assert_eq!(f(&got["length_m"]), f(&want["length_m"]));
        assert_eq!(got["samples"], want["count"]);
        for m in [
            "trans_m",
            "trans_percent",
            "rot_deg",
            "rot_deg_per_m",
            "yaw_deg",
            "roll_pitch_deg",
        ] {
            for s in ["rmse", "mean", "median", "std", "min", "max"] {
                let (g, w) = (f(&got[m][s]), f(&want["stats"][m][s]));
                assert!(
                    (g - w).abs() <= 1e-9 * w.abs().max(1.0),
                    "{m} {s}: {g} vs {w}"
                );
            }
        }
    }
    // Two runs: each run's document as alone, and the summary over runs.
    let two: Value = serde_json::from_str(&ok(&[
        "relative",
        "tum",
        gt,
        run0,
        run7,
        "--lengths",
        "8,16",
        "--format",
        "json",
    ]))
    .unwrap();
    assert_eq!(two["runs"], 2);
    let alone: Value = serde_json::from_str(&ok(&[
        "relative",
        "tum",
        gt,
        run7,
        "--lengths",
        "8,16",
        "--format",
        "json",
    ]))
    .unwrap();
    assert_eq!(two["trials"][1], alone);
    let means: Vec<f64> = (0..2)
        .map(|k| {
            let t = &two["trials"][k]["by_length"];
            let (a, b) = (&t[0], &t[1]);
            let (na, nb) = (f(&a["samples"]), f(&b["samples"]));
            (f(&a["trans_m"]["mean"]) * na + f(&b["trans_m"]["mean"]) * nb) / (na + nb)
        })
        .collect();
    let across = f(&two["across_trials"]["trans_m"]["mean"]);
    assert!((across - (means[0] + means[1]) / 2.0).abs() < 1e-12);
    // CSV: one row per sub-trajectory.
    let csv = ok(&[
        "relative",
        "tum",
        gt,
        run0,
        "--lengths",
        "8",
        "--format",
        "csv",
    ]);
    let count = two["trials"][0]["by_length"][0]["samples"]
        .as_u64()
        .unwrap();
    assert_eq!(csv.lines().count() as u64, count + 1);
    assert!(csv.starts_with("trial,estimate,length_m,start,end,trans_m,"));
    // The box plots, one file per error.
    let tmp = tempfile::tempdir().unwrap();
    let plot = tmp.path().join("rel.svg");
    ok(&[
        "relative",
        "tum",
        gt,
        run0,
        run7,
        "--lengths",
        "8,16",
        "--save_plot",
        plot.to_str().unwrap(),
    ]);
    for m in ["trans_percent", "yaw_deg", "roll_pitch_deg"] {
        assert!(tmp.path().join(format!("rel_{m}.svg")).is_file(), "{m}");
    }
}
