//! The report of a session (`GET /v1/sessions/{id}/report`): one HTML page from the
//! `templates/report.html` template (minijinja, HTML autoescape: every string from a client
//! is escaped unless the template says otherwise, and only the numeric SVG charts do).
//!
//! What it shows: counts in sub-trajectories and regions (the window count labelled as
//! such), the interactive 3-D view (`/assets/report.bundle.js`, three.js served by this backend,
//! data from `scene.json`), a static SVG top view, the problem regions, the charts, the
//! statistics and the downloads. Errors are in cm for `trans_part` and degrees for
//! `angle_deg`.

use std::fmt::Write;

use serde::Deserialize;
use serde_json::json;
use sitar_core::{Convention, ErrorClass, Session as Phone, Thresholds};

use crate::Error;
use crate::config::ServerConfig;
use crate::report::charts::{self, HIGH, LOW, MEDIUM, UNKNOWN};
use crate::report::index_ranges::index_ranges;
use crate::report::region_evidence::{self, CameraEvidence};
use crate::report::regions::{self, SubRow};
use crate::report::scene::Source;
use crate::report::templates;
use crate::session::Session;

#[derive(Debug, Deserialize)]
struct ResultsDoc {
    #[serde(default)]
    setting: String,
    #[serde(default)]
    trials: u32,
    windows: Vec<serde::de::IgnoredAny>,
}

/// How the report writes errors of one unit.
pub(crate) struct Unit {
    /// e.g. `cm`.
    pub name: &'static str,
    /// The factor from the results' unit to the shown one.
    pub scale: f64,
}

impl Unit {
    pub(crate) fn of(session: &Session) -> Unit {
        match session.settings.unit() {
            "deg" => Unit {
                name: "°",
                scale: 1.0,
            },
            _ => Unit {
                name: "cm",
                scale: 100.0,
            },
        }
    }

    /// `4.2 cm`, `3.1°`.
    fn show(&self, value: f64) -> String {
        let space = if self.name == "°" { "" } else { " " };
        format!("{:.1}{space}{}", value * self.scale, self.name)
    }
}

pub(crate) fn colour(class: ErrorClass) -> &'static str {
    match class {
        ErrorClass::High => HIGH,
        ErrorClass::Medium => MEDIUM,
        ErrorClass::Low => LOW,
        ErrorClass::Unknown => UNKNOWN,
    }
}

/// A point of the backend's phone session (always `arcore`, see `crate::report::scene`) in the 3-D
/// view's frame, glTF's: the same frame, so this only states the conversion.
fn view_point(p: glam::DVec3) -> glam::DVec3 {
    Convention::Arcore.convert_vector(p, Convention::Arcore)
}

