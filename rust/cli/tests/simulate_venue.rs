//! `sitar simulate --venue --users N`: every user's files, and each phone session aligns to
//! the venue within a few centimetres and degrees of its truth.json.

use std::process::Command;

use sitar_core::venue::{align, parse_anchors_csv};

#[test]
fn simulate_venue_writes_users_that_align_to_their_truth() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("venue");
    let run = Command::new(env!("CARGO_BIN_EXE_sitar"))
        .args([
            "simulate", "--venue", "--users", "3", "--trials", "2", "--seed", "4",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let index: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("venue.json")).unwrap()).unwrap();
    let anchor = index["anchor"]["id"].as_str().unwrap();
    assert_eq!(anchor, "sitar-anchor-a4");
    assert_eq!(
        index["hard_surfaces"],
        serde_json::json!(["blank wall", "glass pane"])
    );
    let users = index["users"].as_array().unwrap();
    assert_eq!(users.len(), 3);
    let mut headings = Vec::new();
    for user in users {
        let dir = out.join(user["dir"].as_str().unwrap());
        for file in [
            "recording.sitarsim",
            "ground_truth.txt",
            "scene.json",
            "trials/trajectory_1.txt",
            "session/trajectory.txt",
            "session/subtrajectories.csv",
        ] {
            assert!(dir.join(file).is_file(), "{}: no {file}", dir.display());
        }
        let csv = std::fs::read_to_string(dir.join("session/anchors.csv")).unwrap();
        let observations = parse_anchors_csv(&csv, "anchors.csv").unwrap();
        assert_eq!(
            observations.len() as u64,
            user["observations"].as_u64().unwrap()
        );
        let truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap())
                .unwrap();
        let t = &truth["world_from_venue"];
        let translation = glam::DVec3::from_slice(
            &t["translation"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect::<Vec<_>>(),
        );
        let heading = t["heading_rad"].as_f64().unwrap();
        let a = align(&observations, anchor).unwrap();
        let d = a.heading_rad - heading;
        assert!(
            a.translation.distance(translation) < 0.05,
            "{a:?} vs {translation}"
        );
        assert!(
            d.sin().atan2(d.cos()).abs().to_degrees() < 2.0,
            "{a:?} vs {heading}"
        );
        headings.push(heading);
    }
    // Each phone started in its own frame.
    headings.sort_by(f64::total_cmp);
    assert!(
        headings.windows(2).all(|w| w[1] - w[0] > 0.05),
        "{headings:?}"
    );
}

#[test]
fn users_without_venue_and_a_venue_of_no_one_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_sitar"))
            .args(["simulate", "--out"])
            .arg(dir.path())
            .args(args)
            .output()
            .unwrap()
    };
    let out = run(&["--users", "2"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--venue"));
    let out = run(&["--venue", "--users", "0"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--users must be between 1 and"));
    let out = run(&["--venue", "--users", "2", "--scene", "dark-wall"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--scene"));
}
