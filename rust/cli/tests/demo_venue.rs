//! `sitar demo --venue` end to end: three simulated users, the in-process backend, one venue.

use std::process::Command;

#[test]
fn the_venue_demo_aligns_every_user_and_maps_the_blank_wall() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_sitar"))
        .args([
            "demo", "--venue", "--trials", "3", "--speed", "40", "--seed", "5",
        ])
        .arg("--data")
        .arg(dir.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    println!("{stdout}");
    // Each session aligned within 5 cm and 2° of the simulator's truth.
    let alignments: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("alignment"))
        .collect();
    assert_eq!(alignments.len(), 3, "{stdout}");
    for line in &alignments {
        let truth = line
            .split("against the truth ")
            .nth(1)
            .unwrap_or_else(|| panic!("not aligned: {line}"));
        let mut parts = truth.split(", ");
        let mm: f64 = parts
            .next()
            .unwrap()
            .trim_end_matches(" mm")
            .parse()
            .unwrap();
        let deg: f64 = parts.next().unwrap().trim_end_matches('°').parse().unwrap();
        assert!(mm < 50.0 && deg < 2.0, "{line}");
        assert!(
            !line.contains("not aligned"),
            "the backend did not align: {line}"
        );
    }
    // The worst surface cells say what they truly are; the blank wall is among the problems.
    let worst: Vec<&str> = stdout.lines().filter(|l| l.contains(" → ")).collect();
    assert!(!worst.is_empty(), "{stdout}");
    assert!(stdout.contains("blank wall (hard)"), "{stdout}");
    // The report's problem regions (high, seen by ≥ 2 sessions) include the blank wall: the
    // three users' samples of it share cells (the grid puts the anchor's wall mid-cell).
    let regions = stdout
        .lines()
        .find(|l| l.starts_with("regions"))
        .unwrap_or_else(|| panic!("{stdout}"));
    let on_wall: usize = regions
        .split([':', ','])
        .filter_map(|part| {
            part.trim()
                .strip_suffix(" on blank wall (hard)")?
                .parse::<usize>()
                .ok()
        })
        .sum();
    assert!(
        on_wall >= 1,
        "no problem region on the blank wall: {regions}"
    );
    let matched = stdout
        .lines()
        .find(|l| l.starts_with("match"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(!matched.contains("missed: blank wall"), "{matched}");
    // The report page was saved.
    let report = stdout
        .lines()
        .find_map(|l| l.strip_prefix("report      "))
        .unwrap_or_else(|| panic!("{stdout}"));
    let html = std::fs::read_to_string(report.trim()).unwrap();
    assert!(html.contains("<html") || html.contains("<!doctype") || html.contains("<!DOCTYPE"));
    // Its "Problem regions" lists them (the table is there only when there is one).
    assert!(
        html.contains("<table id=\"regions\">"),
        "no problem regions in the report"
    );
}
