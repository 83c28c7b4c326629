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
    assert!(
        printed.contains("candidates") && !printed.contains("warning:"),
        "{printed}"
    );
    let c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!(c["format"], "sitar-calibration");
    assert_eq!(c["version"], 2);
    assert_eq!(c["informative"], true);
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
    let f = |v: &serde_json::Value| v.as_f64().unwrap();
    let models = c["models"].as_array().unwrap();
    let kinds: Vec<(&str, &str)> = models
        .iter()
        .map(|m| (m["target"].as_str().unwrap(), m["runs"].as_str().unwrap()))
        .collect();
    assert_eq!(
        kinds,
        [
            ("live", "one"),
            ("live", "several"),
            ("expected", "several")
        ]
    );
    for m in models {
        let scores = &m["scores"];
        assert_eq!(scores["method"], "leave_one_sequence_out");
        assert_eq!(
            scores["truth"],
            if m["target"] == "live" {
                "own"
            } else {
                "expected"
            }
        );
        let cal = &scores["calibrated"];
        assert!(f(&cal["spearman"]) >= 0.55, "{m}");
        assert!((0.70..=0.90).contains(&f(&cal["coverage"])), "{cal}");
        // Every candidate scored, the kept one marked.
        let candidates = scores["candidates"].as_array().unwrap();
        assert!(candidates.len() >= 4);
        assert_eq!(candidates.iter().filter(|c| c["chosen"] == true).count(), 1);
        for s in scores["sequences"].as_array().unwrap() {
            let coverage = f(&s["calibrated"]["coverage"]);
            assert!(
                (0.70..=0.90).contains(&coverage),
                "{}: {coverage}",
                s["name"]
            );
        }
    }
    // One run has no spread: its model reads the run's own motion only.
    assert!(
        models[0]["features"]
            .as_array()
            .unwrap()
            .iter()
            .all(|f| f != "ln_spread")
    );
    let expected = &models[2]["scores"];
    let cal = &expected["calibrated"];
    assert!(f(&cal["spearman"]) >= 0.60, "{cal}");
    assert!(f(&cal["macro_f1"]) >= 0.47, "{cal}");
    assert!(f(&cal["accuracy"]) >= 0.70, "{cal}");
    for s in expected["sequences"].as_array().unwrap() {
        let ratio = f(&s["calibrated"]["median_ratio"]);
        assert!(
            (0.8..=1.25).contains(&ratio),
            "{}: ratio {ratio}",
            s["name"]
        );
    }
    let raw = &expected["raw"];
    assert!(f(&cal["spearman"]) > f(&raw["spearman"]), "{raw} {cal}");
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

fn shared_set(name: &str) -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/real-runs")
        .join(name);
    if dir.is_dir() {
        Some(dir)
    } else {
        println!("SKIPPED {name} tests: {} is missing", dir.display());
        None
    }
}