/// Static top view (x right, z down the page, as the 3-D view's top view): the path coloured
/// by class, markers and start/stop. Numbers only.
fn top_view(phone: &Phone, subs: &[SubRow]) -> String {
    let joints = phone.render_plan().joints;
    if joints.len() < 2 {
        return String::new();
    }
    let pts: Vec<glam::DVec3> = joints.iter().map(|j| view_point(j.position)).collect();
    let (mut lo, mut hi) = (glam::DVec3::MAX, glam::DVec3::MIN);
    for p in &pts {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let span = (hi.x - lo.x).max(hi.z - lo.z).max(0.5);
    let margin = span * 0.06;
    let stroke = span / 160.0;
    let mut svg = format!(
        r##"<svg id="topview" xmlns="http://www.w3.org/2000/svg" width="520" height="520" viewBox="{:.3} {:.3} {:.3} {:.3}" role="img" aria-label="top view of the walk"><rect x="{:.3}" y="{:.3}" width="{:.3}" height="{:.3}" fill="#fafafa"/>"##,
        lo.x - margin,
        lo.z - margin,
        span + 2.0 * margin,
        span + 2.0 * margin,
        lo.x - margin,
        lo.z - margin,
        span + 2.0 * margin,
        span + 2.0 * margin,
    );
    // 1 m grid.
    let mut g = (lo.x - margin).ceil();
    while g <= lo.x + span + margin {
        let _ = write!(
            svg,
            r##"<line x1="{g}" y1="{:.3}" x2="{g}" y2="{:.3}" stroke="#ddd" stroke-width="{:.4}"/>"##,
            lo.z - margin,
            lo.z + span + margin,
            stroke / 3.0
        );
        g += 1.0;
    }
    let mut g = (lo.z - margin).ceil();
    while g <= lo.z + span + margin {
        let _ = write!(
            svg,
            r##"<line x1="{:.3}" y1="{g}" x2="{:.3}" y2="{g}" stroke="#ddd" stroke-width="{:.4}"/>"##,
            lo.x - margin,
            lo.x + span + margin,
            stroke / 3.0
        );
        g += 1.0;
    }
    // A long walk is thinned for display (the SVG stays small); a segment takes the class
    // of the joint it starts at.
    let kept = crate::report::thinning::thin(pts.len(), MAX_TOP_VIEW_POINTS);
    let _ = write!(
        svg,
        r#"<g stroke-width="{stroke:.4}" stroke-linecap="round">"#
    );
    for pair in kept.windows(2) {
        let (a, b) = (pts[pair[0]], pts[pair[1]]);
        let class = subs
            .get(joints[pair[0]].subtrajectory as usize)
            .map_or(ErrorClass::Unknown, |s| s.class);
        let _ = write!(
            svg,
            r#"<line class="seg {}" x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="{}"/>"#,
            class.name(),
            a.x,
            a.z,
            b.x,
            b.z,
            colour(class)
        );
    }
    svg.push_str("</g>");
    if let Ok(markers) = phone.markers() {
        for (i, m) in markers.iter().enumerate() {
            let p = view_point(m.position);
            let _ = write!(
                svg,
                r##"<circle class="marker" cx="{:.3}" cy="{:.3}" r="{:.3}" fill="{}" stroke="#000" stroke-width="{:.4}"><title>marker {}</title></circle>"##,
                p.x,
                p.z,
                stroke * 4.0,
                colour(m.class),
                stroke / 2.0,
                i + 1
            );
        }
    }
    let (s, e) = (pts[0], pts[pts.len() - 1]);
    let _ = write!(
        svg,
        r#"<circle id="start" cx="{:.3}" cy="{:.3}" r="{:.3}" fill="green"><title>start</title></circle><circle id="stop" cx="{:.3}" cy="{:.3}" r="{:.3}" fill="black"><title>stop</title></circle></svg>"#,
        s.x,
        s.z,
        stroke * 3.0,
        e.x,
        e.z,
        stroke * 3.0
    );
    svg
}

/// rmse, mean, median, max of `values` (none when empty).
fn statistics(values: &[f64]) -> Option<[f64; 4]> {
    if values.is_empty() {
        return None;
    }
    let n = values.len() as f64;
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    let median = if sorted.len().is_multiple_of(2) {
        (sorted[mid - 1] + sorted[mid]) / 2.0
    } else {
        sorted[mid]
    };
    Some([
        (values.iter().map(|v| v * v).sum::<f64>() / n).sqrt(),
        values.iter().sum::<f64>() / n,
        median,
        sorted[sorted.len() - 1],
    ])
}

/// Everything the page needs besides the session row.
pub(crate) struct ReportInput<'a> {
    pub row: &'a Session,
    pub results_json: &'a str,
    pub config: &'a ServerConfig,
    /// The phone session with the results loaded, and where it came from (none without
    /// any trajectory).
    pub phone: Option<(&'a Phone, Source)>,
    /// The published estimates in order (`published::history`).
    pub history: Vec<serde_json::Value>,
    /// Where this reader fetches the session's data: `/v1/sessions/ID/` for its owner,
    /// `/share/TOKEN/` through a share link (the page's scene.json, images and downloads).
    pub base: &'a str,
    /// The phone's camera evidence, when it sent any.
    pub evidence: Option<&'a CameraEvidence>,
}

/// Path points of the static top view (a 10-minute walk logs 3 600).
const MAX_TOP_VIEW_POINTS: usize = 1_500;

/// Regions and markers listed on the page (the counts above the tables are of all).
const MAX_TABLE_ROWS: usize = 100;

pub(crate) fn render(input: &ReportInput<'_>) -> Result<String, Error> {
    let row = input.row;
    let thresholds: Thresholds = row.settings.thresholds(input.config);
    let unit = Unit::of(row);
    let doc: ResultsDoc = serde_json::from_str(input.results_json)
        .map_err(|e| Error::Internal(format!("results.json of {} is unreadable: {e}", row.id)))?;
    let (subs, markers) = match input.phone {
        Some((phone, _)) => (
            regions::sub_rows(phone, thresholds),
            phone.markers().unwrap_or_default(),
        ),
        None => (Vec::new(), Vec::new()),
    };
    let radius = input.phone.map_or(0.5, |(p, _)| p.config().dedup_radius_m);
    let mut found = regions::regions(&subs, &markers, radius);
    if let Some(evidence) = input.evidence {
        let base = input.base;
        region_evidence::attach(&mut found, &subs, evidence, &|k| {
            format!("{base}subtrajectories/{k}/image.jpg")
        });
    }
    let errors: Vec<f64> = subs.iter().filter_map(|s| s.error).collect();
    let count = |c: ErrorClass| subs.iter().filter(|s| s.class == c).count();
    let stats = statistics(&errors);
    let marker_times: Vec<(usize, f64)> = markers
        .iter()
        .enumerate()
        .filter_map(|(i, m)| subs.get(m.subtrajectory as usize).map(|s| (i + 1, s.t0)))
        .collect();
    let y_label = format!("error ({})", unit.name);
    let timeline: Vec<(f64, f64, Option<f64>)> =
        subs.iter().map(|s| (s.t0, s.t1, s.error)).collect();
    let region_rows: Vec<serde_json::Value> = found
        .iter()
        .take(MAX_TABLE_ROWS)
        .map(|r| {
            let evidence = r.evidence.as_ref();
            json!({
                "rank": r.rank,
                "class": r.class.name(),
                "colour": colour(r.class),
                "max_error": unit.show(r.max_error),
                "mean_error": unit.show(r.mean_error),
                "span": format!("{:.1}–{:.1} s", r.t0, r.t1),
                "distance": format!("{:.2} m", r.distance_m),
                "subtrajectories": index_ranges(&r.subtrajectories),
                "sub_count": r.subtrajectories.len(),
                "stretches": r.stretches,
                "surface": r.surface.map(|p| {
                    let p = view_point(p);
                    format!("({:.2}, {:.2}, {:.2})", p.x, p.y, p.z)
                }),
                "markers": r.markers.iter().map(|m| format!("M{m}")).collect::<Vec<_>>().join(", "),
                "thumbnail_url": evidence.and_then(|e| e.thumbnail_url.as_deref()),
                "pictured": evidence.and_then(|e| e.pictured),
                "covered": evidence.map(|e| e.covered),
                "causes": evidence.map(|e| e.causes.iter().map(|c| json!({
                    "name": c.name, "reason": c.reason, "count": c.count,
                })).collect::<Vec<_>>()),
            })
        })
        .collect();
    let marker_rows: Vec<serde_json::Value> = markers
        .iter()
        .enumerate()
        .take(MAX_TABLE_ROWS)
        .map(|(i, m)| {
            let p = view_point(m.position);
            json!({
                "number": i + 1,
                "subtrajectory": m.subtrajectory,
                "class": m.class.name(),
                "colour": colour(m.class),
                "error": format!("{:.1}", m.error_m * unit.scale),
                "position": format!("({:.2}, {:.2}, {:.2})", p.x, p.y, p.z),
                "region": found.iter().find(|r| r.markers.contains(&(i + 1))).map(|r| r.rank),
            })
        })
        .collect();
    let trials = doc.trials;
    let settings = vec![
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
        ("Window", format!("{} frames", row.settings.window_frames)),
        (
            "Pose relation",
            format!("{} ({})", row.settings.pose_relation, row.settings.unit()),
        ),
        ("Trials planned", row.trials_total.to_string()),
        ("Playback", row.playback.as_str().to_string()),
        (
            "Thresholds",
            format!(
                "medium ≥ {}, high ≥ {}",
                unit.show(thresholds.medium),
                unit.show(thresholds.high)
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
    let context = json!({
        "id": row.id,
        "unit": unit.name,
        // Completed ones, as the phone counts them (a last one may have a midpoint only).
        "subtrajectories": input
            .phone
            .and_then(|(p, _)| p.summary())
            .map_or(subs.len(), |s| s.subtrajectories as usize),
        "estimated": errors.len(),
        "high": count(ErrorClass::High),
        "medium": count(ErrorClass::Medium),
        "low": count(ErrorClass::Low),
        "regions": region_rows,
        "region_count": found.len(),
        "markers": marker_rows,
        "marker_count": markers.len(),
        "has_evidence": input.evidence.is_some(),
        "base": input.base,
        "windows": doc.windows.len(),
        "window_frames": row.settings.window_frames,
        "trials": trials,
        "pairs": trials * trials.saturating_sub(1) / 2,
        "stats": stats.map(|s| s.map(|v| unit.show(v))),
        "source": input.phone.map(|(_, s)| s.describe()),
        "top_view": input.phone.map(|(p, _)| top_view(p, &subs)).unwrap_or_default(),
        "error_chart": if subs.is_empty() { String::new() } else {
            charts::error_over_time(&timeline, thresholds, &marker_times, unit.scale, &y_label)
        },
        "histogram": if errors.is_empty() { String::new() } else {
            charts::histogram(&errors, thresholds, unit.scale, &y_label)
        },
        "settings": settings,
        "history_chart": history_chart(&input.history, thresholds, &unit, &y_label),
        "history": input.history.iter().map(|h| json!({
            "trials": h["trials"],
            "mean": unit.show(h["mean"].as_f64().unwrap_or(0.0)),
            "max": unit.show(h["max"].as_f64().unwrap_or(0.0)),
            "high": h["high"], "medium": h["medium"], "low": h["low"],
        })).collect::<Vec<_>>(),
        "colours": {"low": LOW, "medium": MEDIUM, "high": HIGH, "unknown": UNKNOWN},
    });
    templates::render("report.html", &context)
}

/// The estimate as trials arrived, as a chart (none before two estimates).
fn history_chart(
    history: &[serde_json::Value],
    thresholds: Thresholds,
    unit: &Unit,
    y_label: &str,
) -> String {
    let points: Vec<(f64, f64, f64)> = history
        .iter()
        .filter_map(|h| {
            Some((
                h["trials"].as_f64()?,
                h["mean"].as_f64()?,
                h["max"].as_f64()?,
            ))
        })
        .collect();
    if points.len() < 2 {
        return String::new();
    }
    charts::history(&points, thresholds, unit.scale, y_label)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walk of `frames` poses round a 6 m circle at 30 fps, with results whose error rises
    /// and falls along it (so every class shows), loaded.
    fn long_walk(frames: usize) -> Phone {
        use sitar_core::{Pose, SessionConfig};
        let mut phone = Phone::try_new(
            SessionConfig::from_json(r#"{"convention":"arcore","images":false}"#).unwrap(),
        )
        .unwrap();
        let pose = |i: usize| {
            let a = i as f64 * 0.0005;
            let p = glam::DVec3::new(6.0 * a.cos(), 1.4, 6.0 * a.sin());
            (
                i as i64 * 33_333_333,
                Pose::new(p, glam::DQuat::from_rotation_y(-a)),
            )
        };
        let (t, p) = pose(0);
        phone.start(t, p).unwrap();
        for i in 1..frames - 1 {
            let (t, p) = pose(i);
            phone.frame(t, p).unwrap();
        }
        let (t, p) = pose(frames - 1);
        phone.stop(t, p).unwrap();
        let windows: Vec<serde_json::Value> = phone
            .subtrajectories()
            .iter()
            .map(|s| {
                let e = 0.06 + 0.06 * (f64::from(s.index) * 0.01).sin();
                json!({"start": s.start_ns, "error_m": e})
            })
            .collect();
        let results = json!({"version": 1, "setting": "median", "trials": 3,
            "pose_relation": "trans_part", "window_frames": 10, "unit": "m", "windows": windows});
        phone.load_results(&results.to_string()).unwrap();
        phone
    }

    /// Issue 11's huge trial: 390 000 poses give a top view, a chart and a scene.json of
    /// bounded size, thinned for display, while the statistics use every sub-trajectory.
    #[test]
    fn a_390000_pose_walk_gives_a_bounded_page_and_scene() {
        let phone = long_walk(390_000);
        let thresholds = Thresholds {
            medium: 0.05,
            high: 0.10,
        };
        let subs = regions::sub_rows(&phone, thresholds);
        assert_eq!(subs.len(), 39_000);
        let svg = top_view(&phone, &subs);
        assert_eq!(
            svg.matches("<line class=\"seg ").count(),
            MAX_TOP_VIEW_POINTS - 1
        );
        for class in ["low", "medium", "high"] {
            assert!(svg.contains(&format!("seg {class}")), "no {class} segment");
        }
        let timeline: Vec<(f64, f64, Option<f64>)> =
            subs.iter().map(|s| (s.t0, s.t1, s.error)).collect();
        let chart = charts::error_over_time(&timeline, thresholds, &[], 100.0, "error (cm)");
        let unit = Unit {
            name: "cm",
            scale: 100.0,
        };
        let scene = crate::report::scene_view::scene_json(&phone, &subs, thresholds, &unit, "test");
        let scene_text = scene.to_string();
        println!(
            "390 000 poses: top view {} kB, error chart {} kB, scene.json {} kB",
            svg.len() / 1000,
            chart.len() / 1000,
            scene_text.len() / 1000
        );
        assert!(svg.len() < 150_000, "top view {} bytes", svg.len());
        assert!(chart.len() < 60_000, "chart {} bytes", chart.len());
        assert!(
            scene_text.len() < 600_000,
            "scene.json {} bytes",
            scene_text.len()
        );
        let joints = &scene["downsampled"]["joints"];
        assert_eq!(joints["total"], 78_000);
        assert_eq!(joints["shown"], crate::report::scene_view::MAX_VIEW_JOINTS);
        assert_eq!(
            scene["joints"].as_array().unwrap().len(),
            3 * crate::report::scene_view::MAX_VIEW_JOINTS
        );
        // Every drawn joint's sub-trajectory is among those sent.
        let sent: std::collections::HashSet<u64> = scene["subs"]["index"]
            .as_array()
            .unwrap()
            .iter()
            .map(|k| k.as_u64().unwrap())
            .collect();
        assert!(
            scene["joint_sub"]
                .as_array()
                .unwrap()
                .iter()
                .all(|k| sent.contains(&k.as_u64().unwrap()))
        );
        assert_eq!(scene["downsampled"]["subs"]["total"], 39_000);
        // The statistics still come from all 39 000 sub-trajectories.
        let errors: Vec<f64> = subs.iter().filter_map(|s| s.error).collect();
        assert_eq!(errors.len(), 39_000);
        let max = statistics(&errors).unwrap()[3];
        assert!((max - 0.12).abs() < 1e-4, "{max}");
    }

    #[test]
    fn statistics_of_a_sample() {
        let s = statistics(&[3.0, 4.0, 1.0, 2.0]).unwrap();
        assert!((s[0] - (30.0f64 / 4.0).sqrt()).abs() < 1e-12);
        assert_eq!((s[1], s[2], s[3]), (2.5, 2.5, 4.0));
        assert!(statistics(&[]).is_none());
    }
}
