//! SiTAR's alignment and association extras on `sitar ape`/`rpe`/`drift`: `-a --yaw_only`
//! (4-DoF), `--estimate_t_offset`, the pairing report, and ape's direction relations
//! (along_track, cross_track, vertical, yaw_deg, roll_pitch_deg), on a real EuRoC run
//! (`../shared/data/real-runs/euroc-vio/MH_04`; SKIPPED when missing).

mod support;

use std::path::{Path, PathBuf};

use serde_json::Value;
use support::run::{fails, ok, ok_both};

fn json(args: &[&str]) -> Value {
    let mut all = args.to_vec();
    all.extend(["--format", "json"]);
    serde_json::from_str(&ok(&all)).unwrap()
}

fn rmse(doc: &Value) -> f64 {
    doc["statistics"]["rmse"].as_f64().unwrap()
}

/// The real run's folder, or `None` (the test says SKIPPED) when it is missing.
fn real_sequence(test: &str) -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/real-runs/euroc-vio/MH_04");
    if dir.join("ground_truth.txt").is_file() && dir.join("runs/run0.txt").is_file() {
        Some(dir)
    } else {
        eprintln!("SKIPPED {test}: {} is missing", dir.display());
        None
    }
}

fn paths(dir: &Path) -> (String, String) {
    (
        dir.join("ground_truth.txt").display().to_string(),
        dir.join("runs/run0.txt").display().to_string(),
    )
}

#[test]
fn yaw_only_alignment() {
    let Some(dir) = real_sequence("yaw_only_alignment") else {
        return;
    };
    let (gt, est) = paths(&dir);
    let se3 = json(&["ape", "tum", &gt, &est, "-a"]);
    let yaw = json(&["ape", "tum", &gt, &est, "-a", "--yaw_only"]);
    assert_eq!(yaw["alignment"], "position_yaw_z");
    assert!(
        yaw["title"]
            .as_str()
            .unwrap()
            .contains("(with 4-DoF position and yaw alignment about z)")
    );
    // Fewer degrees of freedom fit no better; a VIO's gravity is observable, so not much worse.
    let (r_se3, r_yaw) = (rmse(&se3), rmse(&yaw));
    assert!(r_yaw >= r_se3 - 1e-12, "{r_yaw} < {r_se3}");
    assert!(r_yaw < 2.0 * r_se3, "{r_yaw} vs {r_se3}");
    // The fitted rotation is about z only: its third row and column are (0, 0, 1).
    let rotation = &yaw["transform"]["rotation"];
    for k in 0..2 {
        assert!(rotation[2][k].as_f64().unwrap().abs() < 1e-12);
        assert!(rotation[k][2].as_f64().unwrap().abs() < 1e-12);
    }
    assert!((rotation[2][2].as_f64().unwrap() - 1.0).abs() < 1e-12);
    assert_eq!(yaw["transform"]["scale"].as_f64().unwrap(), 1.0);
    // About y: a different fit, named so.
    let about_y = json(&[
        "ape",
        "tum",
        &gt,
        &est,
        "-a",
        "--yaw_only",
        "--yaw_axis",
        "y",
    ]);
    assert_eq!(about_y["alignment"], "position_yaw_y");
    assert!(rmse(&about_y) > r_yaw);
    // --n_to_align fits on the first poses only.
    let first = json(&[
        "ape",
        "tum",
        &gt,
        &est,
        "-a",
        "--yaw_only",
        "--n_to_align",
        "200",
    ]);
    assert!(rmse(&first) >= r_yaw);
    assert!(
        first["title"]
            .as_str()
            .unwrap()
            .contains("(aligned poses: 200)")
    );
    // rpe and drift take it too.
    let rpe = json(&["rpe", "tum", &gt, &est, "-a", "--yaw_only", "-d", "10"]);
    assert_eq!(rpe["alignment"], "position_yaw_z");
    ok(&[
        "drift",
        "tum",
        &gt,
        &est,
        "-a",
        "--yaw_only",
        "--lengths",
        "1,2,4",
    ]);
    // With -s: refused, by name.
    let stderr = fails(&["ape", "tum", &gt, &est, "-a", "-s", "--yaw_only"]);
    assert!(
        stderr.contains("--yaw_only") && stderr.contains("--correct_scale"),
        "{stderr}"
    );
    // Without -a: refused by the parser.
    fails(&["ape", "tum", &gt, &est, "--yaw_only"]);
}

