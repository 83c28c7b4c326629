//! Runs the built `sitar` binary on files made by `sitar simulate` and on evo goldens.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

use sitar_estimator::{EstimateOptions, RpeOptions, Setting, estimate, read_tum, rpe};
use support::run::{ok, sitar};

/// `sitar ARGS` fails with exit code 1, nothing on stdout and one line `sitar: error: …` on
/// stderr: that line.
fn one_line_error(args: &[&str]) -> String {
    let out = sitar(args);
    assert_eq!(out.status.code(), Some(1), "sitar {args:?} should fail");
    assert!(out.stdout.is_empty());
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "one line expected: {stderr}");
    assert!(stderr.starts_with("sitar: error: "), "{stderr}");
    stderr
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// `sitar simulate` into a fresh temporary directory.
fn simulate(extra: &[&str]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let mut args = vec!["simulate", "--out", p(dir.path()), "--seconds", "5"];
    if !extra.contains(&"--trials") {
        args.extend(["--trials", "4"]);
    }
    args.extend_from_slice(extra);
    ok(&args);
    dir
}

fn csv_rows(text: &str) -> Vec<Vec<String>> {
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect()
}

#[test]
fn simulate_writes_trials_ground_truth_scene_and_recording() {
    let dir = simulate(&["--seed", "3", "--second-set"]);
    let d = dir.path();
    let gt = read_tum(&d.join("ground_truth.txt")).unwrap();
    assert_eq!(gt.len(), 150);
    assert_eq!(gt.stamps[0], 1_000_000_000_000);
    for set in ["trials", "trials-b"] {
        for k in 0..4 {
            let t = read_tum(&d.join(format!("{set}/trajectory_{k}.txt"))).unwrap();
            assert_eq!(t.stamps, gt.stamps);
        }
    }
    // Set B is disjoint from set A (other trial indices).
    let a = std::fs::read_to_string(d.join("trials/trajectory_0.txt")).unwrap();
    let b = std::fs::read_to_string(d.join("trials-b/trajectory_0.txt")).unwrap();
    assert_ne!(a, b);
    let scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("scene.json")).unwrap()).unwrap();
    assert_eq!(
        scene["hard_surfaces"],
        serde_json::json!(["blank wall", "glass pane"])
    );
    assert_eq!(scene["frames"], 150);
    let rec =
        sitar_sim::Recording::from_bytes(&std::fs::read(d.join("recording.sitarsim")).unwrap())
            .unwrap();
    assert_eq!(rec.frames(), 150);
    // The trial file is play_trial's output (quaternions re-normalised on reading).
    let (played, read) = (
        sitar_sim::play_trial(&rec, 2),
        read_tum(&d.join("trials/trajectory_2.txt")).unwrap(),
    );
    assert_eq!(played.positions, read.positions);
    for (a, b) in played.orientations.iter().zip(&read.orientations) {
        assert!((*a - *b).length() < 1e-15);
    }
    // Deterministic: the same seed gives the same files.
    let again = simulate(&["--seed", "3"]);
    assert_eq!(
        std::fs::read_to_string(again.path().join("trials/trajectory_0.txt")).unwrap(),
        a
    );
}

#[test]
fn simulate_seconds_and_dropped_frames() {
    let dir = simulate(&["--time-unit", "s", "--drop-frames", "0.2"]);
    let text = std::fs::read_to_string(dir.path().join("trials/trajectory_1.txt")).unwrap();
    assert!(text.starts_with("1000.000000000 "), "{}", &text[..40]);
    let t = read_tum(&dir.path().join("trials/trajectory_1.txt")).unwrap();
    assert!(t.len() < 140 && t.len() > 90, "{}", t.len());
    // RPE rows keep the input's unit.
    let gt = dir.path().join("ground_truth.txt");
    let out = ok(&[
        "rpe",
        p(&gt),
        p(&dir.path().join("trials/trajectory_1.txt")),
        "--format",
        "csv",
    ]);
    assert!(
        out.lines()
            .nth(1)
            .unwrap()
            .starts_with("1000.000000000,1000."),
        "{out}"
    );
}

