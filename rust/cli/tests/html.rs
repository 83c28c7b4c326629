//! `--html FILE` of `sitar ape`, `rpe` and `drift`: one page that holds the tables, every
//! figure inline and the very JSON document `--format json` prints, and asks for nothing
//! when opened.

mod support;

use std::path::Path;

use serde_json::Value;
use support::run::{fails_in, ok_in};

/// A 20 m walk on a helix (TUM, seconds) and two estimates that drift from it differently.
fn files(dir: &Path) {
    let pose = |i: usize, drift: f64| {
        let t = i as f64 * 0.1;
        let a = t * 0.3;
        format!(
            "{t:.3} {:.6} {:.6} {:.6} 0 0 {:.6} {:.6}\n",
            4.0 * a.cos() + drift * t,
            4.0 * a.sin(),
            0.05 * t + 0.5 * drift * (t * 0.7).sin(),
            (a / 2.0).sin(),
            (a / 2.0).cos()
        )
    };
    let write = |name: &str, drift: f64| {
        let text: String = (0..200).map(|i| pose(i, drift)).collect();
        std::fs::write(dir.join(name), text).unwrap();
    };
    write("gt.txt", 0.0);
    write("run0.txt", 0.01);
    write("run1.txt", 0.03);
}

/// The JSON document shown in the page (HTML-unescaped from its `<pre>`).
fn page_document(html: &str) -> Value {
    let start = html.find("<pre class=\"json\">").expect("a JSON block") + 18;
    let end = start + html[start..].find("</pre>").unwrap();
    let text = html[start..end]
        .replace("&quot;", "\"")
        .replace("&#x27;", "'")
        .replace("&#x2f;", "/")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    serde_json::from_str(&text).expect("the page's JSON parses")
}

/// Asserts the page is self-contained and returns its figures' count.
fn self_contained(html: &str) -> usize {
    assert!(html.starts_with("<!DOCTYPE html>"));
    assert!(html.contains("Content-Security-Policy"));
    assert!(html.contains("default-src 'none'"));
    for fetch in [
        "src=\"http",
        "src=\"/",
        "href=\"",
        "url(",
        "<script",
        "<link",
    ] {
        assert!(
            !html.contains(fetch),
            "the page would fetch something: {fetch}"
        );
    }
    html.matches("<img src=\"data:image/svg+xml;base64,")
        .count()
}

#[test]
fn ape_of_one_run_gives_its_table_both_figures_and_its_json() {
    let dir = tempfile::tempdir().unwrap();
    files(dir.path());
    let json = ok_in(
        dir.path(),
        &["ape", "tum", "gt.txt", "run1.txt", "-a", "--format", "json"],
    );
    ok_in(
        dir.path(),
        &[
            "ape", "tum", "gt.txt", "run1.txt", "-a", "--html", "ape.html",
        ],
    );
    let html = std::fs::read_to_string(dir.path().join("ape.html")).unwrap();
    assert_eq!(self_contained(&html), 2, "raw and map figures");
    let expected: Value = serde_json::from_str(&json).unwrap();
    assert_eq!(page_document(&html), expected);
    let rmse = expected["statistics"]["rmse"].as_f64().unwrap();
    assert!(
        html.contains(&format!("<td class=\"num\">{rmse:.6}</td>")),
        "the RMSE is in a table"
    );
    assert!(html.contains("<td>pairing.paired</td>"));
}

#[test]
fn repeated_runs_give_the_runs_table_and_the_box_plot() {
    let dir = tempfile::tempdir().unwrap();
    files(dir.path());
    let args = [
        "rpe",
        "tum",
        "gt.txt",
        "run0.txt",
        "run1.txt",
        "-a",
        "--delta",
        "1",
        "--delta_unit",
        "m",
    ];
    let json = ok_in(dir.path(), &[&args[..], &["--format", "json"]].concat());
    ok_in(dir.path(), &[&args[..], &["--html", "rpe.html"]].concat());
    let html = std::fs::read_to_string(dir.path().join("rpe.html")).unwrap();
    assert_eq!(self_contained(&html), 1, "the box plot over runs");
    assert_eq!(
        page_document(&html),
        serde_json::from_str::<Value>(&json).unwrap()
    );
    assert!(html.contains("<h2>trials</h2>"));
    assert!(html.contains("<h2>across runs</h2>"));
}

