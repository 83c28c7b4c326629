//! `sitar drift`, and repeated runs of one system (`sitar ape|rpe|drift FORMAT REF EST1 EST2
//! …`): the statistics over runs against numpy and evo
//! (`scripts/golden/make_multirun_goldens.py`, on the real runs of
//! `../shared/data/real-runs`), the text, CSV and JSON outputs, the per-run archives that
//! `sitar res` reads, the plots; and that one estimate keeps evo's output.

mod support;

use std::path::{Path, PathBuf};

use serde_json::Value;
use support::run::{ok_in, sitar_in};

/// Relative tolerance against numpy and evo.
const TOLERANCE: f64 = 1e-9;

/// The real runs' sequence folder, or `None` (the test says SKIPPED) when it is missing.
fn real_sequence(test: &str) -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/real-runs/euroc-vio/MH_04");
    if dir.join("ground_truth.txt").is_file() {
        Some(dir)
    } else {
        eprintln!("SKIPPED {test}: {} is missing", dir.display());
        None
    }
}

fn expected() -> Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/multirun/expected.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The estimator's drift goldens (the synthetic KITTI pair and its numpy results).
fn estimator_data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../estimator/tests/data")
        .join(name)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn assert_close(what: &str, got: &Value, want: &Value) {
    let (g, w) = (f(got), f(want));
    assert!(
        (g - w).abs() <= TOLERANCE * w.abs().max(1e-300),
        "{what}: sitar {g}, numpy {w}"
    );
}

fn strings(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_owned())
        .collect()
}

/// Asserts drift document `got` equals numpy's `want`, `what` in every message: its segments,
/// where its speeds come from (`speed_from`), both errors and both binnings.
fn assert_drift(what: &str, got: &Value, want: &Value, speed_from: &str) {
    assert_eq!(got["segments"], want["segments"], "{what}");
    assert_eq!(got["speed_from"], speed_from, "{what}");
    for key in ["t_err_percent", "r_err_deg_per_m"] {
        assert_close(&format!("{what} {key}"), &got[key], &want[key]);
    }
    for (bins, centre) in [("by_length", "length_m"), ("by_speed", "speed_m_s")] {
        let (g, w) = (
            got[bins].as_array().unwrap(),
            want[bins].as_array().unwrap(),
        );
        assert_eq!(g.len(), w.len(), "{what} {bins}");
        for (a, b) in g.iter().zip(w) {
            assert_eq!(a[centre], b[centre], "{what} {bins}");
            assert_eq!(a["segments"], b["segments"], "{what} {bins}");
            for key in ["t_err_percent", "r_err_deg_per_m"] {
                assert_close(&format!("{what} {bins} {key}"), &a[key], &b[key]);
            }
        }
    }
}

/// Asserts the summaries over runs of `got` (`across_trials`) equal those of golden `want`,
/// `metric` in every message.
fn assert_across_trials(metric: &str, got: &Value, want: &Value) {
    for (stat, summary) in want["across_trials"].as_object().unwrap() {
        for name in ["mean", "median", "min", "max", "std"] {
            assert_close(
                &format!("{metric} {stat} {name}"),
                &got["across_trials"][stat][name],
                &summary[name],
            );
        }
    }
}

fn json_of(dir: &Path, args: &[String]) -> Value {
    serde_json::from_str(&ok_in(dir, args)).unwrap()
}

#[test]
fn ape_over_five_real_runs_equals_evo_and_numpy() {
    let Some(dir) = real_sequence("ape_over_five_real_runs_equals_evo_and_numpy") else {
        return;
    };
    let want = &expected()["ape"];
    let got = json_of(&dir, &strings(&want["args"]));
    assert_eq!(got["runs"], 5);
    assert_eq!(got["metric"], "ape");
    let trials = got["trials"].as_array().unwrap();
    for (k, (trial, evo)) in trials
        .iter()
        .zip(want["trials"].as_array().unwrap())
        .enumerate()
    {
        // Each run's document is the one a single-estimate run prints.
        assert_eq!(trial["estimate"], evo["estimate"]);
        assert_eq!(trial["alignment"], "se3");
        for (name, value) in evo["statistics"].as_object().unwrap() {
            assert_close(
                &format!("run {k} {name}"),
                &trial["statistics"][name],
                value,
            );
        }
        let single = json_of(
            &dir,
            &strings(&serde_json::json!([
                "ape",
                "tum",
                "ground_truth.txt",
                evo["estimate"],
                "-a",
                "--format",
                "json"
            ])),
        );
        assert_eq!(&single, trial, "run {k}");
    }
    assert_eq!(want["across_trials"].as_object().unwrap().len(), 7);
    assert_across_trials("ape", &got, want);
}

