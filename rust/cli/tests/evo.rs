//! `sitar ape|rpe|traj|res` with evo's own command lines against evo 1.38's output on
//! real-format files with dataset quirks (`scripts/golden/make_evo_cli_goldens.py` made the
//! files and the goldens): the printed text (numbers to their printed precision), the
//! archives' info, stats and arrays (1e-9), the saved files, evo's warnings; and, when evo is
//! installed, evo's own `evo_res` reading sitar's archives.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;
use support::run::{fails_in, ok_both_in, ok_in, sitar_in};

fn golden() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/evo")
}

/// evo's test data (TUM RGB-D, EuRoC) and evo's outputs on it.
fn golden_real() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/evo_real")
}

fn cases() -> Vec<Value> {
    cases_in(&golden())
}

fn cases_in(dir: &Path) -> Vec<Value> {
    let text = std::fs::read_to_string(dir.join("expected.json")).unwrap();
    serde_json::from_str::<Value>(&text)
        .unwrap()
        .as_array()
        .unwrap()
        .clone()
}

fn strings(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_owned())
        .collect()
}

/// A fresh directory holding copies of the files of `from`.
fn workdir(from: &Path) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, dir.path().join(path.file_name().unwrap())).unwrap();
    }
    dir
}

/// evo's stdout without its warnings (sitar writes those to stderr) and without the
/// progress percentages of its all-pairs angle search.
fn evo_lines(stdout: &str) -> (Vec<String>, Vec<String>) {
    let mut lines = Vec::new();
    let mut warnings = Vec::new();
    for line in stdout.lines() {
        if let Some(w) = line.strip_prefix("[WARNING] ") {
            warnings.push(w.to_owned());
        } else if !(line.ends_with(" %") && line[..line.len() - 2].parse::<u32>().is_ok()) {
            lines.push(line.to_owned());
        }
    }
    (lines, warnings)
}

fn tokens(line: &str) -> Vec<&str> {
    line.split(|c: char| c.is_whitespace() || "[](),".contains(c))
        .filter(|t| !t.is_empty())
        .collect()
}

/// Two printed lines agree: the same words, numbers equal to `tolerance` (relative above 1).
fn same_line(got: &str, want: &str, tolerance: f64) -> bool {
    let (a, b) = (tokens(got), tokens(want));
    a.len() == b.len()
        && a.iter()
            .zip(&b)
            .all(|(x, y)| match (x.parse::<f64>(), y.parse::<f64>()) {
                (Ok(x), Ok(y)) => (x - y).abs() <= tolerance * y.abs().max(1.0),
                _ => x == y,
            })
}

fn assert_text(name: &str, got: &str, want: &[String], tolerance: f64) {
    let got: Vec<&str> = got.lines().collect();
    assert_eq!(
        got.len(),
        want.len(),
        "{name}: {} lines, evo printed {}:\n{}\n---\n{}",
        got.len(),
        want.len(),
        got.join("\n"),
        want.join("\n")
    );
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            same_line(g, w, tolerance),
            "{name} line {}: '{g}' vs evo '{w}'",
            k + 1
        );
    }
}

fn close(name: &str, what: &str, got: f64, want: f64, tolerance: f64) {
    assert!(
        (got - want).abs() <= tolerance * want.abs().max(1.0) || (got.is_nan() && want.is_nan()),
        "{name} {what}: {got} vs evo {want}"
    );
}