#[test]
fn rpe_and_ape_match_the_library() {
    let dir = simulate(&[]);
    let gt = dir.path().join("ground_truth.txt");
    let est = dir.path().join("trials/trajectory_0.txt");
    let out = ok(&["rpe", p(&gt), p(&est), "-d", "10", "--format", "csv"]);
    assert!(out.starts_with("start,end,error\n"));
    let rows = csv_rows(&out);
    // 150 poses, delta 10 without --all-pairs: starts 0, 10, …, 130.
    assert_eq!(rows.len(), 14);
    assert_eq!(rows[1][0], "1000333333333");
    assert_eq!(rows[1][1], "1000666666667");
    let (r, e) = (read_tum(&gt).unwrap(), read_tum(&est).unwrap());
    let lib = rpe(
        &r,
        &e,
        &RpeOptions {
            all_pairs: false,
            ..RpeOptions::default()
        },
    )
    .unwrap();
    for (row, value) in rows.iter().zip(&lib.errors) {
        assert_eq!(row[2].parse::<f64>().unwrap(), *value);
    }
    let all = csv_rows(&ok(&[
        "rpe",
        p(&gt),
        p(&est),
        "-d",
        "10",
        "--all-pairs",
        "--format",
        "csv",
    ]));
    assert_eq!(all.len(), 140);
    // evo's form and defaults (delta 1, consecutive pairs), evo's table on stdout.
    let table = ok(&["rpe", "tum", p(&gt), p(&est), "--time_unit", "ns"]);
    assert!(
        table.starts_with(
            "RPE w.r.t. translation part (m)\nfor delta = 1 (frames) using consecutive pairs\n(not aligned)\n\n       max\t"
        ),
        "{table}"
    );
    let names: Vec<&str> = table
        .lines()
        .skip(4)
        .filter(|l| !l.is_empty())
        .filter_map(|l| l.split('\t').next())
        .collect();
    assert_eq!(
        names,
        [
            "       max",
            "      mean",
            "    median",
            "       min",
            "      rmse",
            "       sse",
            "       std"
        ]
    );

    let json: serde_json::Value = serde_json::from_str(&ok(&[
        "ape",
        p(&gt),
        p(&est),
        "--align",
        "--format",
        "json",
    ]))
    .unwrap();
    assert_eq!(json["metric"], "ape");
    assert_eq!(json["alignment"], "se3");
    assert_eq!(json["errors"].as_array().unwrap().len(), 150);
    let rmse = json["statistics"]["rmse"].as_f64().unwrap();
    // Aligned, the simulated drift over 5 s is centimetres, not the metre-scale frame offset.
    assert!(rmse > 1e-3 && rmse < 0.2, "{rmse}");
    let unaligned: serde_json::Value =
        serde_json::from_str(&ok(&["ape", p(&gt), p(&est), "--format", "json"])).unwrap();
    assert!(unaligned["statistics"]["rmse"].as_f64().unwrap() > 2.0 * rmse);
    let csv = ok(&["ape", p(&gt), p(&est), "-a", "--format", "csv"]);
    assert!(csv.starts_with("t,error\n1000000000000,"));
}