#[test]
fn one_run_is_enough_with_a_calibration_and_refused_without() {
    let Some(runs) = real_runs() else { return };
    let dir = temp_dir("one-run");
    let file = dir.join("mh.json");
    // Fitted on the Machine Hall, applied to the Vicon room.
    ok(&[
        "calibrate",
        runs.join("MH_04").to_str().unwrap(),
        runs.join("MH_05").to_str().unwrap(),
        "-o",
        file.to_str().unwrap(),
    ]);
    let run = runs.join("V1_02/runs/run9.txt");
    let run = run.to_str().unwrap();
    let message = fails(&["estimate", run]);
    assert!(
        message.contains("one run has no spread to measure") && message.contains("--calibration"),
        "{message}"
    );
    let one: serde_json::Value = serde_json::from_str(&ok(&[
        "estimate",
        run,
        "--calibration",
        file.to_str().unwrap(),
        "--format",
        "json",
    ]))
    .unwrap();
    assert_eq!(one["target"], "live");
    assert_eq!(one["runs"], 1);
    assert_eq!(one["informative"], true);
    let windows = one["windows"].as_array().unwrap();
    // One window per start frame of the run: every pose but the last ten.
    let poses = std::fs::read_to_string(runs.join("V1_02/runs/run9.txt"))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .count();
    assert_eq!(windows.len(), poses - 10);
    for w in windows {
        assert!(w["raw_m"].is_null(), "one run has no spread: {w}");
        let (lo, e, hi) = (
            w["lower_m"].as_f64().unwrap(),
            w["error_m"].as_f64().unwrap(),
            w["upper_m"].as_f64().unwrap(),
        );
        assert!(
            lo < e && e < hi && ["low", "medium", "high"].contains(&w["class"].as_str().unwrap())
        );
    }
    // The same run as the live one, with replays: keyed by its stamps, the spread kept.
    let replays: Vec<String> = (5..9)
        .map(|i| {
            runs.join(format!("V1_02/runs/run{i}.txt"))
                .display()
                .to_string()
        })
        .collect();
    let mut args = vec![
        "estimate",
        "--live",
        run,
        "--calibration",
        file.to_str().unwrap(),
    ];
    args.extend(replays.iter().map(String::as_str));
    args.extend(["--format", "json"]);
    let live: serde_json::Value = serde_json::from_str(&ok(&args)).unwrap();
    assert_eq!(
        (live["target"].clone(), live["runs"].clone()),
        ("live".into(), 5.into())
    );
    let live_windows = live["windows"].as_array().unwrap();
    assert_eq!(live_windows.len(), windows.len());
    assert!(
        live_windows
            .iter()
            .all(|w| w["raw_m"].as_f64().is_some_and(|r| r > 0.0))
    );
    assert!(
        live_windows
            .iter()
            .zip(windows)
            .all(|(a, b)| a["start"] == b["start"])
    );
    // Without --live, several runs give the expected error.
    let mut args = vec!["estimate", "--calibration", file.to_str().unwrap(), run];
    args.extend(replays.iter().map(String::as_str));
    args.extend(["--format", "json"]);
    let expected: serde_json::Value = serde_json::from_str(&ok(&args)).unwrap();
    assert_eq!(expected["target"], "expected");

    // Each run against its own error: alone and with its replays, with the coverage.
    let evaluated: serde_json::Value = serde_json::from_str(&ok(&[
        "evaluate",
        runs.join("V1_02").to_str().unwrap(),
        "--calibration",
        file.to_str().unwrap(),
        "--truth",
        "own",
        "--trial_counts",
        "1,5",
        "--format",
        "json",
        "--no_plot",
        "--bootstrap",
        "10",
    ]))
    .unwrap();
    assert_eq!(evaluated["truth"], "own");
    let agreement = evaluated["agreement"].as_array().unwrap();
    assert_eq!(agreement.len(), 2);
    let alone = &agreement[0];
    assert_eq!(alone["trials"], 1);
    let rank = alone["spearman"][0].as_f64().unwrap();
    assert!(
        rank > 0.45,
        "one run against its own error on a held-out sequence: {rank}"
    );
    assert!(alone["coverage"].as_f64().unwrap() > 0.6, "{alone}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn kitti_runs_do_not_predict_their_error_and_calibrate_says_so() {
    let Some(kitti) = shared_set("kitti-orbslam2-stereo") else {
        return;
    };
    let dir = temp_dir("kitti");
    let file = dir.join("kitti.json");
    let printed = ok(&[
        "calibrate",
        kitti.to_str().unwrap(),
        "--split",
        "2",
        "-o",
        file.to_str().unwrap(),
    ]);
    let warnings: Vec<&str> = printed
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert!(!warnings.is_empty(), "{printed}");
    assert!(warnings[0].contains("Spearman's ρ 0.2"), "{}", warnings[0]);
    let c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!(c["informative"], false);
    // The interval still holds what it says on held-out sequences.
    for m in c["models"].as_array().unwrap() {
        let coverage = m["scores"]["calibrated"]["coverage"].as_f64().unwrap();
        assert!((0.65..=0.95).contains(&coverage), "{coverage}");
    }
    // And every estimate made with it says so.
    let run = kitti.join("00/runs/run4.txt");
    let one: serde_json::Value = serde_json::from_str(&ok(&[
        "estimate",
        run.to_str().unwrap(),
        "--calibration",
        file.to_str().unwrap(),
        "--format",
        "json",
    ]))
    .unwrap();
    assert_eq!(one["informative"], false);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn tum_ground_truth_with_repeated_stamps_is_read_as_published() {
    let Some(tum) = shared_set("tum-orbslam2-rgbd") else {
        return;
    };
    let dir = temp_dir("repeated");
    // fr1_desk as published, with one stamp repeated as fr2_xyz repeats 8.
    let seq = dir.join("fr1_desk");
    std::fs::create_dir_all(seq.join("runs")).unwrap();
    for i in 0..5 {
        std::fs::copy(
            tum.join(format!("fr1_desk/runs/run{i}.txt")),
            seq.join(format!("runs/run{i}.txt")),
        )
        .unwrap();
    }
    let gt = std::fs::read_to_string(tum.join("fr1_desk/ground_truth.txt")).unwrap();
    let mut lines: Vec<&str> = gt.lines().collect();
    let at = lines.iter().position(|l| !l.starts_with('#')).unwrap() + 100;
    let repeated = lines[at].split_once(' ').unwrap().0.to_owned();
    let copy = format!("{repeated} {}", lines[at + 1].split_once(' ').unwrap().1);
    lines.insert(at + 1, &copy);
    std::fs::write(seq.join("ground_truth.txt"), lines.join("\n") + "\n").unwrap();
    let (out, err) = support::run::ok_both(&[
        "calibrate",
        seq.to_str().unwrap(),
        "--split",
        "2",
        "-o",
        dir.join("c.json").to_str().unwrap(),
    ]);
    assert!(out.contains("wrote"), "{out}");
    assert!(
        err.contains("warning:")
            && err.contains("1 repeated timestamp(s)")
            && err.contains("both poses are kept"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