#[test]
fn drift_over_five_real_runs_equals_numpy() {
    let Some(dir) = real_sequence("drift_over_five_real_runs_equals_numpy") else {
        return;
    };
    let want = &expected()["drift"];
    let got = json_of(&dir, &strings(&want["args"]));
    assert_eq!(got["runs"], 5);
    for (k, (trial, numpy)) in got["trials"]
        .as_array()
        .unwrap()
        .iter()
        .zip(want["trials"].as_array().unwrap())
        .enumerate()
    {
        assert_drift(&format!("run {k}"), trial, numpy, "stamps");
    }
    assert_across_trials("drift", &got, want);
}

#[test]
fn one_estimate_keeps_evos_table_and_several_add_the_runs_tables() {
    let Some(dir) = real_sequence("one_estimate_keeps_evos_table_and_several_add_the_runs_tables")
    else {
        return;
    };
    let one = ok_in(
        &dir,
        &["ape", "tum", "ground_truth.txt", "runs/run0.txt", "-a"],
    );
    assert!(one.starts_with(
        "APE w.r.t. translation part (m)\n(with SE(3) Umeyama alignment)\n\n       max\t0.410731\n"
    ));
    assert!(!one.contains("trial"));
    let single = json_of(
        &dir,
        &strings(&serde_json::json!([
            "ape",
            "tum",
            "ground_truth.txt",
            "runs/run0.txt",
            "--format",
            "json"
        ])),
    );
    assert!(single.get("trials").is_none() && single.get("statistics").is_some());

    let several = ok_in(
        &dir,
        &[
            "rpe",
            "tum",
            "ground_truth.txt",
            "runs/run0.txt",
            "runs/run1.txt",
            "-d",
            "10",
        ],
    );
    let lines: Vec<&str> = several.lines().collect();
    assert_eq!(lines[0], "RPE w.r.t. translation part (m)");
    assert!(
        several.contains("\n2 runs against ground_truth.txt\n"),
        "{several}"
    );
    let header = lines
        .iter()
        .position(|l| l.starts_with("trial  estimate"))
        .unwrap();
    assert!(lines[header + 1].starts_with("0      runs/run0.txt"));
    assert!(lines[header + 2].starts_with("1      runs/run1.txt"));
    let across = lines
        .iter()
        .position(|l| l.starts_with("across trials"))
        .unwrap();
    assert_eq!(
        lines[across].split_whitespace().collect::<Vec<_>>(),
        ["across", "trials", "mean", "median", "min", "max", "std"]
    );
    let rows: Vec<&str> = lines[across + 1..]
        .iter()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert_eq!(rows, ["rmse", "mean", "median", "std", "min", "max", "sse"]);

    // CSV: a row per run, then one per summary over the runs.
    let csv = ok_in(
        &dir,
        &[
            "rpe",
            "tum",
            "ground_truth.txt",
            "runs/run0.txt",
            "runs/run1.txt",
            "runs/run2.txt",
            "--format",
            "csv",
        ],
    );
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(
        rows[0].join(","),
        "trial,estimate,rmse,mean,median,std,min,max,sse"
    );
    assert_eq!(rows.len(), 1 + 3 + 5);
    assert_eq!((rows[3][0], rows[3][1]), ("2", "runs/run2.txt"));
    let rmse: Vec<f64> = (1..4).map(|k| rows[k][2].parse().unwrap()).collect();
    let mean = rmse.iter().sum::<f64>() / 3.0;
    assert_eq!(rows[4][0], "mean");
    assert!((rows[4][2].parse::<f64>().unwrap() - mean).abs() < 1e-15);
    let max: f64 = rows[7][2].parse().unwrap();
    assert_eq!(max, rmse.iter().copied().fold(f64::MIN, f64::max));
}

