//! The report of a session (`GET /v1/sessions/{id}/report`): one self-contained HTML page,
//! the reference trial seen from above coloured by error, the worst windows and the
//! settings, every error in its unit (cm for `trans_part`, degrees for `angle_deg`).

use std::fmt::Write;

use serde::Deserialize;
use sitar_core::{ErrorClass, Thresholds};

use crate::Error;
use crate::config::ServerConfig;
use crate::session::Session;

#[derive(Debug, Deserialize)]
struct ResultsDoc {
    #[serde(default)]
    setting: String,
    #[serde(default)]
    trials: u32,
    windows: Vec<WindowDoc>,
}

#[derive(Debug, Deserialize)]
struct WindowDoc {
    start: i64,
    #[serde(default)]
    end: Option<i64>,
    /// `error_m` of `trans_part` results, `error_deg` of `angle_deg` ones.
    #[serde(rename = "error_m", alias = "error_deg")]
    error: f64,
    #[serde(default)]
    pairs: Option<u32>,
}

const LOW: &str = "#2f6fde";
const MEDIUM: &str = "#e0b100";
const HIGH: &str = "#d62728";
const UNKNOWN: &str = "#9a9a9a";

pub(crate) fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// How the report writes errors of one unit.
struct Unit {
    /// Column header, e.g. `error (cm)`.
    header: &'static str,
    /// The factor from the results' unit to the shown one.
    scale: f64,
    /// After a number, e.g. ` cm`.
    suffix: &'static str,
}

impl Unit {
    fn of(session: &Session) -> Unit {
        match session.settings.unit() {
            "deg" => Unit {
                header: "error (°)",
                scale: 1.0,
                suffix: "°",
            },
            _ => Unit {
                header: "error (cm)",
                scale: 100.0,
                suffix: " cm",
            },
        }
    }

    fn show(&self, value: f64, decimals: usize) -> String {
        format!("{:.*}{}", decimals, value * self.scale, self.suffix)
    }
}

fn class_of(error: f64, thresholds: Thresholds) -> (&'static str, &'static str) {
    let class = thresholds.classify(error);
    let colour = match class {
        ErrorClass::High => HIGH,
        ErrorClass::Medium => MEDIUM,
        ErrorClass::Low => LOW,
        ErrorClass::Unknown => UNKNOWN,
    };
    (class.name(), colour)
}