/// `source` (TUM) with `shift` seconds added to every stamp, every `every`-th pose, in a file
/// of the test's own.
fn shifted(source: &Path, shift: f64, every: usize, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(source).unwrap();
    let out: Vec<String> = text
        .lines()
        .filter(|line| !line.starts_with('#') && !line.trim().is_empty())
        .step_by(every)
        .map(|line| {
            let (stamp, rest) = line.split_once(' ').unwrap();
            format!("{:.9} {rest}", stamp.parse::<f64>().unwrap() + shift)
        })
        .collect();
    let path = std::env::temp_dir().join(format!("sitar_align_{}_{name}.txt", std::process::id()));
    std::fs::write(&path, out.join("\n") + "\n").unwrap();
    path
}

/// Offsets come back within 5 ms (a tenth of the runs' 20 Hz frame period; the ground
/// truth's 200 Hz gives the nearest-stamp association a 5 ms grain).
const OFFSET_TOLERANCE_S: f64 = 0.005;

fn estimated(args: &[&str]) -> f64 {
    let mut all = args.to_vec();
    all.push("--estimate_t_offset");
    json(&all)["t_offset_estimated_s"].as_f64().unwrap()
}

#[test]
fn estimate_t_offset_recovers_a_known_shift() {
    let Some(dir) = real_sequence("estimate_t_offset_recovers_a_known_shift") else {
        return;
    };
    let (gt, est) = paths(&dir);
    // An error-free estimate: the ground truth at 20 Hz. --t_offset is added to the
    // estimate's stamps, so a +0.137 s shift is undone by -0.137 s; no shift gives ~0.
    let truth = dir.join("ground_truth.txt");
    let clean = shifted(&truth, 0.0, 10, "clean").display().to_string();
    let late = shifted(&truth, 0.137, 10, "late").display().to_string();
    let found = estimated(&["ape", "tum", &gt, &clean, "-a"]);
    assert!(found.abs() < OFFSET_TOLERANCE_S, "found {found}");
    let doc = json(&["ape", "tum", &gt, &late, "-a", "--estimate_t_offset"]);
    let found = doc["t_offset_estimated_s"].as_f64().unwrap();
    assert!((found + 0.137).abs() < OFFSET_TOLERANCE_S, "found {found}");
    assert_eq!(doc["pairing"]["t_offset_s"].as_f64().unwrap(), found);
    assert!(rmse(&doc) < 0.01, "{}", rmse(&doc));
    // rpe, without alignment (the search aligns with SE(3), the result is not aligned).
    let doc = json(&["rpe", "tum", &gt, &late, "--estimate_t_offset", "-d", "10"]);
    assert!((doc["t_offset_estimated_s"].as_f64().unwrap() + 0.137).abs() < OFFSET_TOLERANCE_S);
    assert_eq!(doc["alignment"], "none");
    // A real VIO run has an offset of its own (its error makes the minimum shallow): shifting
    // its stamps moves the estimate by the shift.
    let own = estimated(&["ape", "tum", &gt, &est, "-a"]);
    let moved = shifted(&dir.join("runs/run0.txt"), 0.137, 1, "moved");
    let moved = moved.display().to_string();
    let found = estimated(&["ape", "tum", &gt, &moved, "-a"]);
    assert!(
        (found - own + 0.137).abs() < OFFSET_TOLERANCE_S,
        "{found} vs {own}"
    );
    // The line on stderr.
    let (_, stderr) = ok_both(&["ape", "tum", &gt, &late, "-a", "--estimate_t_offset"]);
    let line = stderr
        .lines()
        .find_map(|l| l.strip_prefix("estimated t_offset: "))
        .unwrap_or_else(|| panic!("no estimate in {stderr}"));
    let value: f64 = line.strip_suffix(" s").unwrap().parse().unwrap();
    assert!((value + 0.137).abs() < OFFSET_TOLERANCE_S, "{line}");
    // A shift beyond the range is not found; a wider range finds it.
    let far = shifted(&truth, -1.5, 10, "far").display().to_string();
    let found = estimated(&["ape", "tum", &gt, &far, "-a", "--t_offset_range", "2"]);
    assert!((found - 1.5).abs() < OFFSET_TOLERANCE_S, "found {found}");
    let found = estimated(&["ape", "tum", &gt, &far, "-a"]);
    assert!((found - 1.5).abs() > 0.4, "found {found}");
    for path in [clean, late, moved, far] {
        std::fs::remove_file(path).unwrap();
    }
}

