//! `--html FILE`: one self-contained result page of `ape`, `rpe`, `drift` or `bench`: the
//! session report's look (the server's `site.css`), the result's tables, every figure the
//! command draws (inline SVG images) and the JSON document that `--format json` prints.
//! It asks for nothing when opened: the style is inline, the figures are `data:` images
//! and the page's Content-Security-Policy forbids every request.
//!
//! The tables are read off the JSON document, so every command's page shows what its JSON
//! holds: top-level values and small objects (`pairing`, `statistics`) as a summary, each
//! array of records (`by_length`, `trials`, `results`, …) as a table, `across_trials` as
//! the runs' summary. Per-pose arrays (`errors`, `segments`) stay in the JSON only.

use std::path::Path;

use anyhow::{Context, Result};
use base64::Engine;
use serde::Serialize;
use serde_json::{Map, Value};

use crate::figures::canvas::{self, Format, Page};
use crate::figures::figure::PAGE;

/// The report's style sheet, one source for the server's pages and these.
const CSS: &str = include_str!("../../../server/assets/site.css");

/// An array with more records than this is left to the JSON (per-pose or per-segment rows).
const MAX_TABLE_ROWS: usize = 200;

/// Keys whose arrays are per-pose or per-segment data, never a table.
const DATA_ARRAYS: [&str; 3] = ["errors", "segments", "distances"];

/// The page: nothing may be fetched, scripts may not run; inline style and `data:` images
/// are all it has.
const CSP: &str = "default-src 'none'; style-src 'unsafe-inline'; img-src data:; \
     base-uri 'none'; form-action 'none'";

