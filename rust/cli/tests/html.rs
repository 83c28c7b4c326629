//! `--html FILE` of `sitar ape`, `rpe`, `drift`, `relative` and `bench`: one page that holds the
//! tables, every figure inline and the very JSON document `--format json` prints, and asks for
//! nothing when opened.

mod support;

use std::collections::HashMap;
use std::ops::RangeInclusive;
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

/// Asserts page `name` is self-contained and returns its figures' count.
fn self_contained(name: &str, html: &str) -> usize {
    assert!(html.starts_with("<!DOCTYPE html>"), "{name}");
    assert!(html.contains("Content-Security-Policy"), "{name}");
    assert!(html.contains("default-src 'none'"), "{name}");
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
            "{name}: the page would fetch something: {fetch}"
        );
    }
    html.matches("<img src=\"data:image/svg+xml;base64,")
        .count()
}

/// A plain tree in `dir/tree` for `sitar bench`: ALG/SEQ/runN.txt beside gt/SEQ.txt.
fn bench_tree(dir: &Path) {
    let tree = dir.join("tree");
    for (alg, runs) in [
        ("vio", ["run0.txt", "run1.txt"]),
        ("slam", ["run1.txt", "run0.txt"]),
    ] {
        std::fs::create_dir_all(tree.join(alg).join("helix")).unwrap();
        for (k, run) in runs.iter().enumerate() {
            std::fs::copy(
                dir.join(run),
                tree.join(alg).join("helix").join(format!("run{k}.txt")),
            )
            .unwrap();
        }
    }
    std::fs::create_dir_all(tree.join("gt")).unwrap();
    std::fs::copy(dir.join("gt.txt"), tree.join("gt/helix.txt")).unwrap();
}

/// A page: `sitar ARGS --html NAME.html`, beside `sitar ARGS --format json`.
struct Page {
    name: &'static str,
    /// Its command line after `sitar`, split at spaces.
    args: &'static str,
    /// How many figures it inlines, and what they are.
    figures: RangeInclusive<usize>,
    of: &'static str,
    /// Text it holds: its title, headings and columns.
    holds: &'static [&'static str],
}

const PAGES: &[Page] = &[
    Page {
        name: "ape",
        args: "ape tum gt.txt run1.txt -a",
        figures: 2..=2,
        of: "raw and map figures",
        holds: &["<td>pairing.paired</td>"],
    },
    Page {
        name: "rpe",
        args: "rpe tum gt.txt run0.txt run1.txt -a --delta 1 --delta_unit m",
        figures: 1..=1,
        of: "the box plot over runs",
        holds: &["<h2>trials</h2>", "<h2>across runs</h2>"],
    },
    Page {
        name: "drift",
        args: "drift tum gt.txt run1.txt --lengths 2,4 --step 5",
        figures: 2..=2,
        of: "error against length and against speed",
        holds: &["<h2>by length</h2>"],
    },
    Page {
        name: "drift_runs",
        args: "drift tum gt.txt run0.txt run1.txt --lengths 2,4",
        figures: 4..=4,
        of: "two curves and two box plots",
        holds: &[],
    },
    Page {
        name: "relative",
        args: "relative tum gt.txt run0.txt run1.txt --lengths 2,4",
        figures: 2..=usize::MAX,
        of: "a box plot per error",
        holds: &[],
    },
    Page {
        name: "bench",
        args: "bench tree --lengths 2,4",
        figures: 3..=3,
        of: "APE RMSE, then the sequence's translation and yaw",
        holds: &[
            "<h1>sitar bench</h1>",
            "<h2>results</h2>",
            "<th>ape_rmse.mean</th>",
        ],
    },
];

/// Each page holds its tables, its figures inline and the very document `--format json`
/// prints; the numbers in its tables are the document's.
#[test]
fn pages_hold_their_tables_figures_and_json() {
    let dir = tempfile::tempdir().unwrap();
    files(dir.path());
    bench_tree(dir.path());
    let mut pages = HashMap::new();
    for page in PAGES {
        let name = page.name;
        let file = format!("{name}.html");
        let args: Vec<&str> = page.args.split(' ').collect();
        let json = ok_in(dir.path(), &[&args[..], &["--format", "json"]].concat());
        ok_in(dir.path(), &[&args[..], &["--html", &file]].concat());
        let html = std::fs::read_to_string(dir.path().join(&file)).unwrap();
        let figures = self_contained(name, &html);
        assert!(
            page.figures.contains(&figures),
            "{name}: {figures} figures, not {:?}: {}",
            page.figures,
            page.of
        );
        let expected: Value = serde_json::from_str(&json).unwrap();
        assert_eq!(page_document(&html), expected, "{name}: the page's JSON");
        for text in page.holds {
            assert!(html.contains(text), "{name}: no {text}");
        }
        pages.insert(name, (expected, html));
    }

    let (ape, html) = &pages["ape"];
    let rmse = ape["statistics"]["rmse"].as_f64().unwrap();
    assert!(
        html.contains(&format!("<td class=\"num\">{rmse:.6}</td>")),
        "ape: the RMSE is in a table"
    );
    let (bench, html) = &pages["bench"];
    for row in bench["results"].as_array().unwrap() {
        let mean = row["ape_rmse"]["mean"].as_f64().unwrap();
        assert!(
            html.contains(&format!("<td class=\"num\">{mean:.6}</td>")),
            "bench: {mean}"
        );
    }
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