/// The float64 values of a `.npy` written by sitar (format 1.0, `<f8`).
fn npy_values(bytes: &[u8]) -> Vec<f64> {
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let header = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    assert!(
        std::str::from_utf8(&bytes[10..10 + header])
            .unwrap()
            .contains("'<f8'")
    );
    bytes[10 + header..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

/// Entries of a zip archive, in order.
fn zip_entries(path: &Path) -> Vec<(String, Vec<u8>)> {
    let mut archive = zip::ZipArchive::new(std::fs::File::open(path).unwrap()).unwrap();
    (0..archive.len())
        .map(|i| {
            let mut file = archive.by_index(i).unwrap();
            let mut bytes = Vec::new();
            std::io::Read::read_to_end(&mut file, &mut bytes).unwrap();
            (file.name().to_owned(), bytes)
        })
        .collect()
}

/// The entries of a JSON object in the order written.
fn ordered(bytes: &[u8]) -> Vec<(String, Value)> {
    let text = std::str::from_utf8(bytes).unwrap();
    let map: serde_json::Map<String, Value> = serde_json::from_str(text).unwrap();
    let mut keys: Vec<(usize, String)> = map
        .keys()
        .map(|k| (text.find(&format!("\"{k}\":")).unwrap(), k.clone()))
        .collect();
    keys.sort();
    keys.into_iter()
        .map(|(_, k)| (k.clone(), map[&k].clone()))
        .collect()
}

fn check_archive(name: &str, path: &Path, want: &Value) {
    let entries = zip_entries(path);
    let names: Vec<&str> = entries.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, strings(&want["entries"]), "{name}: archive entries");
    let entry = |n: &str| &entries.iter().find(|(k, _)| k == n).unwrap().1;
    let info = ordered(entry("info.json"));
    let want_info = want["info"].as_object().unwrap();
    assert_eq!(info.len(), want_info.len(), "{name}: info.json");
    for (k, v) in &info {
        assert_eq!(v, &want_info[k], "{name}: info {k}");
    }
    let stats = ordered(entry("stats.json"));
    let want_stats: Vec<&String> = want["stats"].as_object().unwrap().keys().collect();
    let order = ["rmse", "mean", "median", "std", "min", "max", "sse"];
    assert_eq!(
        stats.iter().map(|(k, _)| k.as_str()).collect::<Vec<_>>(),
        order,
        "{name}"
    );
    assert_eq!(want_stats.len(), 7);
    for (k, v) in &stats {
        close(
            name,
            k,
            v.as_f64().unwrap(),
            want["stats"][k].as_f64().unwrap(),
            1e-9,
        );
    }
    for (array, values) in want["arrays"].as_object().unwrap() {
        let got = npy_values(entry(&format!("{array}.npy")));
        let want: Vec<f64> = values
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|v| match v {
                Value::Array(row) => row.iter().map(|x| x.as_f64().unwrap()).collect(),
                x => vec![x.as_f64().unwrap()],
            })
            .collect();
        assert_eq!(got.len(), want.len(), "{name}: {array} length");
        // Stamps are 1e9-sized seconds (float rounding ~1e-7 s after interpolation).
        let tolerance = if array.contains("second") || array == "timestamps" {
            1e-6
        } else {
            1e-9
        };
        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
            close(name, &format!("{array}[{k}]"), *g, *w, tolerance);
        }
    }
    // Arrays recorded as the bits of evo's float64s: equal to the last bit.
    for (array, bits) in want
        .get("bits")
        .and_then(Value::as_object)
        .into_iter()
        .flatten()
    {
        let got: Vec<u64> = npy_values(entry(&format!("{array}.npy")))
            .iter()
            .map(|v| v.to_bits())
            .collect();
        let want: Vec<u64> = bits
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b.as_u64().unwrap())
            .collect();
        assert_eq!(got.len(), want.len(), "{name}: {array} length");
        let differing = got.iter().zip(&want).filter(|(g, w)| g != w).count();
        assert_eq!(
            differing, 0,
            "{name}: {differing} values of {array} differ from evo's bits"
        );
    }
}

/// Files saved by evo (`%.18e` numbers) and by sitar agree word by word, numbers to 1e-9.
fn check_saved(name: &str, dir: &Path, saved: &serde_json::Map<String, Value>) {
    for (file, want) in saved {
        let got = std::fs::read_to_string(dir.join(file))
            .unwrap_or_else(|e| panic!("{name}: sitar did not write {file}: {e}"));
        let want: Vec<&str> = want
            .as_str()
            .unwrap()
            .lines()
            .filter(|l| !l.is_empty())
            .collect();
        let got_lines: Vec<&str> = got.lines().filter(|l| !l.is_empty()).collect();
        assert_eq!(got_lines.len(), want.len(), "{name}: {file} lines");
        for (g, w) in got_lines.iter().zip(&want) {
            assert!(same_line(g, w, 1e-9), "{name}: {file}: '{g}' vs evo '{w}'");
        }
    }
}