const TEMPLATE: &str = r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta http-equiv="Content-Security-Policy" content="{{ csp|safe }}">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{{ title }}</title>
<style>{{ css|safe }}
td.num{text-align:right;font-variant-numeric:tabular-nums}
pre.json{max-height:30em;overflow:auto;background:#f4f5f7;padding:.6em;font-size:.85em}
figure{display:inline-block;margin:.4em .6em .4em 0}figure img{border:1px solid #ddd;max-width:100%;height:auto}
figcaption{color:#555;font-size:.9em}</style>
</head>
<body class="report">
<h1>{{ title }}</h1>
<p class="note">{{ command }} · sitar {{ version }}</p>
{% for table in tables %}
<h2>{{ table.heading }}</h2>
<table>
<thead><tr>{% for h in table.header %}<th>{{ h }}</th>{% endfor %}</tr></thead>
<tbody>{% for row in table.rows %}<tr>{% for cell in row %}<td{% if cell.num %} class="num"{% endif %}>{{ cell.text }}</td>{% endfor %}</tr>
{% endfor %}</tbody>
</table>
{% endfor %}
{% if figures %}<h2>Figures</h2>
{% for f in figures %}<figure><img src="{{ f.src|safe }}" alt="{{ f.caption }}" width="{{ width }}"><figcaption>{{ f.caption }}</figcaption></figure>
{% endfor %}{% endif %}
<h2>JSON</h2>
<details><summary>The document <code>--format json</code> prints</summary>
<pre class="json">{{ json }}</pre>
</details>
</body>
</html>
"#;

#[derive(Serialize)]
struct Cell {
    text: String,
    num: bool,
}

#[derive(Serialize)]
struct Table {
    heading: String,
    header: Vec<String>,
    rows: Vec<Vec<Cell>>,
}

#[derive(Serialize)]
struct Figure {
    caption: String,
    src: String,
}

/// Writes the page of `document` with `figures` (caption, page) to `path`.
pub fn write(path: &Path, document: &Value, figures: &[(&str, Page<'_>)]) -> Result<()> {
    let html = page(document, figures, path)?;
    std::fs::write(path, html).with_context(|| format!("{}: cannot write the page", path.display()))
}

/// The page's HTML (`path` only names the file in drawing errors).
pub fn page(document: &Value, figures: &[(&str, Page<'_>)], path: &Path) -> Result<String> {
    let figures = figures
        .iter()
        .map(|(caption, page)| {
            let svg = canvas::render(path, Format::Svg, PAGE, &[page])?;
            let src = format!(
                "data:image/svg+xml;base64,{}",
                base64::engine::general_purpose::STANDARD.encode(svg)
            );
            Ok(Figure {
                caption: caption.replace('_', " "),
                src,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let title = document
        .get("title")
        .and_then(Value::as_str)
        .map(|t| t.lines().next().unwrap_or(t).to_owned())
        .unwrap_or_else(|| match document.get("metric").and_then(Value::as_str) {
            Some(metric) => format!("sitar {metric}"),
            None => "sitar result".into(),
        });
    let command = std::iter::once("sitar".to_owned())
        .chain(std::env::args().skip(1).map(|a| quoted(&a)))
        .collect::<Vec<_>>()
        .join(" ");
    let context = serde_json::json!({
        "csp": CSP,
        "css": CSS,
        "title": title,
        "command": command,
        "version": env!("CARGO_PKG_VERSION"),
        "tables": tables(document),
        "figures": figures,
        "width": PAGE.0,
        "json": serde_json::to_string_pretty(document)?,
    });
    let mut env = minijinja::Environment::new();
    env.add_template("result.html", TEMPLATE)?;
    Ok(env.get_template("result.html")?.render(context)?)
}

/// A shell word as typed (quoted when it has spaces or quotes).
fn quoted(word: &str) -> String {
    if word.is_empty() || word.contains([' ', '\'', '"', '\t']) {
        format!("'{}'", word.replace('\'', "'\\''"))
    } else {
        word.to_owned()
    }
}

/// The tables of a document, in the order of its keys (sorted).
fn tables(document: &Value) -> Vec<Table> {
    let Some(object) = document.as_object() else {
        return Vec::new();
    };
    let mut summary = Vec::new();
    let mut out = Vec::new();
    for (key, value) in object {
        match value {
            Value::Array(items) if DATA_ARRAYS.contains(&key.as_str()) => {
                summary.push(row(&[
                    format!("{key} (in the JSON)"),
                    format!("{} rows", items.len()),
                ]));
            }
            Value::Array(items) if !items.is_empty() && items.iter().all(Value::is_object) => {
                if items.len() > MAX_TABLE_ROWS {
                    summary.push(row(&[
                        format!("{key} (in the JSON)"),
                        format!("{} rows", items.len()),
                    ]));
                } else {
                    out.push(records(key, items));
                }
            }
            Value::Object(inner) if key == "across_trials" => out.push(across(inner)),
            Value::Object(inner) => {
                for (k, v) in flatten(inner, key) {
                    summary.push(vec![text(&k), value_cell(&v)]);
                }
            }
            Value::Array(_) => summary.push(vec![text(key), value_cell(value)]),
            _ if key == "title" || key == "version" => {}
            _ => summary.push(vec![text(key), value_cell(value)]),
        }
    }
    if !summary.is_empty() {
        out.insert(
            0,
            Table {
                heading: "Summary".into(),
                header: vec!["".into(), "".into()],
                rows: summary,
            },
        );
    }
    out
}

/// One table of an array of records: a column per plain value, then per value of a nested
/// object (`ape_rmse.mean`); nested arrays are left to the JSON.
fn records(key: &str, items: &[Value]) -> Table {
    let flat: Vec<Vec<(String, Value)>> = items
        .iter()
        .map(|item| {
            // Plain values (names, counts) first, then the objects' (`ape_rmse.mean`).
            let (mut fields, mut nested) = (Vec::new(), Vec::new());
            if let Some(object) = item.as_object() {
                for (k, v) in object {
                    match v {
                        Value::Object(inner) => nested.extend(flatten(inner, k)),
                        Value::Array(_) => {}
                        _ => fields.push((k.clone(), v.clone())),
                    }
                }
            }
            fields.append(&mut nested);
            fields
        })
        .collect();
    let mut header: Vec<String> = Vec::new();
    for fields in &flat {
        for (k, _) in fields {
            if !header.contains(k) {
                header.push(k.clone());
            }
        }
    }
    let rows = flat
        .iter()
        .map(|fields| {
            header
                .iter()
                .map(|h| {
                    fields
                        .iter()
                        .find(|(k, _)| k == h)
                        .map_or_else(|| text(""), |(_, v)| value_cell(v))
                })
                .collect()
        })
        .collect();
    Table {
        heading: key.replace('_', " "),
        header,
        rows,
    }
}

/// `across_trials`: a row per statistic, a column per summary over the runs.
fn across(object: &Map<String, Value>) -> Table {
    const SUMMARIES: [&str; 5] = ["mean", "median", "min", "max", "std"];
    let rows = object
        .iter()
        .map(|(name, summary)| {
            std::iter::once(text(name))
                .chain(
                    SUMMARIES
                        .iter()
                        .map(|s| summary.get(*s).map_or_else(|| text(""), value_cell)),
                )
                .collect()
        })
        .collect();
    Table {
        heading: "across runs".into(),
        header: std::iter::once("statistic")
            .chain(SUMMARIES)
            .map(str::to_owned)
            .collect(),
        rows,
    }
}

/// An object's scalar values under dotted keys (`pairing.paired`), nested objects too.
fn flatten(object: &Map<String, Value>, prefix: &str) -> Vec<(String, Value)> {
    let mut out = Vec::new();
    for (k, v) in object {
        let key = format!("{prefix}.{k}");
        match v {
            Value::Object(inner) => out.extend(flatten(inner, &key)),
            Value::Array(items) if items.len() > 16 => {}
            _ => out.push((key, v.clone())),
        }
    }
    out
}

fn row(cells: &[String]) -> Vec<Cell> {
    cells.iter().map(|c| text(c)).collect()
}

fn text(s: &str) -> Cell {
    Cell {
        text: s.to_owned(),
        num: false,
    }
}

/// Numbers with six significant digits after the point (as evo's tables), `null` as "—".
fn value_cell(value: &Value) -> Cell {
    match value {
        Value::Number(n) if n.is_f64() => Cell {
            text: format!("{:.6}", n.as_f64().unwrap_or(f64::NAN)),
            num: true,
        },
        Value::Number(n) => Cell {
            text: n.to_string(),
            num: true,
        },
        Value::Null => text("—"),
        Value::String(s) => text(s),
        other => text(&other.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_become_a_table_with_flattened_columns() {
        let doc = serde_json::json!({
            "title": "APE w.r.t. translation part (m)",
            "unit": "m",
            "pairing": {"paired": 10, "dropped": 2},
            "errors": [{"t": 1, "error": 0.5}],
            "results": [
                {"algorithm": "a", "sequence": "s", "trials": 3,
                 "ape_rmse": {"mean": 0.25, "std": 0.125}},
                {"algorithm": "b", "sequence": "s", "trials": 3,
                 "ape_rmse": {"mean": 0.5, "std": 0.0}}
            ],
            "across_trials": {"rmse": {"mean": 1.0, "median": 1.0, "min": 0.5, "max": 1.5, "std": 0.5}}
        });
        let tables = tables(&doc);
        let names: Vec<&str> = tables.iter().map(|t| t.heading.as_str()).collect();
        // serde_json's maps keep keys sorted: the tables follow.
        assert_eq!(names, ["Summary", "across runs", "results"]);
        let summary: Vec<&str> = tables[0].rows.iter().map(|r| r[0].text.as_str()).collect();
        assert_eq!(
            summary,
            [
                "errors (in the JSON)",
                "pairing.dropped",
                "pairing.paired",
                "unit"
            ]
        );
        assert_eq!(
            tables[2].header,
            [
                "algorithm",
                "sequence",
                "trials",
                "ape_rmse.mean",
                "ape_rmse.std"
            ]
        );
        assert_eq!(tables[2].rows[1][3].text, "0.500000");
        assert!(tables[2].rows[1][3].num);
        assert_eq!(tables[1].rows[0][4].text, "1.500000");
    }

    #[test]
    fn the_page_asks_for_nothing_and_escapes_what_it_shows() {
        let doc = serde_json::json!({"title": "<script>x</script>", "estimate": "a&b.txt"});
        let html = page(&doc, &[], Path::new("x.html")).unwrap();
        assert!(
            html.contains("&lt;script&gt;x&lt;&#x2f;script&gt;"),
            "{html}"
        );
        assert!(!html.contains("<script>"));
        assert!(html.contains("default-src 'none'"));
        for fetch in ["src=\"http", "href=", "url(", "@import"] {
            assert!(!html.contains(fetch), "the page fetches something: {fetch}");
        }
    }
}