#[test]
fn estimate_matches_the_library_and_writes_files() {
    let dir = simulate(&["--seed", "5"]);
    let trials: Vec<PathBuf> = (0..4)
        .map(|k| dir.path().join(format!("trials/trajectory_{k}.txt")))
        .collect();
    let names: Vec<&str> = trials.iter().map(|t| p(t)).collect();
    let mut args = vec!["estimate"];
    args.extend(&names);
    let csv = ok(&args);
    let loaded: Vec<_> = trials.iter().map(|t| read_tum(t).unwrap()).collect();
    let lib = estimate(&loaded, &EstimateOptions::default()).unwrap();
    assert_eq!(csv, lib.to_legacy_csv());
    assert_eq!(csv.lines().count(), 141);
    // A directory stands for its trials in natural order; same result.
    let trials_dir = dir.path().join("trials");
    assert_eq!(ok(&["estimate", p(&trials_dir)]), csv);
    // Order matters (trial i is the reference of pair i < j) but only through association:
    // reversed trials give the same windows here.
    let out_file = dir.path().join("est.json");
    ok(&[
        "estimate",
        p(&trials_dir),
        "--setting",
        "median",
        "--format",
        "json",
        "-o",
        p(&out_file),
    ]);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out_file).unwrap()).unwrap();
    assert_eq!(json["setting"], "median");
    assert_eq!(json["trials"], 4);
    let windows = json["windows"].as_array().unwrap();
    assert_eq!(windows.len(), 140);
    assert_eq!(windows[0]["pairs"], 6);
    let median = estimate(
        &loaded,
        &EstimateOptions {
            setting: Setting::Median,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(
        windows[7]["error_m"].as_f64().unwrap(),
        median.windows[7].error_m
    );
}

#[test]
fn bad_input_gives_one_clear_line() {
    let dir = simulate(&[]);
    let gt = dir.path().join("ground_truth.txt");
    let bad = dir.path().join("bad.txt");
    std::fs::write(&bad, "# comment\n1 0 0 0 0 0 0 1\n2 0 0 zero 0 0 0 1\n").unwrap();
    let err = one_line_error(&["rpe", p(&gt), p(&bad)]);
    assert!(err.contains(&format!("{}:3:", bad.display())), "{err}");
    let err = one_line_error(&["estimate", p(&gt), p(&bad)]);
    assert!(err.contains("bad.txt:3:"), "{err}");
    let missing = dir.path().join("missing.txt");
    let err = one_line_error(&["ape", p(&gt), p(&missing)]);
    assert!(err.contains("missing.txt"), "{err}");
    let err = one_line_error(&["estimate", p(&gt)]);
    assert!(err.contains("at least 2 trials"), "{err}");
    // Stamps that never match.
    let far = dir.path().join("far.txt");
    std::fs::write(&far, "5 0 0 0 0 0 0 1\n6 1 0 0 0 0 0 1\n").unwrap();
    let err = one_line_error(&["rpe", p(&gt), p(&far)]);
    assert!(err.contains("no matching timestamps"), "{err}");
    let err = one_line_error(&[
        "simulate",
        "--out",
        p(&dir.path().join("x")),
        "--seconds",
        "0",
    ]);
    assert!(err.contains("duration"), "{err}");
    // clap rejects unknown values with its usage message and exit code 2.
    let out = sitar(&["estimate", p(&gt), p(&gt), "--setting", "trim_mean_33"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown setting 'trim_mean_33'"));
}

#[test]
fn evaluate_reports_every_setting_and_draws_the_plot() {
    let dir = simulate(&["--trials", "6", "--second-set", "--seed", "9"]);
    let d = dir.path();
    let (gt, a, b) = (
        d.join("ground_truth.txt"),
        d.join("trials"),
        d.join("trials-b"),
    );
    let svg = d.join("figure5.svg");
    let common = [
        "--ground-truth",
        p(&gt),
        "--trials-a",
        p(&a),
        "--trials-b",
        p(&b),
    ];
    let mut args = vec![
        "evaluate",
        "--trial-counts",
        "2,4,6",
        "--format",
        "json",
        "--plot",
        p(&svg),
    ];
    args.extend(common);
    let json: serde_json::Value = serde_json::from_str(&ok(&args)).unwrap();
    assert_eq!(json["trials_a"], 6);
    assert_eq!(json["truth_windows"], 140);
    let results = json["results"].as_array().unwrap();
    assert_eq!(results.len(), 3 * 7 * 3);
    for r in results {
        let accuracy = r["accuracy"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&accuracy));
        assert_eq!(r["windows"], 140);
    }
    // The paper's default: trim_mean_30 on 5 & 10 cm with all six trials classifies most
    // windows right (the simulated trials disagree where the truth is bad).
    let best = results
        .iter()
        .find(|r| {
            r["setting"] == "trim_mean_30" && r["trials"] == 6 && r["boundaries_m"][0] == 0.05
        })
        .unwrap();
    assert!(best["accuracy"].as_f64().unwrap() > 0.6, "{best}");
    let plot = std::fs::read_to_string(&svg).unwrap();
    assert!(
        plot.starts_with("<svg")
            && plot.contains("trim_mean_30")
            && plot.contains("F1, boundaries 2 &amp; 5 cm")
    );

    let mut args = vec![
        "evaluate",
        "--trial-counts",
        "3",
        "--settings",
        "mean,median",
        "--no-plot",
    ];
    args.extend(common);
    let table = ok(&args);
    assert!(table.contains("class boundaries 5 & 10 cm"), "{table}");
    assert_eq!(
        table
            .lines()
            .filter(|l| l.starts_with("mean ") || l.starts_with("median "))
            .count(),
        6
    );

    let mut args = vec!["evaluate", "--trial-counts", "7", "--no-plot"];
    args.extend(common);
    assert!(
        one_line_error(&args)
            .contains("--trial_counts: 7 is not between 2 and the 6 trials of set B")
    );
}

#[test]
fn every_subcommand_has_help() {
    for (cmd, flag) in [
        (vec!["rpe", "tum"], "--delta_unit"),
        (vec!["rpe", "euroc"], "--plot_mode"),
        (vec!["rpe", "kitti"], "--all_pairs"),
        (vec!["ape", "tum"], "--align_origin"),
        (vec!["ape", "tum"], "--plot [<FILE>]"),
        (vec!["ape", "tum"], "--save_results"),
        (vec!["ape"], "euroc"),
        (vec!["traj", "tum"], "--full_check"),
        (vec!["res"], "--use_filenames"),
        (vec!["drift", "tum"], "--lengths"),
        (vec!["drift", "kitti"], "--speed_step"),
        (vec!["estimate"], "--setting"),
        (vec!["estimate"], "--time_unit"),
        (vec!["estimate"], "--plot-mode"),
        (vec!["simulate"], "--trials"),
        (vec!["evaluate"], "--trials_b"),
    ] {
        let mut args = cmd.clone();
        args.push("--help");
        let help = ok(&args);
        assert!(help.contains(flag), "{cmd:?}: {help}");
    }
    let top = ok(&["--help"]);
    for cmd in [
        "rpe",
        "ape",
        "traj",
        "res",
        "drift",
        "estimate",
        "evaluate",
        "simulate",
        "completions",
        "man",
    ] {
        assert!(top.contains(cmd));
    }
}

/// The `<circle>` elements of an SVG (only the trajectory panel draws circles): their fills.
fn circle_fills(svg: &str) -> Vec<String> {
    svg.split("<circle")
        .skip(1)
        .map(|e| attribute(e, "fill").to_owned())
        .collect()
}

/// The trimmed contents of the `<text>` elements of an SVG (`&amp;` etc. left escaped).
fn svg_texts(svg: &str) -> Vec<&str> {
    svg.split("<text")
        .skip(1)
        .filter_map(|e| {
            let body = &e[e.find('>')? + 1..];
            Some(body[..body.find("</text>")?].trim())
        })
        .collect()
}

/// Point counts of the `<polyline>` elements stroked in `colour` (`#RRGGBB`).
fn polyline_lengths(svg: &str, colour: &str) -> Vec<usize> {
    svg.split("<polyline")
        .skip(1)
        .filter(|e| attribute(e, "stroke") == colour)
        .map(|e| attribute(e, "points").split_whitespace().count())
        .collect()
}

/// The value of `name="…"` in the element starting `element`.
fn attribute<'a>(element: &'a str, name: &str) -> &'a str {
    let tag = &element[..element.find("/>").expect("closed element")];
    let key = format!(" {name}=\"");
    let start = tag.find(&key).map(|k| k + key.len()).unwrap_or_else(|| {
        panic!("no {name} in {tag}");
    });
    &tag[start..start + tag[start..].find('"').unwrap()]
}