#[test]
fn sitar_prints_saves_and_warns_as_evo_does() {
    let cases = cases();
    let tools: Vec<&str> = cases.iter().map(|c| c["tool"].as_str().unwrap()).collect();
    for tool in ["ape", "rpe", "traj", "res"] {
        assert!(
            tools.iter().filter(|t| **t == tool).count() >= 5,
            "{tool} cases"
        );
    }
    assert!(cases.len() >= 30);
    let evo_archives = golden().join("archives");
    let ours = tempfile::tempdir().unwrap();
    for case in &cases {
        let name = case["name"].as_str().unwrap();
        let source = if case["tool"] == "res" {
            evo_archives.clone()
        } else {
            golden().join("data")
        };
        let dir = run_case(case, &source);
        if case.get("archive").is_some() {
            std::fs::copy(
                dir.path().join("result.zip"),
                ours.path().join(format!("{name}.zip")),
            )
            .unwrap();
        }
    }
    evo_res_reads_sitar_archives(ours.path(), &evo_archives);
}

/// evo's own sample files (TUM fr1/xyz and fr2/desk, EuRoC V1_02): association decided
/// as evo's float64 seconds decide it (the fr2/desk tie at 1311868226.310950), every
/// statistic and error to 1e-9, `timestamps` and `seconds_from_start` equal to the bit.
#[test]
fn real_files_to_the_last_digit() {
    let cases = cases_in(&golden_real());
    assert!(cases.len() >= 10);
    for case in &cases {
        run_case(case, &golden_real().join("data"));
    }
}

/// SiTAR's extras on the same files: `--format csv|json` and the older `sitar rpe REF EST`
/// form print every error evo's archive holds (1e-9), so the association behind them is
/// evo's too.
#[test]
fn csv_json_and_the_older_form_associate_as_evo() {
    let cases = cases_in(&golden_real());
    let errors_of = |name: &str| -> Vec<f64> {
        let case = cases.iter().find(|c| c["name"] == name).unwrap();
        let values = case["archive"]["arrays"]["error_array"].as_array().unwrap();
        values.iter().map(|v| v.as_f64().unwrap()).collect()
    };
    let dir = workdir(&golden_real().join("data"));
    let (gt, est) = ("fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt");
    let pairs = ["-d", "10", "--all_pairs", "-a"];
    let runs: [(&str, Vec<&str>, &str); 3] = [
        (
            "ape_fr2_desk",
            vec!["ape", "tum", gt, est, "-a", "--format", "csv"],
            "csv",
        ),
        (
            "rpe_fr2_desk_all_pairs",
            [&["rpe", "tum", gt, est][..], &pairs, &["--format", "csv"]].concat(),
            "csv",
        ),
        (
            "rpe_fr2_desk_all_pairs",
            [&["rpe", gt, est][..], &pairs, &["--format", "json"]].concat(),
            "json",
        ),
    ];
    for (golden_case, args, format) in runs {
        let text = ok_in(dir.path(), &args);
        let got: Vec<f64> = if format == "csv" {
            text.lines()
                .skip(1)
                .take_while(|l| !l.is_empty())
                .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
                .collect()
        } else {
            let json: Value = serde_json::from_str(&text).unwrap();
            json["errors"]
                .as_array()
                .unwrap()
                .iter()
                .map(|e| e["error"].as_f64().unwrap())
                .collect()
        };
        let want = errors_of(golden_case);
        assert_eq!(got.len(), want.len(), "{args:?}: number of errors");
        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
            close(golden_case, &format!("{format} error {k}"), *g, *w, 1e-9);
        }
    }
}

/// Usage hints name what the usage shows (`--all_pairs`, not its alias), and a file given
/// in the wrong format gets a hint naming the format it reads as.
#[test]
fn hints_name_the_right_spelling_and_format() {
    let dir = workdir(&golden_real().join("data"));
    let run = |args: &[&str]| fails_in(dir.path(), args);
    let (gt, est) = ("fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt");
    let usage = run(&["rpe", "tum", gt, est, "--all-pair"]);
    assert!(usage.contains("'--all_pairs'"), "{usage}");
    assert!(!usage.contains("--all-pairs"), "{usage}");
    for (args, hint) in [
        (
            vec!["ape", "euroc", gt, est],
            "use `tum` in place of `euroc`",
        ),
        (
            vec!["ape", "kitti", gt, est],
            "use `tum` in place of `kitti`",
        ),
        (
            vec!["rpe", "tum", "V102_groundtruth.csv", "V102.txt"],
            "use `euroc` in place of `tum`",
        ),
        (vec!["traj", "euroc", est], "use `tum` in place of `euroc`"),
    ] {
        let stderr = run(&args);
        assert!(stderr.starts_with("sitar: error: "), "{stderr}");
        assert!(stderr.contains(hint), "{args:?}: {stderr}");
    }
}