#[test]
fn runs_save_one_archive_each_that_res_reads_and_a_box_plot() {
    let Some(seq) = real_sequence("runs_save_one_archive_each_that_res_reads_and_a_box_plot")
    else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let gt = seq.join("ground_truth.txt");
    let runs: Vec<PathBuf> = (0..3)
        .map(|k| seq.join(format!("runs/run{k}.txt")))
        .collect();
    let mut args: Vec<String> = vec!["ape".into(), "tum".into(), gt.display().to_string()];
    args.extend(runs.iter().map(|r| r.display().to_string()));
    args.extend(
        [
            "-a",
            "--save_results",
            "ape.zip",
            "--save_plot",
            "ape.svg",
            "--format",
            "json",
            "-o",
            "ape.json",
        ]
        .map(String::from),
    );
    let stdout = ok_in(out.path(), &args);
    assert!(
        stdout.contains("Plot saved to ape_box_plot.svg"),
        "{stdout}"
    );
    let svg = std::fs::read_to_string(out.path().join("ape_box_plot.svg")).unwrap();
    for k in 0..3 {
        assert!(
            svg.contains(&format!("run{k}.txt")),
            "run {k} in the box plot"
        );
        assert!(out.path().join(format!("ape_trial{k}.zip")).is_file());
    }
    assert!(!out.path().join("ape.zip").exists());
    // `sitar res` reads the per-run archives, and the multi-run JSON as the same results.
    let from_zips = ok_in(
        out.path(),
        &[
            "res",
            "ape_trial0.zip",
            "ape_trial1.zip",
            "ape_trial2.zip",
            "--save_table",
            "zips.csv",
        ],
    );
    let from_json = ok_in(out.path(), &["res", "ape.json", "--save_table", "json.csv"]);
    assert_eq!(from_zips, from_json);
    assert!(from_json.contains("run2.txt"), "{from_json}");
    let table = |name: &str| std::fs::read_to_string(out.path().join(name)).unwrap();
    assert_eq!(table("zips.csv"), table("json.csv"));
    assert_eq!(table("json.csv").lines().count(), 4);
}

#[test]
fn drift_on_the_synthetic_kitti_pair_equals_numpy_and_plots() {
    let cases: Value = serde_json::from_str(
        &std::fs::read_to_string(estimator_data("golden_drift.json")).unwrap(),
    )
    .unwrap();
    let want = &cases[0];
    assert_eq!(want["name"], "kitti_synthetic");
    let out = tempfile::tempdir().unwrap();
    let (gt, est) = (
        estimator_data("drift/kitti_gt.txt"),
        estimator_data("drift/kitti_est.txt"),
    );
    let (gt, est) = (gt.to_str().unwrap(), est.to_str().unwrap());
    let got: Value = serde_json::from_str(&ok_in(
        out.path(),
        &["drift", "kitti", gt, est, "--format", "json"],
    ))
    .unwrap();
    assert_drift("kitti", &got, want, "frames");
    // The table: a row per length and the overall line.
    let text = ok_in(out.path(), &["drift", "kitti", gt, est]);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "KITTI drift over segments of 100, 200, 300, 400, 500, 600, 700, 800 m (a start every 10 poses)"
    );
    assert_eq!(lines[1], "(not aligned)");
    let header = lines
        .iter()
        .position(|l| l.starts_with("length (m)"))
        .unwrap();
    assert_eq!(lines[header + 1].split_whitespace().next(), Some("100"));
    let all: Vec<&str> = lines[header + 9].split_whitespace().collect();
    assert_eq!(all[..2], ["all", "166"]);
    assert!((all[2].parse::<f64>().unwrap() - f(&want["t_err_percent"])).abs() < 1e-6);
    // CSV: one row per segment.
    let csv = ok_in(out.path(), &["drift", "kitti", gt, est, "--format", "csv"]);
    assert_eq!(
        csv.lines().next(),
        Some("first,last,length_m,speed_m_s,t_err_percent,r_err_deg_per_m")
    );
    assert_eq!(csv.lines().count(), 167);
    // A rigid alignment changes no segment; a scale correction lowers the error.
    let aligned: Value = serde_json::from_str(&ok_in(
        out.path(),
        &["drift", "kitti", gt, est, "-a", "--format", "json"],
    ))
    .unwrap();
    assert_eq!(aligned["alignment"], "se3");
    assert!((f(&aligned["t_err_percent"]) - f(&got["t_err_percent"])).abs() < 1e-9);
    let scaled: Value = serde_json::from_str(&ok_in(
        out.path(),
        &["drift", "kitti", gt, est, "-s", "--format", "json"],
    ))
    .unwrap();
    assert_eq!(scaled["alignment"], "scale");
    assert!(f(&scaled["scale"]) < 1.0);
    assert!(f(&scaled["t_err_percent"]) < f(&got["t_err_percent"]) - 0.5);
    // The two figures as SVG files, and one two-page PDF.
    let saved = ok_in(
        out.path(),
        &["drift", "kitti", gt, est, "--save_plot", "drift.svg"],
    );
    assert!(saved.contains("Plot saved to drift_length.svg"));
    for page in ["length", "speed"] {
        let svg = std::fs::read_to_string(out.path().join(format!("drift_{page}.svg"))).unwrap();
        assert!(svg.contains("translation error (%)") && svg.contains("rotation error (deg/m)"));
    }
    ok_in(
        out.path(),
        &["drift", "kitti", gt, est, "--save_plot", "drift.pdf"],
    );
    let pdf =
        String::from_utf8_lossy(&std::fs::read(out.path().join("drift.pdf")).unwrap()).into_owned();
    assert!(pdf.starts_with("%PDF") && pdf.contains("/Count 2 >>"));
}

