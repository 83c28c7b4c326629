//! `sitar bench`'s output: the cells' summaries over runs as Markdown, LaTeX, CSV or JSON.
//!
//! Per cell: the APE RMSE over runs (mean, median, min, max, std), the relative errors pooled
//! over runs per length and over every length (rpg's `MulTrajError`), the drift over runs.

use serde_json::{Value, json};
use sitar_estimator::{RelativeSample, Statistics};

use crate::beyond_evo::bench_results::{Bench, CellResult, Lengths};
use crate::io::output::json_number;

/// `sitar bench --format`.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum TableFormat {
    Markdown,
    Latex,
    Csv,
    Json,
}

/// The relative error metrics, as the JSON names them.
const METRICS: [&str; 6] = [
    "trans_m",
    "trans_percent",
    "rot_deg",
    "rot_deg_per_m",
    "yaw_deg",
    "roll_pitch_deg",
];

fn metric(s: &RelativeSample, name: &str) -> f64 {
    match name {
        "trans_m" => s.trans_m,
        "trans_percent" => s.trans_percent,
        "rot_deg" => s.rot_deg,
        "rot_deg_per_m" => s.rot_deg_per_m,
        "yaw_deg" => s.yaw_deg,
        _ => s.roll_pitch_deg,
    }
}

/// Statistics of `values`; `None` when there are none.
fn stats(values: &[f64]) -> Option<Statistics> {
    (!values.is_empty()).then(|| Statistics::from_errors(values))
}

fn stats_json(s: Option<Statistics>) -> Value {
    s.map_or(Value::Null, |s| {
        json!({
            "mean": json_number(s.mean),
            "median": json_number(s.median),
            "min": json_number(s.min),
            "max": json_number(s.max),
            "std": json_number(s.std),
            "rmse": json_number(s.rmse),
        })
    })
}

impl CellResult {
    fn ape(&self) -> Option<Statistics> {
        stats(&self.runs.iter().map(|r| r.ape_rmse).collect::<Vec<_>>())
    }

    /// Every run's samples at length `k` (every length: `None`) for `name`.
    fn pooled(&self, k: Option<usize>, name: &str) -> Vec<f64> {
        self.runs
            .iter()
            .flat_map(|r| {
                r.relative
                    .iter()
                    .enumerate()
                    .filter(move |(i, _)| k.is_none_or(|k| k == *i))
                    .flat_map(|(_, at)| at.samples.iter().map(|s| metric(s, name)))
            })
            .collect()
    }

    fn drift(&self, rotation: bool) -> Option<Statistics> {
        let values: Vec<f64> = self
            .runs
            .iter()
            .filter_map(|r| r.drift.map(|(t, r)| if rotation { r } else { t }))
            .collect();
        stats(&values)
    }
}

/// The column label of length `k`: its percentage or metres.
fn length_label(lengths: &Lengths, k: usize) -> String {
    match lengths {
        Lengths::Percent(p) => format!("{} %", p[k]),
        Lengths::Metres(m) => format!("{} m", m[k]),
    }
}