/// The error line's colour and the grey trajectory's, as `src/figures/plot/style.rs` sets them.
const ERROR_LINE: &str = "#1F77B4";
const TRAJECTORY_LINE: &str = "#A0A0A0";
/// Viridis' ends: the smallest and the largest error.
const VIRIDIS_LOW: &str = "#440154";
const VIRIDIS_HIGH: &str = "#FDE725";

/// Reads a written figure and checks what every error figure has: SVG text, one dot per drawn
/// error spanning the colour map, one error line with a point per error, the whole trajectory.
fn check_figure(path: &Path, errors: usize, dots: usize, trajectory: usize) -> String {
    let svg = std::fs::read_to_string(path).unwrap();
    assert!(svg.starts_with("<svg"), "{}", &svg[..80.min(svg.len())]);
    assert!(svg.trim_end().ends_with("</svg>"));
    let fills = circle_fills(&svg);
    assert_eq!(fills.len(), dots, "coloured trajectory points");
    assert!(
        fills.iter().any(|f| f == VIRIDIS_LOW),
        "no dot at the minimum"
    );
    assert!(
        fills.iter().any(|f| f == VIRIDIS_HIGH),
        "no dot at the maximum"
    );
    let distinct: std::collections::HashSet<&String> = fills.iter().collect();
    assert!(distinct.len() > 5, "{} colours", distinct.len());
    let lines = polyline_lengths(&svg, ERROR_LINE);
    assert_eq!(lines.iter().max(), Some(&errors), "error line: {lines:?}");
    assert_eq!(polyline_lengths(&svg, TRAJECTORY_LINE), [trajectory]);
    svg
}

