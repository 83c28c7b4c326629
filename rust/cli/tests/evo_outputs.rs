//! The evo-style commands' other outputs: plots as real PNG, SVG and PDF files (evo's file
//! naming, the 3-D mode, colour-map limits), `-p` without a display, evo's console options
//! (`--silent`, `--no_warnings`, `--logfile`, `-c`), completions and man pages, a closed
//! pipe, and `--time_unit` of `sitar estimate`.

mod support;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use support::run::{ok_both_in, ok_in, sitar_in};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/evo/data")
}

/// A fresh directory with the golden input files.
fn workdir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(data()).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, dir.path().join(path.file_name().unwrap())).unwrap();
    }
    dir
}

/// Decodes a PNG: its size and how many distinct colours it has.
fn png_summary(path: &Path) -> ((u32, u32), usize) {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut pixels).unwrap();
    let colours: std::collections::HashSet<&[u8]> =
        pixels[..info.buffer_size()].chunks(3).collect();
    ((info.width, info.height), colours.len())
}

/// Checks a PDF's structure: header, every xref offset pointing at its object, the page
/// count, and the trailer. Returns the text drawn (the strings of `Tj`).
fn pdf_check(path: &Path, pages: usize) -> String {
    let bytes = std::fs::read(path).unwrap();
    assert!(bytes.starts_with(b"%PDF-1.4\n"));
    let text = String::from_utf8_lossy(&bytes).into_owned();
    assert!(text.trim_end().ends_with("%%EOF"));
    assert!(text.contains(&format!("/Count {pages} >>")), "pages");
    let tail = &bytes[bytes.len() - 64..];
    let tail = String::from_utf8_lossy(tail);
    let start: usize = tail
        .rsplit("startxref\n")
        .next()
        .unwrap()
        .lines()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(bytes[start..].starts_with(b"xref\n"));
    let table = String::from_utf8_lossy(&bytes[start..]).into_owned();
    let mut lines = table.lines().skip(1);
    let count: usize = lines
        .next()
        .unwrap()
        .split(' ')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(count, 4 + 2 * pages);
    lines.next();
    for object in 1..count {
        let offset: usize = lines.next().unwrap()[..10].parse().unwrap();
        assert!(
            bytes[offset..].starts_with(format!("{object} 0 obj").as_bytes()),
            "object {object} at {offset}"
        );
    }
    text.split(" Tm (")
        .skip(1)
        .filter_map(|s| s.split(") Tj").next())
        .collect::<Vec<_>>()
        .join("|")
}

