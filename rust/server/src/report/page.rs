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

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use serde::Deserialize;
use serde_json::json;
use sitar_core::{Convention, ErrorClass, Session as Phone, Thresholds};

use crate::config::ServerConfig;
use crate::error::Error;
use crate::model::Session;
use crate::report::charts::{self, HIGH, LOW, MEDIUM, UNKNOWN};
use crate::report::index_ranges::index_ranges;
use crate::report::region_evidence::{self, CameraEvidence};
use crate::report::regions::{self, SubRow};
use crate::report::scene::Source;
use crate::report::templates;

#[derive(Debug, Deserialize)]
struct ResultsDoc {
    #[serde(default)]
    setting: String,
    #[serde(default)]
    trials: u32,
    windows: Vec<serde::de::IgnoredAny>,
    /// The calibration the errors are calibrated with (none: the spread, as in the paper).
    #[serde(default)]
    calibration: Option<String>,
    /// The error estimated: `live` (the walk's own) or `expected`.
    #[serde(default)]
    target: Option<String>,
    /// Where the results come from: `walk` (alone) or `replays`.
    #[serde(default)]
    source: Option<String>,
    /// The runs behind them (the walk counts as one).
    #[serde(default)]
    runs: Option<u32>,
    /// `false`: the calibration's runs do not predict the error; the colours are a guess.
    #[serde(default)]
    informative: Option<bool>,
}

impl ResultsDoc {
    /// The replays behind results of the walk as the live run (0 for the walk alone); `None`
    /// for results from the replays alone.
    fn walk_replays(&self) -> Option<u32> {
        (self.target.as_deref() == Some("live")).then(|| match self.source.as_deref() {
            Some("walk") => 0,
            _ => self.runs.unwrap_or(self.trials).saturating_sub(1),
        })
    }

    /// Where results of the walk come from, as the page says it: `from the walk alone`, `from
    /// the walk and 3 replays`.
    fn walk_source(&self) -> Option<String> {
        self.walk_replays().map(|replays| match replays {
            0 => "from the walk alone".to_string(),
            1 => "from the walk and 1 replay".to_string(),
            n => format!("from the walk and {n} replays"),
        })
    }
}

/// A calibrated results document's windows, for their intervals (read only when the
/// document names a calibration).
#[derive(Debug, Deserialize)]
struct IntervalsDoc<'a> {
    #[serde(default)]
    time_unit: Option<String>,
    #[serde(borrow)]
    windows: Vec<IntervalWindow<'a>>,
}

#[derive(Debug, Deserialize)]
struct IntervalWindow<'a> {
    /// The start as written: integer nanoseconds, or seconds with up to 9 decimals.
    #[serde(borrow)]
    start: &'a serde_json::value::RawValue,
    #[serde(default, alias = "lower_deg")]
    lower_m: Option<f64>,
    #[serde(default, alias = "upper_deg")]
    upper_m: Option<f64>,
}

/// A results stamp (`start` as the estimator writes it) in nanoseconds: integer nanoseconds
/// with `time_unit` `ns`, else decimal seconds read exactly (no f64 rounding).
fn stamp_ns(text: &str, nanoseconds: bool) -> Option<i64> {
    if nanoseconds {
        return text.parse().ok();
    }
    let (negative, body) = match text.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, text),
    };
    let (whole, fraction) = body.split_once('.').unwrap_or((body, ""));
    if whole.is_empty()
        || fraction.len() > 9
        || !whole
            .bytes()
            .chain(fraction.bytes())
            .all(|b| b.is_ascii_digit())
    {
        return None;
    }
    let nanos: i64 = format!("{fraction:0<9}").parse().ok()?;
    let ns = whole
        .parse::<i64>()
        .ok()?
        .checked_mul(1_000_000_000)?
        .checked_add(nanos)?;
    Some(if negative { -ns } else { ns })
}