#[test]
fn rpe_plot_draws_each_window_over_time_and_on_the_reference() {
    let dir = simulate(&[]);
    let d = dir.path();
    let (gt, est) = (
        d.join("ground_truth.txt"),
        d.join("trials/trajectory_0.txt"),
    );
    let svg_path = d.join("rpe.svg");
    let json: serde_json::Value = serde_json::from_str(&ok(&[
        "rpe",
        p(&gt),
        p(&est),
        "-d",
        "10",
        "--format",
        "json",
        "--plot",
        p(&svg_path),
        "--plot_mode",
        "xz",
    ]))
    .unwrap();
    // 150 poses, delta 10: 14 windows, each drawn at its end pose on the estimate.
    assert_eq!(json["errors"].as_array().unwrap().len(), 14);
    let svg = check_figure(&svg_path, 14, 14, 150);
    let texts = svg_texts(&svg);
    for text in [
        "RPE over t (s)",
        "RPE (m)",
        "rmse",
        "mean",
        "median",
        "x (m)",
        "z (m)",
    ] {
        assert!(texts.contains(&text), "{text}: {texts:?}");
    }
    assert!(texts.iter().any(|t| t.contains("in the xz plane")));
    // Mean and median are horizontal lines: two points at one height.
    for colour in ["#D62728", "#2CA02C", "#FF7F0E"] {
        assert!(polyline_lengths(&svg, colour).contains(&2), "{colour}");
    }
    // The reference is dashed: many short runs of evo's reference colour.
    assert!(polyline_lengths(&svg, "#444444").len() > 20);
    // Another plane: same dots, other caption (the older hyphen spelling works too).
    ok(&[
        "rpe",
        p(&gt),
        p(&est),
        "-d",
        "10",
        "--all-pairs",
        "--plot",
        p(&svg_path),
        "--plot-mode",
        "zy",
    ]);
    let svg = check_figure(&svg_path, 140, 140, 150);
    let texts = svg_texts(&svg);
    assert!(texts.iter().any(|t| t.contains("in the zy plane")));
    assert!(texts.contains(&"z (m)") && texts.contains(&"y (m)") && !texts.contains(&"x (m)"));
}

#[test]
fn ape_plot_colours_every_reference_pose() {
    let dir = simulate(&["--seed", "2"]);
    let d = dir.path();
    let (gt, est) = (
        d.join("ground_truth.txt"),
        d.join("trials/trajectory_1.txt"),
    );
    let svg_path = d.join("ape.svg");
    let csv = ok(&[
        "ape",
        p(&gt),
        p(&est),
        "--align",
        "-r",
        "angle_deg",
        "--plot",
        p(&svg_path),
        "--plot-mode",
        "xy",
        "--format",
        "csv",
    ]);
    assert_eq!(csv_rows(&csv).len(), 150);
    let svg = check_figure(&svg_path, 150, 150, 150);
    let texts = svg_texts(&svg);
    for text in ["APE over t (s)", "APE (deg)", "x (m)", "y (m)"] {
        assert!(texts.contains(&text), "{text}: {texts:?}");
    }
    assert!(texts.iter().any(|t| t.contains("in the xy plane")));
    assert!(
        texts
            .iter()
            .any(|t| t.contains("rotation angle in degrees (deg) (with SE(3) Umeyama alignment)")),
        "{texts:?}"
    );
}

/// `sitar estimate TRIALS --format json --plot SVG`, parsed.
fn estimate_json_with_plot(trials: &Path, svg: &Path) -> serde_json::Value {
    serde_json::from_str(&ok(&[
        "estimate",
        p(trials),
        "--format",
        "json",
        "--plot",
        p(svg),
    ]))
    .unwrap()
}