/// What evo's figures show, in sitar's SVGs of the real files: x/y/z axis labels on the 3-D
/// map and trajectory plots, an offset time axis, the colour bar's label, the statistics'
/// names beside evo_res's bars, its histogram, box and violin figures, and a warning for the
/// repeated stamp that leaves the trajectory out of the speeds, in evo's words.
#[test]
fn figures_carry_evo_labels() {
    let dir = workdir(&golden_real().join("data"));
    let run = |args: &[&str]| ok_both_in(dir.path(), args).1;
    let texts = |file: &str| -> Vec<String> {
        let svg = std::fs::read_to_string(dir.path().join(file)).unwrap();
        svg.split("<text")
            .skip(1)
            .filter_map(|t| {
                Some(
                    t.split_once('>')?
                        .1
                        .split_once("</text>")?
                        .0
                        .trim()
                        .to_owned(),
                )
            })
            .collect()
    };
    let has = |file: &str, want: &[&str]| {
        let got = texts(file);
        for w in want {
            assert!(
                got.iter().any(|t| t == w),
                "{file}: no text '{w}' among {got:?}"
            );
        }
    };
    let (gt, est) = (
        "freiburg1_xyz-groundtruth.txt",
        "freiburg1_xyz-rgbdslam.txt",
    );
    run(&[
        "ape",
        "tum",
        gt,
        est,
        "-a",
        "--save_plot",
        "ape.svg",
        "--save_results",
        "a.zip",
    ]);
    has("ape_map.svg", &["x (m)", "y (m)", "z (m)", "APE (m)"]);
    has("ape_raw.svg", &["rmse", "median", "mean", "std"]);
    run(&[
        "ape",
        "tum",
        "fr2_desk_groundtruth.txt",
        "fr2_desk_ORB.txt",
        "-a",
        "--save_results",
        "b.zip",
    ]);
    run(&["traj", "tum", est, "--ref", gt, "--save_plot", "t.svg"]);
    has("t_trajectories.svg", &["x (m)", "y (m)", "z (m)"]);
    has("t_xyz.svg", &["t (s) + 1305031000", "x (m)", "100", "125"]);
    run(&[
        "res",
        "a.zip",
        "b.zip",
        "--use_filenames",
        "--save_plot",
        "r.svg",
    ]);
    has(
        "r_stats.svg",
        &["rmse", "mean", "median", "std", "min", "max"],
    );
    has(
        "r_histogram.svg",
        &["estimate = a.zip", "estimate = b.zip", "Density", "APE (m)"],
    );
    has("r_box_plot.svg", &["a.zip", "b.zip", "estimate", "APE (m)"]);
    has(
        "r_violin_histogram.svg",
        &["a.zip", "b.zip", "estimate", "APE (m)"],
    );
    let warned = run(&[
        "traj",
        "tum",
        "fr2_desk_groundtruth.txt",
        "--save_plot",
        "s.svg",
    ]);
    assert!(
        warned.contains(
            "Can't plot speeds of fr2_desk_groundtruth: bad timestamps: 1311868229.576 & 1311868229.576"
        ),
        "{warned}"
    );
}