pub fn document(bench: &Bench) -> Value {
    let results: Vec<Value> = bench
        .cells
        .iter()
        .map(|c| {
            let relative: Vec<Value> = c
                .lengths_m
                .iter()
                .enumerate()
                .map(|(k, length)| {
                    let mut entry = json!({
                        "length_m": length,
                        "samples": c.pooled(Some(k), "trans_m").len(),
                    });
                    for name in METRICS {
                        entry[name] = stats_json(stats(&c.pooled(Some(k), name)));
                    }
                    entry
                })
                .collect();
            let mut all = json!({});
            for name in METRICS {
                all[name] = stats_json(stats(&c.pooled(None, name)));
            }
            json!({
                "algorithm": c.cell.algorithm,
                "sequence": c.cell.sequence,
                "trials": c.runs.len(),
                "align_type": c.cell.alignment.align_type.name(),
                "align_num_frames": c.cell.alignment.num_frames,
                "ground_truth": c.cell.ground_truth.display().to_string(),
                "lengths_m": c.lengths_m,
                "ape_rmse": stats_json(c.ape()),
                "relative": relative,
                "relative_all": all,
                "drift": {
                    "t_err_percent": stats_json(c.drift(false)),
                    "r_err_deg_per_m": stats_json(c.drift(true)),
                },
                "runs": c.runs.iter().map(|r| json!({
                    "estimate": r.file.display().to_string(),
                    "pairs": r.pairs,
                    "scale": json_number(r.scale),
                    "ape_rmse": json_number(r.ape_rmse),
                    "drift_t_err_percent": r.drift.map(|d| d.0),
                    "drift_r_err_deg_per_m": r.drift.map(|d| d.1),
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    let (kind, values) = match &bench.lengths {
        Lengths::Percent(p) => ("percent", p),
        Lengths::Metres(m) => ("metres", m),
    };
    json!({
        "version": 1,
        "metric": "bench",
        "lengths": {"unit": kind, "values": values},
        "results": results,
    })
}

/// `mean ± std` with `digits` decimals; `–` for nothing.
fn pm(s: Option<Statistics>, digits: usize, plus_minus: &str) -> String {
    s.map_or("–".into(), |s| {
        format!("{:.digits$}{plus_minus}{:.digits$}", s.mean, s.std)
    })
}

fn mean(s: Option<Statistics>, digits: usize) -> String {
    s.map_or("–".into(), |s| format!("{:.digits$}", s.mean))
}

/// The human table: header and rows of cells.
fn rows(bench: &Bench, plus_minus: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let n = match &bench.lengths {
        Lengths::Percent(p) => p.len(),
        Lengths::Metres(m) => m.len(),
    };
    let mut header: Vec<String> = ["algorithm", "sequence", "runs", "APE RMSE (m)"]
        .map(String::from)
        .to_vec();
    header.extend((0..n).map(|k| format!("rel. trans. {} (%)", length_label(&bench.lengths, k))));
    header.extend(
        [
            "rel. rot. (deg/m)",
            "rel. yaw (deg)",
            "drift (%)",
            "drift (deg/m)",
        ]
        .map(String::from),
    );
    let body = bench
        .cells
        .iter()
        .map(|c| {
            let mut row = vec![
                c.cell.algorithm.clone(),
                c.cell.sequence.clone(),
                c.runs.len().to_string(),
                pm(c.ape(), 3, plus_minus),
            ];
            row.extend((0..n).map(|k| mean(stats(&c.pooled(Some(k), "trans_percent")), 2)));
            row.push(mean(stats(&c.pooled(None, "rot_deg_per_m")), 4));
            row.push(mean(stats(&c.pooled(None, "yaw_deg")), 3));
            row.push(pm(c.drift(false), 2, plus_minus));
            row.push(pm(c.drift(true), 4, plus_minus));
            row
        })
        .collect();
    (header, body)
}

fn markdown(bench: &Bench) -> String {
    let (header, body) = rows(bench, " ± ");
    let mut text = format!("| {} |\n", header.join(" | "));
    text += &format!("|{}\n", "---|".repeat(header.len()));
    for row in body {
        text += &format!("| {} |\n", row.join(" | "));
    }
    text
}

fn latex_escape(s: &str) -> String {
    s.chars()
        .flat_map(|c| match c {
            '_' | '%' | '&' | '#' | '$' | '{' | '}' => vec!['\\', c],
            c => vec![c],
        })
        .collect()
}

fn latex(bench: &Bench) -> String {
    let (header, body) = rows(bench, " $\\pm$ ");
    let mut text = format!(
        "\\begin{{tabular}}{{ll{}}}\n\\hline\n",
        "r".repeat(header.len() - 2)
    );
    let header: Vec<String> = header.iter().map(|h| latex_escape(h)).collect();
    text += &format!("{} \\\\\n\\hline\n", header.join(" & "));
    for row in body {
        let cells: Vec<String> = row
            .iter()
            .enumerate()
            .map(|(i, c)| if i < 2 { latex_escape(c) } else { c.clone() })
            .collect();
        text += &format!("{} \\\\\n", cells.join(" & "));
    }
    text + "\\hline\n\\end{tabular}\n"
}

fn csv(bench: &Bench) -> String {
    let n = match &bench.lengths {
        Lengths::Percent(p) => p.len(),
        Lengths::Metres(m) => m.len(),
    };
    let label = |k: usize| {
        length_label(&bench.lengths, k)
            .replace(" %", "pct")
            .replace(' ', "")
    };
    let mut header: Vec<String> = [
        "algorithm",
        "sequence",
        "trials",
        "align_type",
        "align_num_frames",
    ]
    .map(String::from)
    .to_vec();
    header.extend(["mean", "median", "min", "max", "std"].map(|s| format!("ape_rmse_{s}")));
    for k in 0..n {
        header.push(format!("length_m_{}", label(k)));
        header.push(format!("rel_trans_percent_mean_{}", label(k)));
        header.push(format!("rel_rot_deg_per_m_mean_{}", label(k)));
    }
    header.extend(
        [
            "rel_trans_percent_mean",
            "rel_rot_deg_per_m_mean",
            "rel_yaw_deg_mean",
            "rel_roll_pitch_deg_mean",
            "drift_t_err_percent_mean",
            "drift_t_err_percent_std",
            "drift_r_err_deg_per_m_mean",
            "drift_r_err_deg_per_m_std",
        ]
        .map(String::from),
    );
    let num = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
    let field = |s: &str| {
        if s.contains([',', '"', '\n']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_owned()
        }
    };
    let mut text = header.join(",") + "\n";
    for c in &bench.cells {
        let ape = c.ape();
        let mut row = vec![
            field(&c.cell.algorithm),
            field(&c.cell.sequence),
            c.runs.len().to_string(),
            c.cell.alignment.align_type.name().to_owned(),
            c.cell.alignment.num_frames.to_string(),
        ];
        row.extend(
            [
                ape.map(|s| s.mean),
                ape.map(|s| s.median),
                ape.map(|s| s.min),
                ape.map(|s| s.max),
                ape.map(|s| s.std),
            ]
            .map(num),
        );
        for k in 0..n {
            row.push(c.lengths_m[k].to_string());
            row.push(num(
                stats(&c.pooled(Some(k), "trans_percent")).map(|s| s.mean)
            ));
            row.push(num(
                stats(&c.pooled(Some(k), "rot_deg_per_m")).map(|s| s.mean)
            ));
        }
        for name in [
            "trans_percent",
            "rot_deg_per_m",
            "yaw_deg",
            "roll_pitch_deg",
        ] {
            row.push(num(stats(&c.pooled(None, name)).map(|s| s.mean)));
        }
        for rotation in [false, true] {
            let d = c.drift(rotation);
            row.push(num(d.map(|s| s.mean)));
            row.push(num(d.map(|s| s.std)));
        }
        text += &(row.join(",") + "\n");
    }
    text
}

/// The output of `sitar bench` in `format`.
pub fn render(bench: &Bench, format: TableFormat) -> String {
    match format {
        TableFormat::Markdown => markdown(bench),
        TableFormat::Latex => latex(bench),
        TableFormat::Csv => csv(bench),
        TableFormat::Json => document(bench).to_string() + "\n",
    }
}