#[test]
fn estimate_plot_colours_window_starts_on_the_first_trial() {
    let dir = simulate(&["--seed", "5"]);
    let trials = dir.path().join("trials");
    let svg_path = dir.path().join("estimate.svg");
    let json = estimate_json_with_plot(&trials, &svg_path);
    assert_eq!(json["windows"].as_array().unwrap().len(), 140);
    let svg = check_figure(&svg_path, 140, 140, 150);
    let texts = svg_texts(&svg);
    assert!(texts.contains(&"estimated error (m)"), "{texts:?}");
    assert!(texts.iter().any(|t| t.contains("trajectory_0.txt")));
    assert!(!svg.contains("not drawn"));
    assert!(
        !texts.contains(&"median") && !texts.contains(&"mean"),
        "the estimate has no statistic lines"
    );

    // Dropped frames: windows starting where trial 0 has no pose are drawn over time only.
    let dir = simulate(&["--seed", "6", "--drop-frames", "0.2"]);
    let trials = dir.path().join("trials");
    let json = estimate_json_with_plot(&trials, &svg_path);
    let first = read_tum(&trials.join("trajectory_0.txt")).unwrap();
    let windows = json["windows"].as_array().unwrap();
    let on_first = windows
        .iter()
        .filter(|w| first.stamps.contains(&w["start"].as_i64().unwrap()))
        .count();
    assert!(on_first < windows.len(), "trial 0 should miss some starts");
    let svg = check_figure(&svg_path, windows.len(), on_first, first.len());
    assert!(
        svg.contains(&format!(
            "({} of {} not drawn: no pose here)",
            windows.len() - on_first,
            windows.len()
        )),
        "caption"
    );
}