/// ROS 2 bags made by rosbags from the fr1/xyz trajectories (both storages, every pose
/// message type evo reads): the printed text, and the archive's statistics and errors to
/// 1e-9, against evo_ape/evo_rpe/evo_traj `bag2` (topics, `--all_topics`) on the same bags.
#[test]
fn ros2_bags_as_evo_reads_them() {
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/evo_bags");
    let cases = cases_in(&golden);
    assert!(cases.len() >= 5);
    let dir = tempfile::tempdir().unwrap();
    for bag in ["fr1_mcap", "fr1_db3"] {
        std::fs::create_dir(dir.path().join(bag)).unwrap();
        for entry in std::fs::read_dir(golden.join(bag)).unwrap() {
            let path = entry.unwrap().path();
            std::fs::copy(&path, dir.path().join(bag).join(path.file_name().unwrap())).unwrap();
        }
    }
    for case in &cases {
        let name = case["name"].as_str().unwrap();
        let mut args = vec![case["tool"].as_str().unwrap().to_owned()];
        args.extend(strings(&case["args"]));
        let archived = case.get("stats").is_some();
        if archived {
            args.extend(["--save_results".into(), format!("{name}.zip")]);
        }
        let (stdout, stderr) = ok_both_in(dir.path(), &args);
        let (want, warnings) = evo_lines(case["stdout"].as_str().unwrap());
        assert_text(name, &stdout, &want, 1e-6);
        for w in warnings {
            assert!(stderr.contains(&w), "{name}: evo warned '{w}': {stderr}");
        }
        if !archived {
            continue;
        }
        let entries = zip_entries(&dir.path().join(format!("{name}.zip")));
        let entry = |n: &str| &entries.iter().find(|(k, _)| k == n).unwrap().1;
        let stats: Value = serde_json::from_slice(entry("stats.json")).unwrap();
        for (k, v) in case["stats"].as_object().unwrap() {
            close(
                name,
                k,
                stats[k].as_f64().unwrap(),
                v.as_f64().unwrap(),
                1e-9,
            );
        }
        let errors = npy_values(entry("error_array.npy"));
        let want = case["errors"].as_array().unwrap();
        assert_eq!(errors.len(), want.len(), "{name}: errors");
        for (k, (g, w)) in errors.iter().zip(want).enumerate() {
            close(name, &format!("error {k}"), *g, w.as_f64().unwrap(), 1e-9);
        }
    }
    // What evo does not read is named with its topic and type.
    let stderr = fails_in(
        dir.path(),
        &["ape", "bag2", "fr1_mcap", "/ground_truth", "/cmd_vel"],
    );
    assert!(
        stderr.contains("/cmd_vel") && stderr.contains("geometry_msgs/msg/Twist"),
        "{stderr}"
    );
    let stderr = fails_in(
        dir.path(),
        &["rpe", "bag2", "fr1_db3", "/ground_truth", "/none"],
    );
    assert!(stderr.contains("no messages for topic '/none'"), "{stderr}");
}

/// Copies every file and bag directory of `from` (one level of directories) into a new
/// temporary directory.
fn copy_bags(from: &Path) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let dest = dir.path().join(path.file_name().unwrap());
        if path.is_dir() {
            std::fs::create_dir(&dest).unwrap();
            for inner in std::fs::read_dir(&path).unwrap() {
                let inner = inner.unwrap().path();
                std::fs::copy(&inner, dest.join(inner.file_name().unwrap())).unwrap();
            }
        } else {
            std::fs::copy(&path, dest).unwrap();
        }
    }
    dir
}