#[test]
fn drift_over_runs_prints_and_plots_each_run() {
    let Some(dir) = real_sequence("drift_over_runs_prints_and_plots_each_run") else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let file = |name: &str| dir.join(name).display().to_string();
    let args = [
        "drift".to_owned(),
        "tum".to_owned(),
        file("ground_truth.txt"),
        file("runs/run0.txt"),
        file("runs/run1.txt"),
        "--lengths".to_owned(),
        "1,2,4,8".to_owned(),
        "--speed_step".to_owned(),
        "0.25".to_owned(),
        "--save_plot".to_owned(),
        "d.svg".to_owned(),
    ];
    let text = ok_in(out.path(), &args);
    assert!(text.contains("2 runs against"), "{text}");
    assert!(text.contains("\nacross trials"), "{text}");
    assert!(text.contains("\nt_err_percent "), "{text}");
    for page in ["length", "speed", "t_err_box_plot", "r_err_box_plot"] {
        let svg = std::fs::read_to_string(out.path().join(format!("d_{page}.svg"))).unwrap();
        assert!(svg.contains("run1.txt"), "{page}");
    }
}

#[test]
fn drift_says_when_no_segment_fits() {
    let Some(dir) = real_sequence("drift_says_when_no_segment_fits") else {
        return;
    };
    let out = sitar_in(&dir, &["drift", "tum", "ground_truth.txt", "runs/run0.txt"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains("no segment"), "{stderr}");
    assert!(stderr.contains("--lengths"), "{stderr}");
}

#[test]
fn drift_and_runs_read_bag_topics() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/evo_bags");
    let drift: Value = serde_json::from_str(&ok_in(
        &dir,
        &[
            "drift",
            "bag2",
            "fr1_mcap",
            "/ground_truth",
            "/odom",
            "--lengths",
            "0.5,1,2",
            "--format",
            "json",
        ],
    ))
    .unwrap();
    assert_eq!(drift["speed_from"], "stamps");
    assert_eq!(drift["segments"], 3);
    assert_eq!(drift["by_length"].as_array().unwrap().len(), 1);
    let text = ok_in(
        &dir,
        &[
            "drift",
            "bag2",
            "fr1_mcap",
            "/ground_truth",
            "/odom",
            "--lengths",
            "0.5,1,2",
        ],
    );
    assert!(
        text.contains("(left out, fewer than 3 segments, as in the devkit's plots: 1, 2 m)"),
        "{text}"
    );
    let runs: Value = serde_json::from_str(&ok_in(
        &dir,
        &[
            "ape",
            "bag2",
            "fr1_mcap",
            "/ground_truth",
            "/odom",
            "/pose_cov",
            "-a",
            "--format",
            "json",
        ],
    ))
    .unwrap();
    assert_eq!(runs["runs"], 2);
    assert_eq!(runs["trials"][1]["estimate"], "/pose_cov");
}