#[test]
fn save_plot_writes_png_svg_and_pdf_by_extension() {
    let dir = workdir();
    let d = dir.path();
    let stdout = ok_in(
        d,
        &[
            "ape",
            "tum",
            "gt.txt",
            "est_a.txt",
            "-a",
            "--save_plot",
            "ape.png",
        ],
    );
    assert!(
        stdout.contains("Plot saved to ape_raw.png")
            && stdout.contains("Plot saved to ape_map.png"),
        "{stdout}"
    );
    for name in ["ape_raw.png", "ape_map.png"] {
        let (size, colours) = png_summary(&d.join(name));
        assert_eq!(size, (1000, 760));
        // Text, lines, the viridis dots and bar: far more than a blank image.
        assert!(colours > 50, "{name}: {colours} colours");
    }
    ok_in(
        d,
        &[
            "rpe",
            "tum",
            "gt.txt",
            "est_b.txt",
            "-d",
            "5",
            "--save_plot",
            "rpe.pdf",
        ],
    );
    let text = pdf_check(&d.join("rpe.pdf"), 2);
    assert!(
        text.contains("RPE w.r.t. translation part \\(m\\)"),
        "{text}"
    );
    assert!(text.contains("for delta = 5 \\(frames\\) using consecutive pairs"));
    assert!(
        !d.join("rpe_raw.pdf").exists(),
        "a PDF holds every page, as evo's"
    );

    // SVG, 3-D: one dot per error on the map, viridis' ends with evo's default limits.
    let json = ok_in(
        d,
        &[
            "ape",
            "tum",
            "gt.txt",
            "est_a.txt",
            "-a",
            "--format",
            "json",
        ],
    );
    let json: serde_json::Value = serde_json::from_str(&json).unwrap();
    let errors: Vec<f64> = json["errors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["error"].as_f64().unwrap())
        .collect();
    ok_in(
        d,
        &[
            "ape",
            "tum",
            "gt.txt",
            "est_a.txt",
            "-a",
            "--save_plot",
            "map.svg",
        ],
    );
    let svg = std::fs::read_to_string(d.join("map_map.svg")).unwrap();
    assert_eq!(svg.matches("<circle").count(), errors.len());
    assert!(svg.contains("estimate in 3-D, coloured by APE, reference dashed"));
    assert!(svg.contains("fill=\"#FDE725\"") && svg.contains("fill=\"#440154\""));
    // --plot_colormap_max: every error at or above it takes the top colour.
    let limit = 0.05;
    ok_in(
        d,
        &[
            "ape",
            "tum",
            "gt.txt",
            "est_a.txt",
            "-a",
            "--plot_mode",
            "xy",
            "--plot_colormap_max",
            "0.05",
            "--save_plot",
            "clamped.svg",
        ],
    );
    let svg = std::fs::read_to_string(d.join("clamped_map.svg")).unwrap();
    let top = svg.matches("fill=\"#FDE725\"").count();
    let above = errors.iter().filter(|&&e| e >= limit).count();
    // The colour bar's top step is a rect of the same colour: one more than the dots.
    assert!(
        top >= above && top <= above + 2,
        "{top} top-coloured vs {above} errors above"
    );
    assert!(above > 0 && above < errors.len());
    assert!(svg.contains("estimate in the xy plane"));
    // An unknown extension is refused before anything is written.
    let out = sitar_in(
        d,
        &["ape", "tum", "gt.txt", "est_a.txt", "--save_plot", "x.jpg"],
    );
    assert_eq!(out.status.code(), Some(1));
}

#[test]
fn traj_and_res_plots() {
    let dir = workdir();
    let d = dir.path();
    ok_in(
        d,
        &[
            "traj",
            "tum",
            "est_a.txt",
            "est_b.txt",
            "--ref",
            "gt.txt",
            "-a",
            "--save_plot",
            "traj.pdf",
            "--plot_mode",
            "xz",
        ],
    );
    let text = pdf_check(&d.join("traj.pdf"), 4);
    for title in ["evo_traj - trajectory plot", "xyz", "speeds", "gt", "est_a"] {
        assert!(text.contains(title), "{title}: {text}");
    }
    ok_in(
        d,
        &[
            "ape",
            "tum",
            "gt.txt",
            "est_a.txt",
            "-a",
            "--save_results",
            "a.zip",
            "--silent",
        ],
    );
    ok_in(
        d,
        &[
            "ape",
            "tum",
            "gt.txt",
            "est_b.txt",
            "-a",
            "--save_results",
            "b.zip",
            "--silent",
        ],
    );
    let stdout = ok_in(d, &["res", "a.zip", "b.zip", "--save_plot", "res.png"]);
    assert!(stdout.contains("Plot saved to res_stats.png"));
    for name in ["res_raw.png", "res_stats.png"] {
        assert!(png_summary(&d.join(name)).1 > 20, "{name}");
    }
}

#[test]
fn show_without_a_display_says_so() {
    let dir = workdir();
    let (stdout, stderr) = ok_both_in(
        dir.path(),
        &["ape", "tum", "gt.txt", "est_a.txt", "-a", "-p"],
    );
    assert!(
        stderr.contains("no display") && stderr.contains("--save_plot"),
        "{stderr}"
    );
    assert!(stdout.contains("APE w.r.t. translation part (m)"));
    let (_, stderr) = ok_both_in(dir.path(), &["traj", "tum", "est_a.txt", "-p"]);
    assert!(stderr.contains("no display"));
}

#[test]
fn console_options_config_and_logfile() {
    let dir = workdir();
    let d = dir.path();
    // --silent prints nothing but still writes the archive.
    let stdout = ok_in(
        d,
        &[
            "ape",
            "tum",
            "gt.txt",
            "est_a.txt",
            "-a",
            "--silent",
            "--save_results",
            "s.zip",
        ],
    );
    assert!(stdout.is_empty() && d.join("s.zip").exists());
    // evo's warnings go to stderr; --no_warnings silences them.
    let (_, stderr) = ok_both_in(d, &["ape", "tum", "gt_unsorted.txt", "est_b.txt", "-a"]);
    assert!(stderr.contains("[WARNING] Timestamps aren't sorted"));
    let (_, stderr) = ok_both_in(
        d,
        &[
            "ape",
            "tum",
            "gt_repeated.txt",
            "est_b.txt",
            "-a",
            "--no_warnings",
        ],
    );
    assert!(stderr.is_empty(), "{stderr}");
    let (_, stderr) = ok_both_in(d, &["ape", "tum", "gt_repeated.txt", "est_b.txt", "-a"]);
    assert!(
        stderr.contains("gt_repeated.txt: 1 repeated timestamp(s), the first on line 62"),
        "{stderr}"
    );
    assert!(
        stderr.contains("associated 145 of max. 145") || stderr.contains("dropped"),
        "{stderr}"
    );
    // -v adds evo's debug lines; --logfile gets them all.
    let stdout = ok_in(
        d,
        &[
            "rpe",
            "tum",
            "gt.txt",
            "est_a.txt",
            "-v",
            "--logfile",
            "log.txt",
        ],
    );
    assert!(stdout.contains("Loaded 150 stamps and poses from: gt.txt"));
    assert!(stdout.contains("Found 136 of max. 136 possible matching timestamps between..."));
    let log = std::fs::read_to_string(d.join("log.txt")).unwrap();
    assert!(
        log.contains("[DEBUG] Loaded 136 stamps and poses from: est_a.txt")
            && log.contains("[INFO] RPE w.r.t.")
    );
    // -c FILE.json: its keys are flags and win over the command line's, as in evo.
    std::fs::write(
        d.join("cfg.json"),
        r#"{"align": true, "pose_relation": "angle_deg", "correct_scale": false, "plot_mode_default": "xy"}"#,
    )
    .unwrap();
    let (with_config, warned) = ok_both_in(
        d,
        &[
            "ape",
            "tum",
            "gt.txt",
            "est_a.txt",
            "-r",
            "full",
            "-c",
            "cfg.json",
        ],
    );
    let direct = ok_in(
        d,
        &["ape", "tum", "gt.txt", "est_a.txt", "-a", "-r", "angle_deg"],
    );
    assert_eq!(with_config, direct);
    assert!(warned.contains("'plot_mode_default' is not an option"));
}

#[test]
fn completions_and_man_pages_come_from_the_flags() {
    let dir = tempfile::tempdir().unwrap();
    for shell in ["bash", "zsh", "fish"] {
        let text = ok_in(dir.path(), &["completions", shell]);
        for word in ["sitar", "traj", "save_results", "pose_relation"] {
            assert!(text.contains(word), "{shell}: {word}");
        }
    }
    let page = ok_in(dir.path(), &["man"]);
    assert!(
        page.starts_with(".ie") || page.contains(".TH sitar"),
        "{}",
        &page[..200.min(page.len())]
    );
    ok_in(dir.path(), &["man", "--out", "pages"]);
    let page = std::fs::read_to_string(dir.path().join("pages/sitar-ape.1")).unwrap();
    assert!(page.contains("sitar\\-ape"), "{page}");
}

#[test]
fn a_closed_pipe_ends_quietly() {
    let dir = workdir();
    // 20 000 poses of CSV: far more than a pipe buffer, so the write meets the closed pipe.
    let mut text = String::new();
    for i in 0..20_000 {
        text += &format!(
            "{}.{:03} {} 0 0 0 0 0 1\n",
            1000 + i / 1000,
            i % 1000,
            i as f64 * 0.01
        );
    }
    std::fs::write(dir.path().join("long.txt"), &text).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_sitar"))
        .args(["ape", "tum", "long.txt", "long.txt", "--format", "csv"])
        .current_dir(dir.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 16];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap();
    // The reader has gone (as `| head` does): the stdout handle was dropped above.
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "exit {:?}", out.status);
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(&first[..8], b"t,error\n");
}