/// ROS 1 bags (uncompressed, bz2 and lz4 chunks), compressed ROS 2 bags (MCAP zstd and lz4
/// chunks; sqlite3 with rosbag2's zstd file and message compression) and a tf bag, made by
/// rosbags from the fr1/xyz trajectories: the printed text, the archive's statistics and
/// errors to 1e-9 and its timestamps bit for bit, against evo_ape/evo_rpe/evo_traj on the
/// same bags. The tf trajectory `/tf:map.base` equals the reference tf2 lookup (numpy, in
/// the golden script) to 1e-9 and gives evo's numbers on that reference.
#[test]
fn ros1_compressed_and_tf_bags_as_evo_reads_them() {
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/evo_bag_formats");
    let expected: Value =
        serde_json::from_str(&std::fs::read_to_string(golden.join("expected.json")).unwrap())
            .unwrap();
    let cases = expected["cases"].as_array().unwrap();
    assert!(cases.len() >= 10);
    let dir = copy_bags(&golden);
    for case in cases {
        let name = case["name"].as_str().unwrap();
        let mut args = vec![case["tool"].as_str().unwrap().to_owned()];
        args.extend(strings(&case["args"]));
        // The tf case: sitar reads the transform where evo read its reference topic.
        let tf_case = args.iter().any(|a| a == "/tf_reference");
        for a in &mut args {
            if a == "/tf_reference" {
                *a = "/tf:map.base".into();
            }
        }
        let archived = case.get("stats").is_some();
        if archived {
            args.extend(["--save_results".into(), format!("{name}.zip")]);
        }
        let (stdout, stderr) = ok_both_in(dir.path(), &args);
        let (want, warnings) = evo_lines(case["stdout"].as_str().unwrap());
        if !tf_case {
            assert_text(name, &stdout, &want, 1e-6);
        }
        for w in warnings {
            assert!(stderr.contains(&w), "{name}: evo warned '{w}': {stderr}");
        }
        if !archived {
            continue;
        }
        let entries = zip_entries(&dir.path().join(format!("{name}.zip")));
        let entry = |n: &str| &entries.iter().find(|(k, _)| k == n).unwrap().1;
        let stats: Value = serde_json::from_slice(entry("stats.json")).unwrap();
        for (k, v) in case["stats"].as_object().unwrap() {
            close(
                name,
                k,
                stats[k].as_f64().unwrap(),
                v.as_f64().unwrap(),
                1e-9,
            );
        }
        let errors = npy_values(entry("error_array.npy"));
        let want = case["errors"].as_array().unwrap();
        assert_eq!(errors.len(), want.len(), "{name}: errors");
        for (k, (g, w)) in errors.iter().zip(want).enumerate() {
            close(name, &format!("error {k}"), *g, w.as_f64().unwrap(), 1e-9);
        }
        let stamps = npy_values(entry("timestamps.npy"));
        let want: Vec<f64> = case["timestamps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| t.as_str().unwrap().parse().unwrap())
            .collect();
        assert_eq!(stamps.len(), want.len(), "{name}: timestamps");
        for (k, (g, w)) in stamps.iter().zip(&want).enumerate() {
            assert_eq!(
                g.to_bits(),
                w.to_bits(),
                "{name}: timestamp {k}: {g} vs evo's {w}"
            );
        }
    }
    // The tf lookup, pose by pose, against the reference (ROS 1 and ROS 2 bags alike).
    let reference = expected["tf_reference"].as_array().unwrap();
    for bag in [["bag", "fr1_ros1.bag"], ["bag2", "fr1_tf"]] {
        ok_in(
            dir.path(),
            &["traj", bag[0], bag[1], "/tf:map.base", "--save_as_tum"],
        );
        let text = std::fs::read_to_string(dir.path().join("tf_map.base.tum")).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| l.split_whitespace().map(|v| v.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), reference.len(), "{}", bag[1]);
        for (row, want) in rows.iter().zip(reference) {
            let mut want: Vec<f64> = want
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            assert!((row[0] - want[0] / 1e9).abs() < 1e-6, "{row:?} {want:?}");
            // sitar normalises the looked-up rotation (the file's quaternions are rounded).
            let norm = want[4..8].iter().map(|v| v * v).sum::<f64>().sqrt();
            want[4..8].iter_mut().for_each(|v| *v /= norm);
            for k in 1..8 {
                close(bag[1], "tf pose", row[k], want[k], 1e-9);
            }
        }
    }
    // Errors name the frames, the topic and the message type.
    for (args, message) in [
        (
            vec!["ape", "bag2", "fr1_tf", "/ground_truth", "/tf:map.camera"],
            "\"camera\"",
        ),
        (
            vec!["ape", "bag2", "fr1_tf", "/ground_truth", "/tf:map"],
            "child frame id is missing",
        ),
        (
            vec!["ape", "bag", "fr1_lz4.bag", "/ground_truth", "/tf:map.base"],
            "no messages for topic /tf",
        ),
        (
            vec!["ape", "bag", "fr1_ros1.bag", "/ground_truth", "/cmd_vel"],
            "geometry_msgs/msg/Twist",
        ),
        (vec!["ape", "bag", "fr1_tf", "/a", "/b"], "not a ROS 1 bag"),
        (
            vec!["ape", "bag", "fr1_tf/metadata.yaml", "/a", "/b"],
            "not a ROS 1 bag",
        ),
        (
            vec!["ape", "bag2", "fr1_ros1.bag", "/a", "/b"],
            "fr1_ros1.bag",
        ),
    ] {
        let stderr = fails_in(dir.path(), &args);
        assert!(stderr.contains(message), "{args:?}: {stderr}");
    }
}