#[test]
fn pairing_is_reported() {
    let Some(dir) = real_sequence("pairing_is_reported") else {
        return;
    };
    let (gt, est) = paths(&dir);
    let doc = json(&["ape", "tum", &gt, &est, "-a"]);
    let pairing = &doc["pairing"];
    let (n, paired, dropped) = (
        pairing["estimate_poses"].as_u64().unwrap(),
        pairing["paired"].as_u64().unwrap(),
        pairing["estimate_dropped"].as_u64().unwrap(),
    );
    assert_eq!(paired + dropped, n);
    assert_eq!(paired, doc["associated_poses"].as_u64().unwrap());
    // Cutting the reference short drops estimate poses, and says why.
    let (_, stderr) = ok_both(&[
        "ape",
        "tum",
        &gt,
        &est,
        "-a",
        "--t_max_diff",
        "0.001",
        "--show_pairing",
    ]);
    let line = stderr
        .lines()
        .find(|l| l.contains("paired "))
        .unwrap_or_else(|| panic!("no pairing line in {stderr}"));
    assert!(line.contains(&format!(" of {n} estimate poses")), "{line}");
    // Without the flag, nothing is added to evo's output.
    let (stdout, stderr) = ok_both(&["ape", "tum", &gt, &est, "-a"]);
    assert!(!stdout.contains("paired ") && !stderr.contains("paired "));
}

#[test]
fn direction_relations_add_up_to_the_translation_error() {
    let Some(dir) = real_sequence("direction_relations_add_up_to_the_translation_error") else {
        return;
    };
    let (gt, est) = paths(&dir);
    for axis in ["z", "y"] {
        let trans = rmse(&json(&["ape", "tum", &gt, &est, "-a", "--yaw_axis", axis]));
        let parts: Vec<f64> = ["along_track", "cross_track", "vertical"]
            .iter()
            .map(|r| {
                let doc = json(&["ape", "tum", &gt, &est, "-a", "-r", r, "--yaw_axis", axis]);
                assert_eq!(doc["pose_relation"], *r);
                assert_eq!(doc["unit"], "m");
                assert_eq!(doc["yaw_axis"], axis);
                rmse(&doc)
            })
            .collect();
        let sum = parts.iter().map(|p| p * p).sum::<f64>().sqrt();
        assert!(
            (sum - trans).abs() <= 1e-9 * trans,
            "{axis}: {sum} vs {trans}"
        );
        // The rotation: yaw and roll/pitch are each at most the whole angle.
        let angle = json(&["ape", "tum", &gt, &est, "-a", "-r", "angle_deg"]);
        let yaw = json(&[
            "ape",
            "tum",
            &gt,
            &est,
            "-a",
            "-r",
            "yaw_deg",
            "--yaw_axis",
            axis,
        ]);
        let tilt = json(&[
            "ape",
            "tum",
            &gt,
            &est,
            "-a",
            "-r",
            "roll_pitch_deg",
            "--yaw_axis",
            axis,
        ]);
        for (a, (y, t)) in angle["errors"].as_array().unwrap().iter().zip(
            yaw["errors"]
                .as_array()
                .unwrap()
                .iter()
                .zip(tilt["errors"].as_array().unwrap()),
        ) {
            let (a, y, t) = (
                a["error"].as_f64().unwrap(),
                y["error"].as_f64().unwrap(),
                t["error"].as_f64().unwrap(),
            );
            assert!(
                y <= a + 1e-9 && t <= a + 1e-9 && a <= y + t + 1e-9,
                "{a} {y} {t}"
            );
        }
    }
    // The table keeps evo's layout, with the relation in the title.
    let stdout = ok(&["ape", "tum", &gt, &est, "-a", "-r", "cross_track"]);
    assert!(
        stdout.starts_with("APE w.r.t. cross-track translation (m)\n"),
        "{stdout}"
    );
    // rpe does not take them.
    fails(&["rpe", "tum", &gt, &est, "-r", "yaw_deg"]);
}