#[test]
fn estimate_reads_small_integer_nanoseconds_with_time_unit() {
    let dir = tempfile::tempdir().unwrap();
    let trial = |name: &str, base: i64, wobble: f64| {
        let mut text = String::new();
        for i in 0..60i64 {
            let x = i as f64 * 0.02 + wobble * ((i * 7 % 5) as f64 - 2.0);
            text += &format!("{} {x} 0 0 0 0 0 1\n", base + i * 33_333_333);
        }
        std::fs::write(dir.path().join(name), text).unwrap();
    };
    for (k, wobble) in [0.0, 0.001, 0.003].iter().enumerate() {
        // Nanoseconds from boot 0: below 10^11, so only --time_unit ns reads them as such.
        trial(&format!("small_{k}.txt"), 0, *wobble);
        trial(&format!("large_{k}.txt"), 1_000_000_000_000, *wobble);
    }
    let run = |prefix: &str, extra: &[&str]| {
        let mut args = vec!["estimate"];
        let files: Vec<String> = (0..3).map(|k| format!("{prefix}_{k}.txt")).collect();
        args.extend(files.iter().map(String::as_str));
        args.extend(extra);
        let text = ok_in(dir.path(), &args);
        text.lines()
            .skip(1)
            .map(|l| l.split(',').nth(1).unwrap().to_owned())
            .collect::<Vec<_>>()
    };
    let large = run("large", &[]);
    assert_eq!(large.len(), 50);
    assert_eq!(run("small", &["--time_unit", "ns"]), large);
    // Without it they are whole seconds (the rule), and the output keeps that unit.
    let small_as_seconds = ok_in(
        dir.path(),
        &["estimate", "small_0.txt", "small_1.txt", "small_2.txt"],
    );
    assert!(small_as_seconds.contains("33333333.000000000,"));
}
