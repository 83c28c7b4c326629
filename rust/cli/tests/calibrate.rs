//! `sitar calibrate` on the real repeated SLAM runs (`../shared/data/real-runs/euroc-vio`),
//! and the calibration applied by `sitar estimate` and scored by `sitar evaluate`.

mod support;

use std::path::{Path, PathBuf};

use support::run::{fails, ok};

fn real_runs() -> Option<PathBuf> {
    let dir =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/real-runs/euroc-vio");
    if dir.join("MH_04/ground_truth.txt").is_file() {
        Some(dir)
    } else {
        println!("SKIPPED calibrate tests: {} is missing", dir.display());
        None
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sitar-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn calibrate_real_runs_then_estimate_and_evaluate_with_it() {
    let Some(runs) = real_runs() else { return };
    let dir = temp_dir("calibrate");
    let file = dir.join("euroc-vio.json");
    let printed = ok(&[
        "calibrate",
        runs.to_str().unwrap(),
        "-o",
        file.to_str().unwrap(),
    ]);
    assert!(printed.contains("leave one sequence out"), "{printed}");
    let c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!(c["format"], "sitar-calibration");
    assert_eq!(c["version"], 1);
    let fitted = &c["fitted_on"];
    let names: Vec<&str> = fitted["sequences"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["MH_04", "MH_05", "V1_02"]);
    for s in fitted["sequences"].as_array().unwrap() {
        assert_eq!(
            (s["set_a"].as_u64(), s["set_b"].as_u64()),
            (Some(5), Some(5))
        );
    }
    assert_eq!(fitted["setting"], "trim_mean_30");
    assert_eq!(fitted["window_frames"], 10);
    assert_eq!(fitted["pose_relation"], "trans_part");
    assert_eq!(fitted["unit"], "m");
    assert_eq!(fitted["coverage"], 0.8);

    // The targets, on sequences left out of the fit (the README's figures).
    let scores = &c["scores"];
    let f = |v: &serde_json::Value| v.as_f64().unwrap();
    for s in scores["sequences"].as_array().unwrap() {
        let ratio = f(&s["calibrated"]["median_ratio"]);
        assert!(
            (0.75..=1.33).contains(&ratio),
            "{}: ratio {ratio}",
            s["name"]
        );
        let coverage = f(&s["calibrated"]["coverage"]);
        assert!(
            (0.65..=0.95).contains(&coverage),
            "{}: coverage {coverage}",
            s["name"]
        );
    }
    let (raw, cal) = (&scores["raw"], &scores["calibrated"]);
    assert!(f(&cal["spearman"]) >= 0.47, "{cal}");
    assert!(f(&cal["accuracy"]) >= 0.74, "{cal}");
    assert!(f(&cal["macro_f1"]) >= f(&raw["macro_f1"]), "{raw} {cal}");
    assert!((0.70..=0.90).contains(&f(&cal["coverage"])), "{cal}");
    assert!(
        f(&cal["high_called_low"]) < f(&raw["high_called_low"]),
        "{raw} {cal}"
    );

    // sitar estimate --calibration: the bounds in JSON, the calibrated error in the CSV.
    let set_b: Vec<String> = (5..10)
        .map(|i| {
            runs.join(format!("V1_02/runs/run{i}.txt"))
                .display()
                .to_string()
        })
        .collect();
    let mut args: Vec<&str> = vec!["estimate"];
    args.extend(set_b.iter().map(String::as_str));
    args.extend(["--calibration", file.to_str().unwrap()]);
    let json: serde_json::Value =
        serde_json::from_str(&ok(&[args.as_slice(), &["--format", "json"]].concat())).unwrap();
    assert_eq!(json["calibration"], "euroc-vio");
    let windows = json["windows"].as_array().unwrap();
    assert!(windows.len() > 1000);
    let raw_json: serde_json::Value = {
        let plain: Vec<&str> = args[..args.len() - 2].to_vec();
        serde_json::from_str(&ok(&[plain.as_slice(), &["--format", "json"]].concat())).unwrap()
    };
    for (w, r) in windows.iter().zip(raw_json["windows"].as_array().unwrap()) {
        let (lower, error, upper) = (f(&w["lower_m"]), f(&w["error_m"]), f(&w["upper_m"]));
        assert!(lower < error && error < upper, "{w}");
        assert_eq!(
            w["raw_m"], r["error_m"],
            "raw_m keeps the uncalibrated value"
        );
        assert_eq!(w["start"], r["start"]);
    }
    let csv = ok(&args);
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("start,error"));
    for (line, w) in lines.zip(windows) {
        let error: f64 = line.split(',').nth(1).unwrap().parse().unwrap();
        assert_eq!(
            error,
            f(&w["error_m"]),
            "the CSV's error is the calibrated one"
        );
    }

    // A calibration for another setting or window is refused, naming both.
    let message = fails(&[args.as_slice(), &["--setting", "median", "-d", "20"]].concat());
    assert!(
        message.contains("fitted for setting trim_mean_30, 10 window frames")
            && message.contains("the estimate is setting median, 20 window frames"),
        "{message}"
    );

    // sitar evaluate --calibration: the calibrated estimate scored with its coverage.
    let evaluated: serde_json::Value = serde_json::from_str(&ok(&[
        "evaluate",
        runs.join("V1_02").to_str().unwrap(),
        "--calibration",
        file.to_str().unwrap(),
        "--trial_counts",
        "5",
        "--format",
        "json",
        "--no_plot",
        "--bootstrap",
        "10",
    ]))
    .unwrap();
    assert_eq!(evaluated["calibrated_by"], "euroc-vio");
    let agreement = &evaluated["agreement"][0];
    assert_eq!(agreement["setting"], "trim_mean_30");
    let coverage = f(&agreement["coverage"]);
    assert!((0.5..=1.0).contains(&coverage), "{agreement}");
    assert!(agreement["high_called_low"][0].is_number());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn evaluate_takes_runs_with_a_split() {
    let Some(runs) = real_runs() else { return };
    let seq = runs.join("MH_05");
    let json = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec![
            "evaluate",
            seq.to_str().unwrap(),
            "--settings",
            "trim_mean_30",
            "--format",
            "json",
            "--no_plot",
            "--bootstrap",
            "10",
        ];
        args.extend(extra);
        serde_json::from_str(&ok(&args)).unwrap()
    };
    let halves = json(&[]);
    assert_eq!(
        (halves["trials_a"].as_u64(), halves["trials_b"].as_u64()),
        (Some(5), Some(5))
    );
    let three = json(&["--split", "3"]);
    assert_eq!(
        (three["trials_a"].as_u64(), three["trials_b"].as_u64()),
        (Some(3), Some(7))
    );
    // The starting point on this sequence: informative, not exact.
    let rank = three["agreement"][0]["spearman"][0].as_f64().unwrap();
    assert!(rank > 0.3, "{rank}");
    let stderr = fails(&[
        "evaluate",
        seq.to_str().unwrap(),
        "--split",
        "9",
        "--no_plot",
    ]);
    assert!(stderr.contains("--split 9"));
}