/// The interval of every window of calibrated results, by start (ns).
fn window_intervals(results_json: &str) -> std::collections::HashMap<i64, (f64, f64)> {
    let Ok(doc) = serde_json::from_str::<IntervalsDoc<'_>>(results_json) else {
        return Default::default();
    };
    let nanoseconds = doc.time_unit.as_deref() != Some("s");
    doc.windows
        .iter()
        .filter_map(|w| {
            let start = stamp_ns(w.start.get(), nanoseconds)?;
            Some((start, (w.lower_m?, w.upper_m?)))
        })
        .collect()
}

/// Each sub-trajectory's interval: that of the window the phone session matched it with.
fn attach_intervals(subs: &mut [SubRow], phone: &Phone, results_json: &str) {
    let Some(results) = phone.results() else {
        return;
    };
    let intervals = window_intervals(results_json);
    let starts: Vec<i64> = phone.subtrajectories().iter().map(|s| s.start_ns).collect();
    let windows = results.lookup_many(&starts, phone.lookup_tolerance_ns());
    for (sub, window) in subs.iter_mut().zip(windows) {
        sub.interval = window.and_then(|w| intervals.get(&w.start).copied());
    }
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

    /// `6.1–31.0 cm`, `1.2–5.0°`.
    fn range(&self, (lower, upper): (f64, f64)) -> String {
        let space = if self.name == "°" { "" } else { " " };
        format!(
            "{:.1}–{:.1}{space}{}",
            lower * self.scale,
            upper * self.scale,
            self.name
        )
    }
}

/// The calibration of a session's results, as the page shows it.
struct CalibrationView {
    /// Its name, as the results name it.
    name: String,
    /// `80 % interval` (the coverage of the calibration this server has by that name), or
    /// `interval` when this server does not have it.
    interval: String,
}

impl CalibrationView {
    fn of(doc: &ResultsDoc, config: &ServerConfig) -> Option<CalibrationView> {
        let name = doc.calibration.clone()?;
        let interval = match config.calibrations.get(&name) {
            Some(c) => format!("{} % interval", trim_percent(c.fitted_on.coverage)),
            None => "interval".to_string(),
        };
        Some(CalibrationView { name, interval })
    }
}