#[test]
fn plot_errors_are_clear() {
    let dir = simulate(&[]);
    let d = dir.path();
    let (gt, est) = (
        d.join("ground_truth.txt"),
        d.join("trials/trajectory_0.txt"),
    );
    let trials = d.join("trials");
    let unwritable = d.join("no/such/dir/figure.svg");
    for args in [
        vec!["rpe", p(&gt), p(&est)],
        vec!["ape", p(&gt), p(&est), "-a"],
        vec!["estimate", p(&trials)],
    ] {
        let mut args = args.clone();
        args.extend(["--plot", p(&unwritable)]);
        let err = one_line_error(&args);
        assert!(
            err.contains(&format!("{}: cannot write the plot", unwritable.display())),
            "{err}"
        );
    }
    // clap rejects an unknown plane (exit code 2) and names the flag and the planes.
    let out = sitar(&[
        "rpe",
        p(&gt),
        p(&est),
        "--plot",
        p(&d.join("x.svg")),
        "--plot-mode",
        "xx",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("invalid value 'xx' for '--plot_mode")
            && stderr.contains("xy, xz, yz, zx, zy, yx, xyz"),
        "{stderr}"
    );
    assert!(!d.join("x.svg").exists());
    // For the estimate, a plane without a figure is a mistake, not silently ignored (evo's
    // ape and rpe take --plot_mode alone, and so do sitar's).
    let out = sitar(&["estimate", p(&trials), "--plot-mode", "xy"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--plot <FILE.svg>"));
}

#[derive(serde::Deserialize)]
struct Golden {
    name: String,
    tool: String,
    reference: String,
    estimate: String,
    args: Vec<String>,
    errors: Vec<f64>,
    stamps_s: Vec<f64>,
    stats: std::collections::HashMap<String, f64>,
}

/// `sitar rpe`/`ape` with evo's own arguments equal `evo_rpe`/`evo_ape` to 1e-9.
#[test]
fn rpe_and_ape_equal_evo() {
    let here = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let goldens: Vec<Golden> =
        serde_json::from_str(&std::fs::read_to_string(here.join("expected.json")).unwrap())
            .unwrap();
    assert!(goldens.len() >= 14);
    for g in &goldens {
        let (r, e) = (
            here.join("data").join(&g.reference),
            here.join("data").join(&g.estimate),
        );
        let mut args = vec![g.tool.as_str(), p(&r), p(&e), "--format", "json"];
        args.extend(g.args.iter().map(String::as_str));
        let json: serde_json::Value = serde_json::from_str(&ok(&args)).unwrap();
        let rows = json["errors"].as_array().unwrap();
        assert_eq!(rows.len(), g.errors.len(), "{}", g.name);
        let tolerance = |v: f64| 1e-9 * v.abs().max(1.0);
        for (k, (row, want)) in rows.iter().zip(&g.errors).enumerate() {
            let got = row["error"].as_f64().unwrap();
            assert!(
                (got - want).abs() <= tolerance(*want),
                "{} row {k}: {got} vs evo {want}",
                g.name
            );
            let stamp_ns = if g.tool == "rpe" {
                &row["end"]
            } else {
                &row["t"]
            };
            let stamp_s = stamp_ns.as_i64().unwrap() as f64 * 1e-9;
            assert!(
                (stamp_s - g.stamps_s[k]).abs() < 0.011,
                "{} row {k}: stamp",
                g.name
            );
        }
        for (key, want) in &g.stats {
            let got = json["statistics"][key].as_f64().unwrap();
            assert!(
                (got - want).abs() <= tolerance(*want),
                "{} {key}: {got} vs evo {want}",
                g.name
            );
        }
    }
}

/// `sitar evaluate` equals an independent evo + numpy/scipy + scikit-learn computation of the
/// paper's protocol (`tests/golden/make_evaluate_golden.py`) to 1e-12.
#[test]
fn evaluate_equals_evo_scipy_sklearn() {
    let eval = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/eval");
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(eval.join("expected.json")).unwrap())
            .unwrap();
    let (gt, a, b) = (
        eval.join("ground_truth.txt"),
        eval.join("trials"),
        eval.join("trials-b"),
    );
    let got: serde_json::Value = serde_json::from_str(&ok(&[
        "evaluate",
        "--ground-truth",
        p(&gt),
        "--trials-a",
        p(&a),
        "--trials-b",
        p(&b),
        "--trial-counts",
        "2,3,4",
        "--format",
        "json",
        "--no-plot",
    ]))
    .unwrap();
    assert_eq!(got["truth_windows"], expected["truth_windows"]);
    let (got, want) = (
        got["results"].as_array().unwrap(),
        expected["results"].as_array().unwrap(),
    );
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(want) {
        for key in ["boundaries_m", "setting", "trials", "windows"] {
            assert_eq!(g[key], w[key], "{key}: {g} vs {w}");
        }
        for key in ["accuracy", "macro_f1", "sensitivity", "specificity"] {
            let (x, y) = (g[key].as_f64().unwrap(), w[key].as_f64().unwrap());
            assert!((x - y).abs() < 1e-12, "{key}: {g} vs {w}");
        }
    }
}

/// `sitar estimate` equals the evo + scipy/numpy goldens of sitar-estimator for every setting
/// (its data: own world frames, dropped frames, stamp jitter, one trial in seconds).
#[test]
fn estimate_equals_evo_scipy_for_every_setting() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../estimator/tests/data");
    let golden: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(data.join("golden_estimate.json")).unwrap())
            .unwrap();
    let trials: Vec<PathBuf> = golden["trials"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| data.join("trials").join(t.as_str().unwrap()))
        .collect();
    let settings = golden["settings"].as_object().unwrap();
    assert_eq!(settings.len(), 7);
    for (setting, windows) in settings {
        let mut args = vec!["estimate", "--setting", setting, "--format", "json"];
        args.extend(trials.iter().map(|t| p(t)));
        let json: serde_json::Value = serde_json::from_str(&ok(&args)).unwrap();
        let got = json["windows"].as_array().unwrap();
        let want = windows.as_array().unwrap();
        assert_eq!(got.len(), want.len(), "{setting}");
        for (g, w) in got.iter().zip(want) {
            assert_eq!(g["start"].as_i64(), w[0].as_i64(), "{setting}");
            let (x, y) = (g["error_m"].as_f64().unwrap(), w[1].as_f64().unwrap());
            assert!((x - y).abs() < 1e-9, "{setting} at {}: {x} vs {y}", w[0]);
            assert_eq!(g["pairs"].as_u64(), w[2].as_u64(), "{setting}");
        }
    }
}