/// `traj --save_as_bag` / `--save_as_bag2` write evo's `<date>.bag` and `<date>/` (MCAP)
/// with a PoseStamped topic per trajectory; sitar reads them back to the same poses, and so
/// does evo_traj (when installed).
#[test]
fn saved_bags_read_back_in_sitar_and_evo() {
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/evo_bag_formats");
    let dir = copy_bags(&golden);
    let out = tempfile::tempdir().unwrap();
    let source = dir.path().join("fr1_mcap_zstd");
    let source = source.to_str().unwrap();
    ok_in(
        out.path(),
        &[
            "traj",
            "bag2",
            source,
            "/odom",
            "--ref",
            "/ground_truth",
            "--save_as_bag",
            "--save_as_bag2",
            "--save_as_tum",
        ],
    );
    let mut bag1 = None;
    let mut bag2 = None;
    for entry in std::fs::read_dir(out.path()).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.ends_with(".bag") {
            bag1 = Some(name);
        } else if path.is_dir() {
            assert!(
                path.join(format!("{name}.mcap")).exists() && path.join("metadata.yaml").exists()
            );
            bag2 = Some(name);
        }
    }
    let (bag1, bag2) = (bag1.expect("a .bag"), bag2.expect("a bag directory"));
    // evo's name: the date and time, 2026-12-05-05-17-00.bag.
    assert_eq!(bag1.len(), "YYYY-MM-DD-HH-MM-SS.bag".len(), "{bag1}");
    let tum = |path: &Path| -> Vec<Vec<f64>> {
        std::fs::read_to_string(path)
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| l.split_whitespace().map(|v| v.parse().unwrap()).collect())
            .collect()
    };
    let original = |topic: &str| tum(&out.path().join(format!("{topic}.tum")));
    let same = |what: &str, got: &[Vec<f64>], want: &[Vec<f64>]| {
        assert_eq!(got.len(), want.len(), "{what}");
        for (g, w) in got.iter().zip(want) {
            // evo writes stamps truncated to whole ns: within 2 ns of the originals.
            assert!(
                (g[0] - w[0]).abs() < 3e-9 * w[0].abs().max(1.0),
                "{what}: {g:?} {w:?}"
            );
            for k in 1..8 {
                close(what, "pose", g[k], w[k], 1e-12);
            }
        }
    };
    let (odom, truth) = (original("odom"), original("ground_truth"));
    for (kind, bag) in [("bag", &bag1), ("bag2", &bag2)] {
        let back = tempfile::tempdir().unwrap();
        let path = out.path().join(bag);
        ok_in(
            back.path(),
            &[
                "traj",
                kind,
                path.to_str().unwrap(),
                "--all_topics",
                "--save_as_tum",
            ],
        );
        same(kind, &tum(&back.path().join("odom.tum")), &odom);
        same(kind, &tum(&back.path().join("ground_truth.tum")), &truth);
        let probe = Command::new("evo_traj").arg("--help").output();
        if !probe.is_ok_and(|o| o.status.success()) {
            println!(
                "SKIPPED evo_traj on sitar's bags: evo_traj is not on PATH (pip install evo==1.38.1 rosbags)"
            );
            continue;
        }
        let evo = tempfile::tempdir().unwrap();
        let done = Command::new("evo_traj")
            .args([
                kind,
                path.to_str().unwrap(),
                "--all_topics",
                "--save_as_tum",
                "--no_warnings",
            ])
            .current_dir(evo.path())
            .output()
            .unwrap();
        assert!(
            done.status.success(),
            "evo_traj {kind}: {}",
            String::from_utf8_lossy(&done.stderr)
        );
        same(
            &format!("evo {kind}"),
            &tum(&evo.path().join("odom.tum")),
            &odom,
        );
        same(
            &format!("evo {kind}"),
            &tum(&evo.path().join("ground_truth.tum")),
            &truth,
        );
    }
}