/// A share as a percentage without needless decimals: 0.8 → `80`, 0.875 → `87.5`.
fn trim_percent(share: f64) -> String {
    let text = format!("{:.1}", share * 100.0);
    text.trim_end_matches(".0").to_string()
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

/// Static top view (x right, z down the page, as the 3-D view's top view), framing the
/// path, the markers and the faced surface points: the path coloured by class, the surface
/// points, markers and start/stop, grid coordinates, axis names and a scale bar. Numbers only.
fn top_view(phone: &Phone, subs: &[SubRow]) -> String {
    let joints = phone.render_plan().joints;
    if joints.len() < 2 {
        return String::new();
    }
    let pts: Vec<glam::DVec3> = joints.iter().map(|j| view_point(j.position)).collect();
    let markers = phone.markers().unwrap_or_default();
    // The frame holds the walk, the markers and the faced surface points.
    let (mut lo, mut hi) = (glam::DVec3::MAX, glam::DVec3::MIN);
    let faced = subs.iter().filter_map(|s| s.surface).map(view_point);
    for p in pts
        .iter()
        .copied()
        .chain(markers.iter().map(|m| view_point(m.position)))
        .chain(faced)
    {
        lo = lo.min(p);
        hi = hi.max(p);
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
    axis_labels(&mut svg, lo, span, margin);
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
    // The faced surface points (thinned like the path), under the markers.
    let surface: Vec<glam::DVec3> = subs
        .iter()
        .filter_map(|s| s.surface)
        .map(view_point)
        .collect();
    let _ = write!(svg, r##"<g class="surface" fill="#8c564b">"##);
    for i in crate::report::thinning::thin(surface.len(), MAX_TOP_VIEW_POINTS) {
        let _ = write!(
            svg,
            r#"<circle cx="{:.3}" cy="{:.3}" r="{:.3}"/>"#,
            surface[i].x,
            surface[i].z,
            stroke * 1.5
        );
    }
    svg.push_str("</g>");
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

/// The top view's reading aids: each 1 m grid line's coordinate on the edges, the axes'
/// names and directions, and a scale bar (1 m, or 5 m for a large walk). `lo` is the walk's
/// lower corner, `span` its larger side and `margin` the frame round it, all in metres.
fn axis_labels(svg: &mut String, lo: glam::DVec3, span: f64, margin: f64) {
    let font = span / 38.0;
    let (left, top) = (lo.x - margin, lo.z - margin);
    let (right, bottom) = (lo.x + span + margin, lo.z + span + margin);
    let _ = write!(
        svg,
        r##"<g class="axis-labels" font-size="{font:.3}" fill="#555">"##
    );
    let mut g = left.ceil();
    while g <= right - 2.0 * font {
        let _ = write!(
            svg,
            r#"<text x="{g}" y="{:.3}" text-anchor="middle">{:.0}</text>"#,
            top + font * 1.1,
            g + 0.0
        );
        g += 1.0;
    }
    let mut g = (top + 2.0 * font).ceil();
    while g <= bottom - 2.5 * font {
        let _ = write!(
            svg,
            r#"<text x="{:.3}" y="{:.3}">{:.0}</text>"#,
            left + font * 0.3,
            g + font * 0.35,
            g + 0.0
        );
        g += 1.0;
    }
    let _ = write!(
        svg,
        r#"<text class="axis" x="{:.3}" y="{:.3}" text-anchor="end">x (m) →</text><text class="axis" x="{:.3}" y="{:.3}">z (m) ↓</text>"#,
        right - font * 0.3,
        top + font * 2.3,
        left + font * 0.3,
        bottom - font * 0.5,
    );
    let bar = if span > 12.0 { 5.0 } else { 1.0 };
    let (x1, y) = (right - font, bottom - font * 0.8);
    let _ = write!(
        svg,
        r##"<g class="scale-bar"><line x1="{:.3}" y1="{y:.3}" x2="{x1:.3}" y2="{y:.3}" stroke="#222" stroke-width="{:.4}"/><text x="{:.3}" y="{:.3}" text-anchor="middle" fill="#222">{bar} m</text></g></g>"##,
        x1 - bar,
        font * 0.25,
        x1 - bar / 2.0,
        y - font * 0.4,
    );
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
    /// Some for a page that stands alone (`?download=1`, the demo's file): everything
    /// inline, nothing fetched.
    pub standalone: Option<Standalone<'a>>,
}

/// What a stand-alone page needs besides the served one's input.
pub(crate) struct Standalone<'a> {
    /// The stored JPEG thumbnail of sub-trajectory k (none when there is none).
    pub thumbnail: &'a dyn Fn(u32) -> Option<Vec<u8>>,
    /// What the 3-D view draws (`crate::report::scene_view`, as `scene.json` serves it), none
    /// without a trajectory.
    pub scene: Option<serde_json::Value>,
}

/// Path points of the static top view (a 10-minute walk logs 3 600).
const MAX_TOP_VIEW_POINTS: usize = 1_500;

/// Regions and markers listed on the page (the counts above the tables are of all).
const MAX_TABLE_ROWS: usize = 100;

/// Seconds between reloads of a page whose estimate is still partial.
pub(crate) const REFRESH_S: u32 = 5;

/// The session's sub-trajectories, markers and regions as the page shows them.
struct Analysis {
    thresholds: Thresholds,
    unit: Unit,
    doc: ResultsDoc,
    subs: Vec<SubRow>,
    markers: Vec<sitar_core::Marker>,
    regions: Vec<regions::Region>,
    /// The errors of the sub-trajectories with an estimate.
    errors: Vec<f64>,
    /// The calibration of calibrated results.
    calibration: Option<CalibrationView>,
}

/// Step 1: the results read, the walk classified, regions found and their evidence attached.
fn analyse(input: &ReportInput<'_>) -> Result<Analysis, Error> {
    let row = input.row;
    let thresholds: Thresholds = row
        .settings
        .thresholds(input.config.thresholds, input.config.thresholds_deg);
    let doc: ResultsDoc = serde_json::from_str(input.results_json)
        .map_err(|e| Error::Internal(format!("results.json of {} is unreadable: {e}", row.id)))?;
    let calibration = CalibrationView::of(&doc, input.config);
    let (subs, markers) = match input.phone {
        Some((phone, _)) => {
            let mut subs = regions::sub_rows(phone, thresholds);
            if calibration.is_some() {
                attach_intervals(&mut subs, phone, input.results_json);
            }
            (subs, phone.markers().unwrap_or_default())
        }
        None => (Vec::new(), Vec::new()),
    };
    let radius = input.phone.map_or(0.5, |(p, _)| p.config().dedup_radius_m);
    let mut found = regions::regions(&subs, &markers, radius);
    if let Some(evidence) = input.evidence {
        let base = input.base;
        let image_url = |k: u32| match &input.standalone {
            // Inline: the page opens from disk.
            Some(alone) => (alone.thumbnail)(k)
                .map(|jpeg| format!("data:image/jpeg;base64,{}", BASE64.encode(jpeg)))
                .unwrap_or_default(),
            None => format!("{base}subtrajectories/{k}/image.jpg"),
        };
        region_evidence::attach(&mut found, &subs, evidence, &image_url);
    }
    let errors = subs.iter().filter_map(|s| s.error).collect();
    Ok(Analysis {
        thresholds,
        unit: Unit::of(row),
        doc,
        subs,
        markers,
        regions: found,
        errors,
        calibration,
    })
}

/// Step 2: the regions table.
fn region_rows(a: &Analysis, phone: Option<&Phone>) -> Vec<serde_json::Value> {
    let unit = &a.unit;
    a.regions
        .iter()
        .take(MAX_TABLE_ROWS)
        .map(|r| {
            let evidence = r.evidence.as_ref();
            json!({
                "rank": r.rank,
                "class": r.class.name(),
                "colour": colour(r.class),
                "max_error": match (&a.calibration, r.interval) {
                    (Some(c), Some(bounds)) => format!(
                        "{} ({} {})",
                        unit.show(r.max_error),
                        c.interval,
                        unit.range(bounds)
                    ),
                    _ => unit.show(r.max_error),
                },
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
                "no_marker": phone.and_then(|p| regions::why_no_marker(r, &a.subs, &a.markers, p.config())),
                "thumbnail_url": evidence.and_then(|e| e.thumbnail_url.as_deref()).filter(|u| !u.is_empty()),
                "pictured": evidence.and_then(|e| e.pictured),
                "covered": evidence.map(|e| e.covered),
                "causes": evidence.map(|e| e.causes.iter().map(|c| json!({
                    "name": c.name, "reason": c.reason, "count": c.count,
                })).collect::<Vec<_>>()),
            })
        })
        .collect()
}

/// Step 3: the markers table, each with the tier it was placed at.
fn marker_rows(a: &Analysis, phone: Option<&Phone>) -> Vec<serde_json::Value> {
    let unit = &a.unit;
    a.markers
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
                "tier": phone
                    .and_then(|p| regions::marker_tier(p, m.error_m))
                    .map(|t| format!("≥ {}", unit.show(t))),
                "position": format!("({:.2}, {:.2}, {:.2})", p.x, p.y, p.z),
                "region": a.regions.iter().find(|r| r.markers.contains(&(i + 1))).map(|r| r.rank),
            })
        })
        .collect()
}

