//! `sitar evaluate` over several sequences equals an independent evo + numpy/scipy +
//! scikit-learn computation (`tests/golden/make_sequences_golden.py`): averaged scores, the
//! estimate/truth ratio, Spearman's rank correlation, the calibration and the threshold sweep
//! to 1e-12; the bootstrap interval within Monte Carlo error of scipy's.

use std::path::Path;
use std::process::Command;

fn evaluate(args: &[&str]) -> serde_json::Value {
    let out = Command::new(env!("CARGO_BIN_EXE_sitar"))
        .arg("evaluate")
        .args(args)
        .output()
        .expect("run sitar");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn close(got: &serde_json::Value, want: &serde_json::Value, tolerance: f64, what: &str) {
    match (got.as_f64(), want.as_f64()) {
        (Some(g), Some(w)) => assert!((g - w).abs() <= tolerance, "{what}: {g} vs {w}"),
        _ => assert!(got.is_null() && want.is_null(), "{what}: {got} vs {want}"),
    }
}

#[test]
fn evaluate_over_sequences_equals_scipy_and_sklearn() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/sequences");
    let want: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("expected.json")).unwrap()).unwrap();
    let got = evaluate(&[
        dir.to_str().unwrap(),
        "--trial_counts",
        "2,4",
        "--format",
        "json",
        "--no_plot",
        "--calibrate",
        "--train",
        "2",
        "--sweep",
        "--bootstrap",
        "20000",
    ]);
    assert_eq!(got["sequences"].as_array().unwrap().len(), 4);
    let (g, w) = (
        got["averaged"].as_array().unwrap(),
        want["averaged"].as_array().unwrap(),
    );
    assert_eq!(g.len(), w.len());
    for (g, w) in g.iter().zip(w) {
        for key in ["setting", "trials", "boundaries_m"] {
            assert_eq!(g[key], w[key]);
        }
        for key in ["accuracy", "macro_f1", "sensitivity", "specificity"] {
            close(&g[key]["mean"], &w[key], 1e-12, key);
        }
        // Percentile bootstrap over 4 sequences: ours and scipy's resample differently.
        close(
            &g["accuracy"]["low"],
            &w["accuracy_low"],
            0.02,
            "accuracy low",
        );
        close(
            &g["accuracy"]["high"],
            &w["accuracy_high"],
            0.02,
            "accuracy high",
        );
    }
    let (g, w) = (
        got["agreement"].as_array().unwrap(),
        want["agreement"].as_array().unwrap(),
    );
    assert_eq!(g.len(), w.len());
    for (g, w) in g.iter().zip(w) {
        assert_eq!((&g["setting"], &g["trials"]), (&w["setting"], &w["trials"]));
        // Ranks: windows whose values tie exactly in one implementation may differ in the
        // last bit in the other (evo's arithmetic vs ours), which moves Spearman's r a little.
        for (key, tolerance) in [("median_ratio", 1e-12), ("spearman", 2e-3)] {
            for (x, y) in g[key]
                .as_array()
                .unwrap()
                .iter()
                .zip(w[key].as_array().unwrap())
            {
                close(x, y, tolerance, key);
            }
        }
        close(
            &g["pooled_median_ratio"],
            &w["pooled_median_ratio"],
            1e-12,
            "pooled ratio",
        );
    }
    let (g, w) = (
        got["calibration"]["rows"].as_array().unwrap(),
        want["calibration"].as_array().unwrap(),
    );
    assert_eq!(g.len(), w.len());
    for (g, w) in g.iter().zip(w) {
        close(&g["scale"], &w["scale"], 1e-12, "scale");
        close(
            &g["held_out_raw"]["accuracy"],
            &w["raw"][0],
            1e-12,
            "raw accuracy",
        );
        close(
            &g["held_out_raw"]["macro_f1"],
            &w["raw"][1],
            1e-12,
            "raw F1",
        );
        close(
            &g["held_out_calibrated"]["accuracy"],
            &w["calibrated"][0],
            1e-12,
            "calibrated accuracy",
        );
        close(
            &g["held_out_calibrated"]["macro_f1"],
            &w["calibrated"][1],
            1e-12,
            "calibrated F1",
        );
    }
    let (g, w) = (
        got["sweeps"].as_array().unwrap(),
        want["sweeps"].as_array().unwrap(),
    );
    assert_eq!(g.len(), w.len());
    for (g, w) in g.iter().zip(w) {
        for key in ["setting", "trials", "positives", "negatives"] {
            assert_eq!(g[key], w[key], "{key}");
        }
        close(&g["boundary_m"], &w["boundary_m"], 0.0, "boundary");
        close(&g["roc_auc"], &w["roc_auc"], 1e-12, "ROC AUC");
        close(
            &g["average_precision"],
            &w["average_precision"],
            1e-12,
            "average precision",
        );
    }
}

#[test]
fn window_frames_sweep_and_bad_arguments() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/sequences");
    let seq = dir.join("seq_01");
    let got = evaluate(&[
        seq.to_str().unwrap(),
        "--trial_counts",
        "4",
        "--settings",
        "trim_mean_30",
        "--window_frames",
        "5,10,20",
        "--format",
        "json",
        "--no_plot",
    ]);
    let frames: Vec<u64> = got["averaged"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["window_frames"].as_u64().unwrap())
        .collect();
    assert_eq!(frames, [5, 5, 5, 10, 10, 10, 20, 20, 20]);
    // Longer windows: fewer of them (a 3 s sequence at 30 fps has 90 poses).
    let windows = &got["sequences"][0]["truth_windows"];
    assert_eq!(windows, &serde_json::json!([85, 80, 70]));
    let fails = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_sitar"))
            .arg("evaluate")
            .args(args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1));
        String::from_utf8(out.stderr).unwrap()
    };
    let err = fails(&[seq.to_str().unwrap(), "--calibrate", "--no_plot"]);
    assert!(
        err.contains("--calibrate needs at least 2 sequences"),
        "{err}"
    );
    let err = fails(&[
        dir.to_str().unwrap(),
        "--calibrate",
        "--train",
        "4",
        "--no_plot",
    ]);
    assert!(err.contains("--train 4"), "{err}");
    let err = fails(&[dir.join("seq_01/trials").to_str().unwrap(), "--no_plot"]);
    assert!(err.contains("neither a sequence"), "{err}");
}