/// The README's main command, end to end: the demo's session gets the phone's camera
/// evidence, and its saved report shows thumbnails and likely causes per region.
#[test]
fn the_demo_sends_the_camera_evidence_and_its_report_shows_it() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("demo");
    let out = ok(&["demo", "--data", p(&data), "--trials", "4"]);
    let sent: usize = out
        .lines()
        .find_map(|l| l.strip_prefix("evidence    "))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no evidence line in:\n{out}"));
    // The estimate from one walk: coloured on the phone at once, first results from the
    // walk at upload, refined by the replays, with how many sub-trajectories changed class.
    let line = |prefix: &str| {
        out.lines()
            .find_map(|l| l.strip_prefix(prefix))
            .unwrap_or_else(|| panic!("no {prefix:?} line in:\n{out}"))
            .to_owned()
    };
    assert!(
        line("instant     ").contains("from the walk alone in"),
        "{out}"
    );
    assert!(
        line("backend     ").starts_with("first results at upload, from the walk alone"),
        "{out}"
    );
    let refined = line("refined     ");
    assert!(
        refined.starts_with("from the walk and 4 replays (backend):")
            && refined.contains("sub-trajectories changed class"),
        "{out}"
    );
    let evidence = std::fs::read_to_string(data.join("demo-phone-session/evidence.csv")).unwrap();
    let with_image = evidence
        .lines()
        .skip(1)
        .filter(|row| row.split(',').nth(1) == Some("1"));
    assert_eq!(
        sent,
        with_image.count(),
        "every thumbnail the phone kept is sent"
    );
    let report = out
        .lines()
        .find_map(|l| l.strip_prefix("report      "))
        .unwrap_or_else(|| panic!("no report line in:\n{out}"));
    let path = report
        .trim()
        .strip_suffix(" (opens from disk)")
        .unwrap_or_else(|| panic!("{report}"));
    let html = std::fs::read_to_string(path).unwrap();
    // The saved page carries its thumbnails inline (it opens with no server).
    assert!(
        html.contains("<img src=\"data:image"),
        "no region thumbnail in the report"
    );
    assert!(
        html.contains("low_texture"),
        "no likely cause in the report"
    );
    assert!(!html.contains("No camera evidence uploaded"));
}

/// `sitar demo --serve`: after the demo the backend keeps running and prints the served
/// report's address with its token; that address opens the report (a browser's first
/// visit: the token becomes a cookie), and Ctrl-C (SIGINT) stops the backend cleanly.
#[test]
fn the_demo_serves_its_report_until_ctrl_c() {
    use std::io::BufRead;
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("demo");
    let mut child = Command::new(env!("CARGO_BIN_EXE_sitar"))
        .args(["demo", "--serve", "--data", p(&data), "--trials", "2"])
        .args(["--seconds", "4", "--speed", "40"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let stdout = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut lines = stdout.lines();
    let url = lines
        .by_ref()
        .map_while(Result::ok)
        .find_map(|l| l.strip_prefix("served      ").map(str::to_owned))
        .expect("no `served` line");
    assert!(url.contains("/report?token=sitar_"), "{url}");
    // The backend comes up again on the same address: poll its health for a while.
    let origin = &url[..url.find("/v1/").unwrap()];
    let started = std::time::Instant::now();
    let addr = origin.trim_start_matches("http://");
    while std::net::TcpStream::connect(addr).is_err() {
        assert!(
            started.elapsed().as_secs() < 20,
            "the backend did not come back"
        );
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    let token = &url[url.find("token=").unwrap() + 6..];
    let report = url.replace(&format!("?token={token}"), "");
    let (status, ct, page) = sitar_tests::get_bytes(&report, Some(token));
    assert_eq!(status, 200);
    assert!(ct.starts_with("text/html"), "{ct}");
    assert!(String::from_utf8_lossy(&page).contains("<h1>SiTAR report</h1>"));
    let pid = child.id().to_string();
    assert!(
        Command::new("kill")
            .args(["-INT", &pid])
            .status()
            .unwrap()
            .success()
    );
    let started = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        assert!(
            started.elapsed().as_secs() < 20,
            "Ctrl-C did not stop the demo's backend"
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    assert!(status.success(), "{status:?}");
}

/// A build without the cluster backends refuses every cluster flag and `sitar migrate`,
/// saying how to get a build that has them (and touches nothing first).
#[cfg(not(feature = "cluster"))]
#[test]
fn cluster_flags_say_how_to_get_a_cluster_build() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let data = data.to_str().unwrap();
    let database = "postgres://sitar@127.0.0.1:9/sitar";
    let store = "s3://bucket/prefix";
    let runs: [&[&str]; 4] = [
        &["serve", "--data", data, "--database", database],
        &["serve", "--data", data, "--store", store],
        &[
            "migrate",
            "--data",
            data,
            "--database",
            database,
            "--store",
            store,
        ],
        &["token", "list", "--database", database],
    ];
    for args in runs {
        let stderr = support::run::fails(args);
        assert!(
            stderr.contains("cargo build --release -p sitar-cli --features cluster"),
            "{args:?}: {stderr}"
        );
    }
    assert!(
        !dir.path().join("data").exists(),
        "a refused command made its data folder"
    );
}