/// Step 4: the settings table (a calibrated session's calibration last).
fn settings_rows(row: &Session, a: &Analysis) -> Vec<(&'static str, String)> {
    let unit = &a.unit;
    let mut rows = vec![
        ("Session", row.id.clone()),
        ("State", row.state.as_str().to_string()),
        (
            "Statistic",
            if a.doc.setting.is_empty() {
                row.settings.setting.to_string()
            } else {
                a.doc.setting.clone()
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
                unit.show(a.thresholds.medium),
                unit.show(a.thresholds.high)
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
    if let Some(name) = &row.calibration {
        let how = match &a.calibration {
            Some(c) if &c.name == name => format!("{name} (errors calibrated, {})", c.interval),
            _ => format!("{name} (not on this server: errors uncalibrated)"),
        };
        rows.push(("Calibration", how));
    }
    rows
}

/// The banner of a session whose calibration this server lacks: its results are the
/// uncalibrated spread (none when they are calibrated, or none was asked for).
fn calibration_missing(row: &Session, a: &Analysis) -> Option<String> {
    let asked = row.calibration.as_ref()?;
    let applied = a.calibration.as_ref().map(|c| &c.name);
    (applied != Some(asked)).then(|| asked.clone())
}

/// Step 5: whether the estimate is still partial (trials are arriving), for the banner
/// and the page's reload.
fn partial(row: &Session, doc: &ResultsDoc) -> Option<serde_json::Value> {
    use crate::model::SessionState;
    let finished = matches!(row.state, SessionState::Done | SessionState::Failed);
    (!finished).then(|| {
        json!({
            "trials": doc.walk_replays().unwrap_or(doc.trials),
            "walk": doc.walk_replays().is_some(),
            "total": row.trials_total,
            "state": row.state.as_str(),
        })
    })
}

/// The style and script a stand-alone page carries inline.
const INLINE_CSS: &str = include_str!("../../assets/site.css");
const INLINE_SCRIPT: &str = include_str!("../../assets/report.bundle.js");

/// The bundle as a stand-alone page's inline script (this page's and the venue page's).
pub(crate) fn inline_script() -> Result<&'static str, Error> {
    // The script element ends at the first `</script`: the bundle must not hold one.
    if INLINE_SCRIPT.to_ascii_lowercase().contains("</script") {
        return Err(Error::Internal(
            "report.bundle.js holds </script: it cannot be inlined".into(),
        ));
    }
    Ok(INLINE_SCRIPT)
}

/// The Content-Security-Policy of a stand-alone page (this one and the venue page): its
/// inline script and style by hash.
pub(crate) fn standalone_csp() -> String {
    let hash = |text: &str| {
        let digest = ring::digest::digest(&ring::digest::SHA256, text.as_bytes());
        format!("'sha256-{}'", BASE64.encode(digest.as_ref()))
    };
    templates::standalone_csp(&hash(INLINE_SCRIPT), &hash(INLINE_CSS))
}

/// Step 6: what a stand-alone page carries inline (style, script, scene data) and its
/// Content-Security-Policy, which allows exactly those.
fn inline_parts(alone: &Standalone<'_>) -> Result<serde_json::Value, Error> {
    let script = inline_script()?;
    // `<` only occurs inside JSON strings, where `\u003c` means the same: no `</script`.
    let scene = alone
        .scene
        .as_ref()
        .map(|s| s.to_string().replace('<', "\\u003c"));
    Ok(json!({
        "css": INLINE_CSS,
        "script": script,
        "scene": scene,
        "csp": standalone_csp(),
    }))
}

/// The report page: the steps above into `templates/report.html`.
pub(crate) fn render(input: &ReportInput<'_>) -> Result<String, Error> {
    let row = input.row;
    let a = analyse(input)?;
    let phone = input.phone.map(|(p, _)| p);
    let (unit, thresholds) = (&a.unit, a.thresholds);
    let marker_times: Vec<(usize, f64)> = a
        .markers
        .iter()
        .enumerate()
        .filter_map(|(i, m)| a.subs.get(m.subtrajectory as usize).map(|s| (i + 1, s.t0)))
        .collect();
    let y_label = format!("error ({})", unit.name);
    let timeline: Vec<(f64, f64, Option<f64>)> =
        a.subs.iter().map(|s| (s.t0, s.t1, s.error)).collect();
    let intervals: Vec<Option<(f64, f64)>> = a.subs.iter().map(|s| s.interval).collect();
    let band = a.calibration.as_ref().map(|c| charts::Band {
        intervals: &intervals,
        title: format!("{} (calibration {})", c.interval, c.name),
    });
    let count = |c: ErrorClass| a.subs.iter().filter(|s| s.class == c).count();
    // Results of the walk: the replays are the trials, each paired with the walk.
    let walk_replays = a.doc.walk_replays();
    let trials = walk_replays.unwrap_or(a.doc.trials);
    let pairs = match walk_replays {
        Some(replays) => replays,
        None => trials * trials.saturating_sub(1) / 2,
    };
    let standalone = match &input.standalone {
        Some(alone) => Some(inline_parts(alone)?),
        None => None,
    };
    let tiers: Vec<String> = phone
        .map(|p| p.config().marker_thresholds().to_vec())
        .unwrap_or_default()
        .iter()
        .map(|t| unit.show(*t))
        .collect();
    let mut context = json!({
        "id": row.id,
        "unit": unit.name,
        // Every sub-trajectory the walk has, the same count as the 3-D view's, the tables'
        // and the charts' (a last one may have its midpoint only).
        "subtrajectories": a.subs.len(),
        "estimated": a.errors.len(),
        "high": count(ErrorClass::High),
        "medium": count(ErrorClass::Medium),
        "low": count(ErrorClass::Low),
        "regions": region_rows(&a, phone),
        "region_count": a.regions.len(),
        "markers": marker_rows(&a, phone),
        "marker_count": a.markers.len(),
        "max_markers": phone.map(|p| p.config().max_regions),
        "marker_radius": phone.map(|p| p.config().dedup_radius_m),
        "tiers": tiers.join(", "),
        "medium_at": unit.show(thresholds.medium),
        "high_at": unit.show(thresholds.high),
        "has_evidence": input.evidence.is_some(),
        "base": input.base,
        "windows": a.doc.windows.len(),
        "window_frames": row.settings.window_frames,
        "trials": trials,
        "pairs": pairs,
        "partial": partial(row, &a.doc),
        "refresh_s": REFRESH_S,
        "standalone": standalone,
        "stats": statistics(&a.errors).map(|s| s.map(|v| unit.show(v))),
        "source": input.phone.map(|(_, s)| s.describe()),
        "top_view": phone.map(|p| top_view(p, &a.subs)).unwrap_or_default(),
        "error_chart": if a.subs.is_empty() { String::new() } else {
            charts::error_over_time(&timeline, thresholds, &marker_times, unit.scale, &y_label, band.as_ref())
        },
        "histogram": if a.errors.is_empty() { String::new() } else {
            charts::histogram(&a.errors, thresholds, unit.scale, &y_label)
        },
        "settings": settings_rows(row, &a),
        "history_chart": history_chart(&input.history, thresholds, unit, &y_label),
        "history": input.history.iter().map(|h| json!({
            "trials": h["trials"],
            "mean": unit.show(h["mean"].as_f64().unwrap_or(0.0)),
            "max": unit.show(h["max"].as_f64().unwrap_or(0.0)),
            "high": h["high"], "medium": h["medium"], "low": h["low"],
        })).collect::<Vec<_>>(),
        "colours": {"low": LOW, "medium": MEDIUM, "high": HIGH, "unknown": UNKNOWN},
    });
    context["calibration"] = json!(a.calibration.as_ref().map(|c| json!({
        "name": c.name,
        "interval": c.interval,
    })));
    context["calibration_missing"] = json!(calibration_missing(row, &a));
    context["from_walk"] = json!(a.doc.walk_source());
    context["runs"] = json!(a.doc.runs.unwrap_or(a.doc.trials));
    context["not_informative"] = json!(a.doc.informative == Some(false));
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
        // Read at a glance: the axes named, a scale bar, the grid lines' coordinates.
        assert!(svg.contains(">x (m) →</text>") && svg.contains(">z (m) ↓</text>"));
        assert!(svg.contains(r#"<g class="scale-bar">"#) && svg.contains(">1 m</text>"));
        assert!(
            svg.contains(r#"text-anchor="middle">-6</text>"#),
            "no x = -6 m label"
        );
        assert_eq!(
            svg.matches("<line class=\"seg ").count(),
            MAX_TOP_VIEW_POINTS - 1
        );
        for class in ["low", "medium", "high"] {
            assert!(svg.contains(&format!("seg {class}")), "no {class} segment");
        }
        let timeline: Vec<(f64, f64, Option<f64>)> =
            subs.iter().map(|s| (s.t0, s.t1, s.error)).collect();
        let chart = charts::error_over_time(&timeline, thresholds, &[], 100.0, "error (cm)", None);
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

    /// The demo's walk: its markers stand on the wall at x ≈ 2.5 m, past the path's own
    /// extent; the top view's frame holds them and every faced surface point.
    #[test]
    fn the_top_view_frames_the_markers_and_the_faced_surfaces() {
        let recording = sitar_sim::Recording::demo(15.0, 30.0, 42).unwrap();
        let mut phone = recording
            .phone_session(
                sitar_core::SessionConfig::from_json(r#"{"convention":"arcore"}"#).unwrap(),
                sitar_core::DisplayRotation::Deg90,
            )
            .unwrap();
        // An error that rises along the walk: every class, and markers.
        let windows: Vec<serde_json::Value> = phone
            .subtrajectories()
            .iter()
            .map(|s| json!({"start": s.start_ns, "error_m": 0.003 * f64::from(s.index)}))
            .collect();
        let results = json!({"version": 1, "setting": "median", "trials": 3,
            "pose_relation": "trans_part", "window_frames": 10, "unit": "m", "windows": windows});
        phone.load_results(&results.to_string()).unwrap();
        let thresholds = Thresholds {
            medium: 0.05,
            high: 0.10,
        };
        let subs = regions::sub_rows(&phone, thresholds);
        let markers = phone.markers().unwrap();
        assert!(!markers.is_empty());
        let svg = top_view(&phone, &subs);
        let view: Vec<f64> = svg
            .split("viewBox=\"")
            .nth(1)
            .and_then(|v| v.split('"').next())
            .unwrap()
            .split(' ')
            .map(|n| n.parse().unwrap())
            .collect();
        let inside = |p: glam::DVec3| {
            (view[0]..=view[0] + view[2]).contains(&p.x)
                && (view[1]..=view[1] + view[3]).contains(&p.z)
        };
        for m in &markers {
            assert!(
                inside(m.position),
                "marker at {} outside {view:?}",
                m.position
            );
        }
        let faced: Vec<glam::DVec3> = subs.iter().filter_map(|s| s.surface).collect();
        assert!(faced.iter().all(|p| inside(*p)), "{view:?}");
        assert_eq!(
            svg.matches(r#"<circle class="marker""#).count(),
            markers.len()
        );
        let dots = svg.split(r#"<g class="surface""#).nth(1).unwrap();
        let dots = &dots[..dots.find("</g>").unwrap()];
        assert_eq!(dots.matches("<circle").count(), faced.len());
    }

    fn row(calibration: Option<&str>) -> Session {
        Session {
            id: "s0123456789abcdef".into(),
            state: crate::model::SessionState::Done,
            playback: crate::model::PlaybackKind::Upload,
            trials_total: 3,
            settings: crate::model::estimate_settings::EstimateSettings::defaults(
                &ServerConfig::new("unused").default_setting,
            )
            .unwrap(),
            error: None,
            stop_reason: None,
            adaptive_min: None,
            adaptive_k: 3,
            recording_bytes: None,
            results_trials: 3,
            legacy: false,
            owner: None,
            venue: None,
            convention: Convention::Arcore,
            calibration: calibration.map(str::to_string),
        }
    }

    /// The demo walk with results whose error rises along it; calibrated ones (`lab`) carry
    /// an interval of ×0.5 … ×2 around each error.
    fn demo_report(calibrated: bool, config: &ServerConfig, row: &Session) -> String {
        let recording = sitar_sim::Recording::demo(15.0, 30.0, 42).unwrap();
        let mut phone = recording
            .phone_session(
                sitar_core::SessionConfig::from_json(r#"{"convention":"arcore"}"#).unwrap(),
                sitar_core::DisplayRotation::Deg90,
            )
            .unwrap();
        let windows: Vec<serde_json::Value> = phone
            .subtrajectories()
            .iter()
            .map(|s| {
                let e = 0.003 * f64::from(s.index);
                let mut w = json!({"start": s.start_ns, "error_m": e});
                if calibrated {
                    w["lower_m"] = json!(e * 0.5);
                    w["upper_m"] = json!(e * 2.0);
                    w["raw_m"] = json!(e / 3.0);
                }
                w
            })
            .collect();
        let mut results = json!({"version": 1, "setting": "trim_mean_30", "trials": 3,
            "time_unit": "ns", "pose_relation": "trans_part", "window_frames": 10, "unit": "m",
            "windows": windows});
        if calibrated {
            results["calibration"] = json!("lab");
        }
        let results = results.to_string();
        phone.load_results(&results).unwrap();
        render(&ReportInput {
            row,
            results_json: &results,
            config,
            phone: Some((&phone, Source::SimulatedWalk)),
            history: Vec::new(),
            base: "/v1/sessions/s0123456789abcdef/",
            evidence: None,
            standalone: None,
        })
        .unwrap()
    }

    #[test]
    fn a_calibrated_report_draws_the_interval_and_names_the_calibration() {
        let mut config = ServerConfig::new("unused");
        let calibration = sitar_estimator::Calibration::from_json(
            &crate::estimate::calibrations::tests::calibration("trim_mean_30", 10, "trans_part"),
            "test",
        )
        .unwrap();
        config.calibrations.insert("lab", calibration).unwrap();
        let page = demo_report(true, &config, &row(Some("lab")));
        assert!(page.contains(r#"id="error-interval""#), "no band");
        assert!(page.contains(r#"<b id="calibration-name">lab</b>"#));
        assert!(page.contains("80 % interval"));
        // Each region gives its worst sub-trajectory's error with its interval.
        let regions = &page[page.find(r#"<table id="regions">"#).unwrap()..];
        let regions = &regions[..regions.find("</table>").unwrap()];
        let first = regions.split("<td>").nth(3).unwrap();
        let first = &first[..first.find("</td>").unwrap()];
        let (error, interval) = first.split_once(" (80 % interval ").unwrap();
        let error: f64 = error.trim_end_matches(" cm").parse().unwrap();
        let (lower, upper) = interval.trim_end_matches(" cm)").split_once('–').unwrap();
        let (lower, upper): (f64, f64) = (lower.parse().unwrap(), upper.parse().unwrap());
        assert!(
            (lower - error * 0.5).abs() < 0.06 && (upper - error * 2.0).abs() < 0.06,
            "{first}"
        );
        assert!(page.contains("lab (errors calibrated, 80 % interval)"));
        assert!(!page.contains("calibration-missing"));

        // Served without the calibration, the results published with it keep their interval.
        let without = ServerConfig::new("unused");
        let page = demo_report(true, &without, &row(Some("lab")));
        assert!(page.contains(r#"id="error-interval""#) && page.contains(" (interval "));
        // Results published uncalibrated for a session that asked: the banner says why.
        let page = demo_report(false, &without, &row(Some("lab")));
        assert!(page.contains(r#"id="calibration-missing""#));
        assert!(!page.contains("error-interval") && !page.contains("calibration-legend"));

        // An uncalibrated session's page has nothing of it.
        let page = demo_report(false, &config, &row(None));
        for word in ["interval", "calibrat"] {
            assert!(!page.to_lowercase().contains(word), "{word}");
        }
    }

    #[test]
    fn results_stamps_are_read_exactly() {
        assert_eq!(
            stamp_ns("1700000000000000001", true),
            Some(1_700_000_000_000_000_001)
        );
        assert_eq!(
            stamp_ns("1403636579.763555527", false),
            Some(1_403_636_579_763_555_527)
        );
        assert_eq!(stamp_ns("1.5", false), Some(1_500_000_000));
        assert_eq!(stamp_ns("-0.25", false), Some(-250_000_000));
        for bad in ["", ".5", "1.0000000001", "1e9", "x"] {
            assert_eq!(stamp_ns(bad, false), None, "{bad}");
        }
    }

    #[test]
    fn statistics_of_a_sample() {
        let s = statistics(&[3.0, 4.0, 1.0, 2.0]).unwrap();
        assert!((s[0] - (30.0f64 / 4.0).sqrt()).abs() < 1e-12);
        assert_eq!((s[1], s[2], s[3]), (2.5, 2.5, 4.0));
        assert!(statistics(&[]).is_none());
    }
}