/// The report: a top view (x right, z up) of the reference trial coloured by
/// the error of the window starting at each pose, the worst windows and the settings.
pub(crate) fn render(
    row: &Session,
    reference_tum: &str,
    results_json: &str,
    config: &ServerConfig,
) -> Result<String, Error> {
    let thresholds = row.settings.thresholds(config);
    let unit = Unit::of(row);
    let doc: ResultsDoc = serde_json::from_str(results_json)
        .map_err(|e| Error::Internal(format!("results.json of {} is unreadable: {e}", row.id)))?;
    let mut windows = doc.windows;
    windows.sort_by_key(|w| w.start);
    let trajectory = sitar_estimator::parse_tum(reference_tum, "trial_000.txt").ok();
    let t0 = trajectory
        .as_ref()
        .and_then(|t| t.stamps.first().copied())
        .or(windows.first().map(|w| w.start))
        .unwrap_or(0);
    let seconds = |t: i64| (t - t0) as f64 * 1e-9;

    let mut svg = String::new();
    match trajectory.as_ref().filter(|t| t.len() >= 2) {
        Some(t) => {
            let (mut min_x, mut max_x, mut min_z, mut max_z) =
                (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
            for p in &t.positions {
                min_x = min_x.min(p.x);
                max_x = max_x.max(p.x);
                min_z = min_z.min(p.z);
                max_z = max_z.max(p.z);
            }
            let span = (max_x - min_x).max(max_z - min_z).max(0.1);
            let margin = span * 0.05;
            let stroke = span / 150.0;
            let _ = write!(
                svg,
                r#"<svg id="topview" xmlns="http://www.w3.org/2000/svg" width="640" height="640" viewBox="{:.4} {:.4} {:.4} {:.4}" style="background:#fafafa;border:1px solid #ccc">"#,
                min_x - margin,
                -max_z - margin,
                span + 2.0 * margin,
                span + 2.0 * margin
            );
            // Each segment i→i+1 takes the window starting at (or last before) pose i.
            let mut w = 0;
            for i in 0..t.len() - 1 {
                while w + 1 < windows.len() && windows[w + 1].start <= t.stamps[i] {
                    w += 1;
                }
                let (class, colour) = match windows.get(w) {
                    Some(win) if win.start <= t.stamps[i] => class_of(win.error, thresholds),
                    _ => ("unknown", UNKNOWN),
                };
                let (a, b) = (t.positions[i], t.positions[i + 1]);
                let _ = write!(
                    svg,
                    r#"<line class="seg {class}" x1="{:.4}" y1="{:.4}" x2="{:.4}" y2="{:.4}" stroke="{colour}" stroke-width="{stroke:.4}" stroke-linecap="round"/>"#,
                    a.x, -a.z, b.x, -b.z
                );
            }
            let (s, e) = (t.positions[0], t.positions[t.len() - 1]);
            let _ = write!(
                svg,
                r#"<circle id="start" cx="{:.4}" cy="{:.4}" r="{:.4}" fill="green"><title>start</title></circle><circle id="stop" cx="{:.4}" cy="{:.4}" r="{:.4}" fill="black"><title>stop</title></circle></svg>"#,
                s.x,
                -s.z,
                stroke * 3.0,
                e.x,
                -e.z,
                stroke * 3.0
            );
        }
        None => svg.push_str(r#"<p id="no-trajectory">The reference trial is not available.</p>"#),
    }

    let mut worst: Vec<&WindowDoc> = windows.iter().collect();
    worst.sort_by(|a, b| b.error.total_cmp(&a.error));
    let mut rows = String::new();
    for (rank, w) in worst.iter().take(10).enumerate() {
        let (class, colour) = class_of(w.error, thresholds);
        let _ = write!(
            rows,
            r#"<tr class="{class}"><td>{}</td><td>{:.3}</td><td>{}</td><td style="color:{colour}">{:.2}</td><td>{class}</td><td>{}</td></tr>"#,
            rank + 1,
            seconds(w.start),
            w.end
                .map(|e| format!("{:.3}", seconds(e)))
                .unwrap_or_default(),
            w.error * unit.scale,
            w.pairs.map(|p| p.to_string()).unwrap_or_default()
        );
    }
    let counts = windows.iter().fold([0usize; 3], |mut c, w| {
        match class_of(w.error, thresholds).0 {
            "high" => c[2] += 1,
            "medium" => c[1] += 1,
            _ => c[0] += 1,
        }
        c
    });

    let settings = [
        ("Session", row.id.clone()),
        ("State", row.state.as_str().to_string()),
        (
            "Statistic",
            if doc.setting.is_empty() {
                row.settings.setting.to_string()
            } else {
                doc.setting.clone()
            },
        ),
        ("Windows", format!("{} frames", row.settings.window_frames)),
        (
            "Pose relation",
            format!("{} ({})", row.settings.pose_relation, row.settings.unit()),
        ),
        ("Trials in this estimate", doc.trials.to_string()),
        ("Trials planned", row.trials_total.to_string()),
        ("Playback", row.playback.as_str().to_string()),
        (
            "Thresholds",
            format!(
                "medium ≥ {}, high ≥ {}",
                unit.show(thresholds.medium, 1),
                unit.show(thresholds.high, 1)
            ),
        ),
        (
            "Adaptive stopping",
            row.adaptive_min
                .map(|m| format!("after ≥ {m} trials, k = {}", row.adaptive_k))
                .unwrap_or_else(|| "off".into()),
        ),
        (
            "Stop reason",
            row.stop_reason
                .clone()
                .unwrap_or_else(|| "all trials played".into()),
        ),
    ];
    let mut settings_rows = String::new();
    for (k, v) in settings {
        let _ = write!(
            settings_rows,
            "<tr><th>{}</th><td>{}</td></tr>",
            escape(k),
            escape(&v)
        );
    }

    Ok(format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>SiTAR report {id}</title>
<style>body{{font-family:sans-serif;margin:2em;color:#222}} table{{border-collapse:collapse}} td,th{{border:1px solid #ddd;padding:3px 8px;text-align:left}} .legend span{{display:inline-block;width:1em;height:1em;margin:0 .3em 0 1em;vertical-align:middle}}</style>
</head><body>
<h1>SiTAR report</h1>
<p id="summary">{n} windows: <b id="count-high">{high}</b> high, <b id="count-medium">{medium}</b> medium, <b id="count-low">{low}</b> low.</p>
<h2>Trajectory (top view, coloured by estimated error)</h2>
<p class="legend"><span style="background:{LOW}"></span>low<span style="background:{MEDIUM}"></span>medium<span style="background:{HIGH}"></span>high<span style="background:{UNKNOWN}"></span>no estimate</p>
{svg}
<h2>Worst windows</h2>
<table id="worst"><thead><tr><th>#</th><th>start (s)</th><th>end (s)</th><th>{error_header}</th><th>class</th><th>pairs</th></tr></thead><tbody>{rows}</tbody></table>
<h2>Settings</h2>
<table id="settings">{settings_rows}</table>
</body></html>
"#,
        id = escape(&row.id),
        error_header = unit.header,
        n = windows.len(),
        high = counts[2],
        medium = counts[1],
        low = counts[0],
    ))
}