#[test]
fn drift_pages_hold_the_per_length_table_and_every_plot() {
    let dir = tempfile::tempdir().unwrap();
    files(dir.path());
    let one = [
        "drift",
        "tum",
        "gt.txt",
        "run1.txt",
        "--lengths",
        "2,4",
        "--step",
        "5",
    ];
    let json = ok_in(dir.path(), &[&one[..], &["--format", "json"]].concat());
    ok_in(dir.path(), &[&one[..], &["--html", "drift.html"]].concat());
    let html = std::fs::read_to_string(dir.path().join("drift.html")).unwrap();
    assert_eq!(
        self_contained(&html),
        2,
        "error against length and against speed"
    );
    assert_eq!(
        page_document(&html),
        serde_json::from_str::<Value>(&json).unwrap()
    );
    assert!(html.contains("<h2>by length</h2>"));

    let runs = [
        "drift",
        "tum",
        "gt.txt",
        "run0.txt",
        "run1.txt",
        "--lengths",
        "2,4",
    ];
    ok_in(dir.path(), &[&runs[..], &["--html", "runs.html"]].concat());
    let html = std::fs::read_to_string(dir.path().join("runs.html")).unwrap();
    assert_eq!(self_contained(&html), 4, "two curves and two box plots");
}

#[test]
fn an_unwritable_page_is_an_error_that_names_it() {
    let dir = tempfile::tempdir().unwrap();
    files(dir.path());
    let stderr = fails_in(
        dir.path(),
        &[
            "ape",
            "tum",
            "gt.txt",
            "run0.txt",
            "--html",
            "missing/ape.html",
        ],
    );
    assert!(stderr.contains("missing/ape.html"), "{stderr}");
}

#[test]
fn relative_and_bench_pages_hold_their_tables_and_box_plots() {
    let dir = tempfile::tempdir().unwrap();
    files(dir.path());
    let rel = [
        "relative",
        "tum",
        "gt.txt",
        "run0.txt",
        "run1.txt",
        "--lengths",
        "2,4",
    ];
    let json = ok_in(dir.path(), &[&rel[..], &["--format", "json"]].concat());
    ok_in(
        dir.path(),
        &[&rel[..], &["--html", "relative.html"]].concat(),
    );
    let html = std::fs::read_to_string(dir.path().join("relative.html")).unwrap();
    assert!(self_contained(&html) >= 2, "a box plot per error");
    assert_eq!(
        page_document(&html),
        serde_json::from_str::<Value>(&json).unwrap()
    );

    // A plain tree: ALG/SEQ/runN.txt beside gt/SEQ.txt.
    let tree = dir.path().join("tree");
    for (alg, runs) in [
        ("vio", ["run0.txt", "run1.txt"]),
        ("slam", ["run1.txt", "run0.txt"]),
    ] {
        std::fs::create_dir_all(tree.join(alg).join("helix")).unwrap();
        for (k, run) in runs.iter().enumerate() {
            std::fs::copy(
                dir.path().join(run),
                tree.join(alg).join("helix").join(format!("run{k}.txt")),
            )
            .unwrap();
        }
    }
    std::fs::create_dir_all(tree.join("gt")).unwrap();
    std::fs::copy(dir.path().join("gt.txt"), tree.join("gt/helix.txt")).unwrap();
    let json = ok_in(
        dir.path(),
        &["bench", "tree", "--lengths", "2,4", "--format", "json"],
    );
    ok_in(
        dir.path(),
        &["bench", "tree", "--lengths", "2,4", "--html", "bench.html"],
    );
    let html = std::fs::read_to_string(dir.path().join("bench.html")).unwrap();
    assert_eq!(
        self_contained(&html),
        3,
        "APE RMSE, then the sequence's translation and yaw"
    );
    let expected: Value = serde_json::from_str(&json).unwrap();
    assert_eq!(page_document(&html), expected);
    assert!(
        html.contains("<h1>sitar bench</h1>"),
        "titled by its metric"
    );
    assert!(html.contains("<h2>results</h2>"));
    assert!(html.contains("<th>ape_rmse.mean</th>"));
    for row in expected["results"].as_array().unwrap() {
        let mean = row["ape_rmse"]["mean"].as_f64().unwrap();
        assert!(
            html.contains(&format!("<td class=\"num\">{mean:.6}</td>")),
            "{mean}"
        );
    }
}