/// Runs one golden case in a copy of `source` and checks stdout, warnings, the archive
/// and the saved files against evo's; returns the directory it ran in.
fn run_case(case: &Value, source: &Path) -> tempfile::TempDir {
    {
        let name = case["name"].as_str().unwrap();
        let tool = case["tool"].as_str().unwrap();
        let dir = workdir(source);
        let mut args = vec![tool.to_owned()];
        args.extend(strings(&case["args"]));
        if case.get("archive").is_some() {
            args.extend(["--save_results".into(), "result.zip".into()]);
        }
        let out = sitar_in(dir.path(), &args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success(),
            "{name}: sitar {args:?} failed: {stderr}"
        );
        let (want, warnings) = evo_lines(case["stdout"].as_str().unwrap());
        // Printed statistics have 6 decimals; longer numbers (traj) agree far closer.
        assert_text(name, &String::from_utf8_lossy(&out.stdout), &want, 1e-6);
        for w in warnings {
            assert!(
                stderr.lines().any(|l| l == format!("[WARNING] {w}")),
                "{name}: evo warned '{w}', sitar's stderr: {stderr}"
            );
        }
        if let Some(archive) = case.get("archive") {
            check_archive(name, &dir.path().join("result.zip"), archive);
        }
        check_saved(name, dir.path(), case["saved"].as_object().unwrap());
        dir
    }
}

/// evo's `evo_res` reads every archive sitar wrote and prints the statistics it prints for
/// evo's own archives of the same cases.
fn evo_res_reads_sitar_archives(ours: &Path, theirs: &Path) {
    let probe = Command::new("evo_res").arg("--help").output();
    if !probe.is_ok_and(|o| o.status.success()) {
        println!(
            "SKIPPED evo_res on sitar's archives: evo_res is not on PATH (pip install evo==1.38.1)"
        );
        return;
    }
    let mut names: Vec<String> = std::fs::read_dir(ours)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(names.len() >= 30, "{} archives", names.len());
    let run = |dir: &Path| {
        let out = Command::new("evo_res")
            .args(&names)
            .args(["--use_filenames", "--ignore_title", "--no_warnings"])
            .current_dir(dir)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "evo_res in {}: {}",
            dir.display(),
            String::from_utf8_lossy(&out.stdout)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    let (on_ours, on_theirs) = (run(ours), run(theirs));
    let want: Vec<String> = on_theirs.lines().map(str::to_owned).collect();
    assert_text("evo_res on sitar's archives", &on_ours, &want, 1e-6);
    for name in &names {
        assert!(
            on_ours.contains(name.as_str()),
            "evo_res did not list {name}"
        );
    }
}

#[test]
fn bag_formats_and_viewers_are_refused_clearly() {
    let dir = workdir(&golden().join("data"));
    for (args, message) in [
        (
            vec!["ape", "bag", "x.bag", "/a", "/b"],
            "x.bag: cannot read",
        ),
        (vec!["rpe", "bag2", "x", "/a", "/b"], "x: cannot read"),
        (
            vec!["rpe", "mcap", "gt.txt", "/a", "/b"],
            "MCAP: Bad magic number",
        ),
        (vec!["traj", "bag", "x.bag", "/a"], "x.bag: cannot read"),
        (
            vec!["ape", "tum", "gt.txt", "est_a.txt", "--rerun"],
            "--rerun is not supported",
        ),
        (
            vec!["ape", "tum", "gt.txt", "est_a.txt", "--save_plot", "x.gif"],
            ".png, .svg or .pdf",
        ),
    ] {
        let out = sitar_in(dir.path(), &args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.starts_with("sitar: error: ") && stderr.contains(message),
            "{args:?}: {stderr}"
        );
    }
    // A NUL byte is no separator: the error names file, line and column.
    std::fs::write(
        dir.path().join("nul.txt"),
        "1 0 0 0 0 0 0 1\n2 0\x000 0 0 0 0 1\n",
    )
    .unwrap();
    let out = sitar_in(dir.path(), &["ape", "tum", "nul.txt", "est_a.txt"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("nul.txt:2:4: control character U+0000"),
        "{stderr}"
    );
}
