//! The report's charts as SVG text (numbers only: nothing from a client reaches them).

use std::fmt::Write;

use sitar_core::Thresholds;

pub(crate) const LOW: &str = "#2f6fde";
pub(crate) const MEDIUM: &str = "#e0b100";
pub(crate) const HIGH: &str = "#d62728";
pub(crate) const UNKNOWN: &str = "#9a9a9a";

/// Round tick steps: 1, 2 or 5 × 10^k giving about `count` ticks over `span`.
fn tick_step(span: f64, count: f64) -> f64 {
    let raw = (span / count).max(1e-12);
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag)
}

/// Plot frame: data ranges mapped into a `w × h` box with margins for the axes.
struct Frame {
    w: f64,
    h: f64,
    x0: f64,
    x1: f64,
    y1: f64,
}

const LEFT: f64 = 48.0;
const BOTTOM: f64 = 30.0;
const TOP: f64 = 10.0;
const RIGHT: f64 = 10.0;

impl Frame {
    fn x(&self, v: f64) -> f64 {
        LEFT + (v - self.x0) / (self.x1 - self.x0).max(1e-12) * (self.w - LEFT - RIGHT)
    }
    fn y(&self, v: f64) -> f64 {
        self.h - BOTTOM - v / self.y1.max(1e-12) * (self.h - BOTTOM - TOP)
    }
    /// The low, medium and high bands behind a chart of errors, from the class thresholds.
    fn class_bands(&self, svg: &mut String, thresholds: Thresholds) {
        for (lo, hi, colour) in [
            (0.0, thresholds.medium, LOW),
            (thresholds.medium, thresholds.high, MEDIUM),
            (thresholds.high, self.y1, HIGH),
        ] {
            let _ = write!(
                svg,
                r#"<rect class="band" x="{x:.1}" y="{y:.1}" width="{bw:.1}" height="{bh:.1}" fill="{colour}" fill-opacity="0.10"/>"#,
                x = LEFT,
                y = self.y(hi),
                bw = self.w - LEFT - RIGHT,
                bh = self.y(lo) - self.y(hi),
            );
        }
    }

    fn axes(&self, svg: &mut String, x_label: &str, y_label: &str, scale: f64) {
        let step = tick_step(self.x1 - self.x0, 6.0);
        let mut t = (self.x0 / step).ceil() * step;
        while t <= self.x1 + 1e-9 {
            let _ = write!(
                svg,
                r##"<line x1="{x:.1}" y1="{b:.1}" x2="{x:.1}" y2="{b2:.1}" stroke="#666"/><text x="{x:.1}" y="{ty:.1}" text-anchor="middle" font-size="11">{t}</text>"##,
                x = self.x(t),
                b = self.h - BOTTOM,
                b2 = self.h - BOTTOM + 4.0,
                ty = self.h - BOTTOM + 16.0,
                t = trim(t)
            );
            t += step;
        }
        let step = tick_step(self.y1 * scale, 4.0) / scale;
        let mut v = 0.0;
        while v <= self.y1 + 1e-12 {
            let _ = write!(
                svg,
                r##"<line x1="{l:.1}" y1="{y:.1}" x2="{r:.1}" y2="{y:.1}" stroke="#e4e4e4"/><text x="{tx:.1}" y="{ty:.1}" text-anchor="end" font-size="11">{v}</text>"##,
                l = LEFT,
                r = self.w - RIGHT,
                y = self.y(v),
                tx = LEFT - 4.0,
                ty = self.y(v) + 4.0,
                v = trim(v * scale)
            );
            v += step;
        }
        let _ = write!(
            svg,
            r##"<line x1="{l}" y1="{b:.1}" x2="{r:.1}" y2="{b:.1}" stroke="#333"/><line x1="{l}" y1="{t}" x2="{l}" y2="{b:.1}" stroke="#333"/><text x="{cx:.1}" y="{by:.1}" text-anchor="middle" font-size="12">{x_label}</text><text x="12" y="{cy:.1}" font-size="12" transform="rotate(-90 12 {cy:.1})" text-anchor="middle">{y_label}</text>"##,
            l = LEFT,
            r = self.w - RIGHT,
            t = TOP,
            b = self.h - BOTTOM,
            cx = (self.w + LEFT) / 2.0,
            by = self.h - 2.0,
            cy = (self.h - BOTTOM) / 2.0,
        );
    }
}

/// A short number: no trailing zeros.
fn trim(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// Steps of the error-over-time chart: past this many sub-trajectories, consecutive ones are
/// grouped and each group drawn at its largest error (the chart is 760 px wide).
pub(crate) const MAX_CHART_STEPS: usize = 1_000;

/// `subs` grouped into at most `MAX_CHART_STEPS` steps, each spanning its group's time and
/// showing its largest error (none when no member has one).
fn grouped(subs: &[(f64, f64, Option<f64>)]) -> Vec<(f64, f64, Option<f64>)> {
    let size = subs.len().div_ceil(MAX_CHART_STEPS).max(1);
    subs.chunks(size)
        .map(|group| {
            let max = group.iter().filter_map(|s| s.2).reduce(f64::max);
            (group[0].0, group[group.len() - 1].1, max)
        })
        .collect()
}

/// The interval band of a calibrated estimate behind the error chart.
pub(crate) struct Band<'a> {
    /// Per sub-trajectory (as the chart's `subs`), its window's interval (lower, upper).
    pub intervals: &'a [Option<(f64, f64)>],
    /// The band's tooltip, e.g. `80 % interval (calibration lab)`.
    pub title: String,
}

/// One step of the band: its start and end time, and its bounds (lower, upper).
type BandStep = (f64, f64, Option<(f64, f64)>);

/// The band's steps, grouped as [`grouped`] groups the errors: each group's lowest lower
/// and highest upper bound (none when no member has an interval).
fn grouped_band(
    subs: &[(f64, f64, Option<f64>)],
    intervals: &[Option<(f64, f64)>],
) -> Vec<BandStep> {
    let size = subs.len().div_ceil(MAX_CHART_STEPS).max(1);
    subs.chunks(size)
        .zip(intervals.chunks(size))
        .map(|(group, bounds)| {
            let envelope = bounds
                .iter()
                .flatten()
                .copied()
                .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)));
            (group[0].0, group[group.len() - 1].1, envelope)
        })
        .collect()
}

/// `text` for an SVG text node or attribute.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Rows of marker labels at the top of the error chart.
const LABEL_ROWS: usize = 3;

/// The width of `text` at font size 11 in px, generously (digits and capitals ≈ 7 px).
fn label_width(text: &str) -> f64 {
    7.0 * text.chars().count() as f64
}

/// Error over time: class bands, one step per sub-trajectory (gaps where no window matched;
/// grouped past `MAX_CHART_STEPS`), a calibrated estimate's interval as a grey band behind
/// the line, dashed lines at the markers' times. `scale` turns the unit into the shown one
/// (m → cm).
pub(crate) fn error_over_time(
    subs: &[(f64, f64, Option<f64>)],
    thresholds: Thresholds,
    markers: &[(usize, f64)],
    scale: f64,
    y_label: &str,
    band: Option<&Band<'_>>,
) -> String {
    let (w, h) = (760.0, 240.0);
    let x1 = subs.last().map_or(1.0, |s| s.1).max(1e-3);
    let uppers = band
        .into_iter()
        .flat_map(|b| b.intervals.iter().flatten().map(|i| i.1));
    let max = subs
        .iter()
        .filter_map(|s| s.2)
        .chain(uppers)
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let frame = Frame {
        w,
        h,
        x0: 0.0,
        x1,
        y1: max.max(thresholds.high * 1.25),
    };
    let mut svg = format!(
        r#"<svg id="error-time" xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" aria-label="estimated error over time">"#
    );
    frame.class_bands(&mut svg, thresholds);
    frame.axes(&mut svg, "time (s)", y_label, scale);
    if let Some(band) = band {
        interval_band(&mut svg, &frame, subs, band);
    }
    let mut path = String::new();
    let mut pen_down = false;
    let steps = grouped(subs);
    if steps.len() < subs.len() {
        let _ = write!(
            svg,
            r#"<title>each step: the largest error of {} consecutive sub-trajectories</title>"#,
            subs.len().div_ceil(steps.len())
        );
    }
    for &(t0, t1, e) in &steps {
        match e {
            Some(e) => {
                let op = if pen_down { 'L' } else { 'M' };
                let _ = write!(
                    path,
                    "{op}{:.1} {:.1}L{:.1} {:.1}",
                    frame.x(t0),
                    frame.y(e),
                    frame.x(t1),
                    frame.y(e)
                );
                pen_down = true;
            }
            None => pen_down = false,
        }
    }
    let _ = write!(
        svg,
        r##"<path id="error-line" d="{path}" fill="none" stroke="#222" stroke-width="1.2"/>"##
    );
    // Labels that would touch go one row down (up to `LABEL_ROWS`); past that, the line
    // keeps its label as a tooltip only.
    let mut row_ends = [f64::MIN; LABEL_ROWS];
    for &(number, t) in markers {
        let x = frame.x(t);
        let label = format!("M{number}");
        let width = label_width(&label);
        let _ = write!(
            svg,
            r##"<line class="marker-time" x1="{x:.1}" y1="{t:.1}" x2="{x:.1}" y2="{b:.1}" stroke="#7b2cbf" stroke-dasharray="4 3"><title>{label}</title></line>"##,
            t = TOP,
            b = h - BOTTOM,
        );
        let tx = x + 3.0;
        if let Some(row) = row_ends.iter().position(|&end| tx >= end + 2.0) {
            row_ends[row] = tx + width;
            let _ = write!(
                svg,
                r##"<text class="marker-label" x="{tx:.1}" y="{ty:.1}" font-size="11" fill="#7b2cbf">{label}</text>"##,
                ty = TOP + 12.0 + 12.0 * row as f64,
            );
        }
    }
    svg.push_str("</svg>");
    svg
}

/// The interval band: one closed path per run of steps with an interval, along the upper
/// bounds forward and the lower bounds back.
fn interval_band(
    svg: &mut String,
    frame: &Frame,
    subs: &[(f64, f64, Option<f64>)],
    band: &Band<'_>,
) {
    let steps = grouped_band(subs, band.intervals);
    let mut path = String::new();
    let mut run: Vec<(f64, f64, (f64, f64))> = Vec::new();
    let close = |run: &mut Vec<(f64, f64, (f64, f64))>, path: &mut String| {
        for (i, &(t0, t1, (_, upper))) in run.iter().enumerate() {
            let op = if i == 0 { 'M' } else { 'L' };
            let y = frame.y(upper);
            let _ = write!(
                path,
                "{op}{:.1} {y:.1}L{:.1} {y:.1}",
                frame.x(t0),
                frame.x(t1)
            );
        }
        for &(t0, t1, (lower, _)) in run.iter().rev() {
            let y = frame.y(lower);
            let _ = write!(path, "L{:.1} {y:.1}L{:.1} {y:.1}", frame.x(t1), frame.x(t0));
        }
        if !run.is_empty() {
            path.push('Z');
        }
        run.clear();
    };
    for (t0, t1, interval) in steps {
        match interval {
            Some(bounds) if bounds.0.is_finite() && bounds.1.is_finite() => {
                run.push((t0, t1, bounds));
            }
            _ => close(&mut run, &mut path),
        }
    }
    close(&mut run, &mut path);
    let _ = write!(
        svg,
        r##"<path id="error-interval" class="interval-band" d="{path}" fill="#555" fill-opacity="0.22" stroke="none"><title>{}</title></path>"##,
        escape(&band.title)
    );
}

/// The distribution of sub-trajectory errors: 20 bins, each coloured by its class.
pub(crate) fn histogram(
    errors: &[f64],
    thresholds: Thresholds,
    scale: f64,
    x_label: &str,
) -> String {
    let (w, h) = (420.0, 240.0);
    let max = errors.iter().copied().fold(thresholds.high, f64::max) * 1.02;
    const BINS: usize = 20;
    let width = max / BINS as f64;
    let mut counts = [0usize; BINS];
    for e in errors {
        counts[((e / width) as usize).min(BINS - 1)] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(1).max(1) as f64;
    let frame = Frame {
        w,
        h,
        x0: 0.0,
        x1: max * scale,
        y1: top,
    };
    let mut svg = format!(
        r#"<svg id="error-histogram" xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" aria-label="distribution of sub-trajectory errors">"#
    );
    frame.axes(&mut svg, x_label, "sub-trajectories", 1.0);
    for (i, c) in counts.iter().enumerate() {
        let lo = i as f64 * width;
        let colour = match thresholds.classify(lo + width / 2.0) {
            sitar_core::ErrorClass::High => HIGH,
            sitar_core::ErrorClass::Medium => MEDIUM,
            _ => LOW,
        };
        let (xa, xb) = (frame.x(lo * scale), frame.x((lo + width) * scale));
        let _ = write!(
            svg,
            r#"<rect class="bin" x="{xa:.1}" y="{y:.1}" width="{bw:.1}" height="{bh:.1}" fill="{colour}"><title>{c}</title></rect>"#,
            y = frame.y(*c as f64),
            bw = (xb - xa - 1.0).max(0.5),
            bh = frame.y(0.0) - frame.y(*c as f64),
        );
    }
    svg.push_str("</svg>");
    svg
}

/// The estimate as trials arrived: mean and max window error after each published
/// estimate (`(trials, mean, max)`, in the results' unit), over the class bands.
pub(crate) fn history(
    points: &[(f64, f64, f64)],
    thresholds: Thresholds,
    scale: f64,
    y_label: &str,
) -> String {
    let (w, h) = (420.0, 240.0);
    let x0 = points.iter().map(|p| p.0).fold(f64::MAX, f64::min);
    let x1 = points.iter().map(|p| p.0).fold(f64::MIN, f64::max);
    let top = points
        .iter()
        .map(|p| p.2)
        .fold(thresholds.high * 1.25, f64::max);
    let frame = Frame {
        w,
        h,
        x0,
        x1: x1.max(x0 + 1.0),
        y1: top,
    };
    let mut svg = format!(
        r#"<svg id="history-chart" xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" aria-label="the estimate as trials arrived">"#
    );
    frame.class_bands(&mut svg, thresholds);
    frame.axes(&mut svg, "trials received", y_label, scale);
    for (id, pick, colour, dash) in [
        ("history-mean", 1, "#222", ""),
        ("history-max", 2, HIGH, r#" stroke-dasharray="5 3""#),
    ] {
        let value = |p: &(f64, f64, f64)| if pick == 1 { p.1 } else { p.2 };
        let mut path = String::new();
        for (i, p) in points.iter().enumerate() {
            let op = if i == 0 { 'M' } else { 'L' };
            let _ = write!(path, "{op}{:.1} {:.1}", frame.x(p.0), frame.y(value(p)));
        }
        let _ = write!(
            svg,
            r#"<path id="{id}" d="{path}" fill="none" stroke="{colour}" stroke-width="1.5"{dash}/>"#
        );
        for p in points {
            let _ = write!(
                svg,
                r#"<circle class="{id}" cx="{:.1}" cy="{:.1}" r="2.5" fill="{colour}"><title>{} trials: {}</title></circle>"#,
                frame.x(p.0),
                frame.y(value(p)),
                p.0,
                trim(value(p) * scale)
            );
        }
    }
    let _ = write!(
        svg,
        r##"<text x="{x:.1}" y="{y:.1}" font-size="11" text-anchor="end">— mean  - - max window error</text>"##,
        x = w - RIGHT - 4.0,
        y = TOP + 12.0
    );
    svg.push_str("</svg>");
    svg
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Marker labels at nearby times never overlap: each text's box ends before the next
    /// one on its row starts.
    #[test]
    fn marker_labels_never_overlap() {
        let t = Thresholds {
            medium: 0.05,
            high: 0.1,
        };
        let subs: Vec<(f64, f64, Option<f64>)> = (0..100)
            .map(|i| (f64::from(i) * 0.3, f64::from(i + 1) * 0.3, Some(0.06)))
            .collect();
        // M2 and M3 at the same moment, M4 just after, then ten more close together.
        let mut markers = vec![(1, 2.0), (2, 9.0), (3, 9.0), (4, 9.1)];
        markers.extend((5..15).map(|n| (n, 20.0 + 0.05 * n as f64)));
        let svg = error_over_time(&subs, t, &markers, 100.0, "error (cm)", None);
        let mut boxes: Vec<(f64, f64, f64)> = Vec::new();
        for text in svg.split(r#"<text class="marker-label" "#).skip(1) {
            let number = |key: &str| -> f64 {
                let at = text.find(&format!("{key}=\"")).unwrap() + key.len() + 2;
                text[at..text[at..].find('"').unwrap() + at]
                    .parse()
                    .unwrap()
            };
            let label = &text[text.find('>').unwrap() + 1..text.find("</text>").unwrap()];
            boxes.push((number("x"), number("x") + label_width(label), number("y")));
        }
        assert!(boxes.len() >= 4 && boxes.len() < markers.len(), "{boxes:?}");
        for (i, a) in boxes.iter().enumerate() {
            for b in &boxes[i + 1..] {
                let same_row = (a.2 - b.2).abs() < 1.0;
                assert!(
                    !same_row || a.1 <= b.0 || b.1 <= a.0,
                    "{a:?} overlaps {b:?}"
                );
            }
        }
        // Every marker keeps its line and its name as a tooltip.
        assert_eq!(svg.matches(r#"class="marker-time""#).count(), markers.len());
        assert!(svg.contains("<title>M14</title>"));
    }

    #[test]
    fn the_interval_band_runs_between_the_bounds_and_breaks_at_gaps() {
        let t = Thresholds {
            medium: 0.05,
            high: 0.1,
        };
        let subs = [
            (0.0, 1.0, Some(0.1)),
            (1.0, 2.0, Some(0.2)),
            (2.0, 3.0, None),
            (3.0, 4.0, Some(0.1)),
        ];
        let intervals = [Some((0.05, 0.3)), Some((0.1, 0.4)), None, Some((0.05, 0.3))];
        let band = Band {
            intervals: &intervals,
            title: "80 % interval (calibration <lab>)".into(),
        };
        let svg = error_over_time(&subs, t, &[], 100.0, "error (cm)", Some(&band));
        let d = svg
            .split(r#"id="error-interval" class="interval-band" d=""#)
            .nth(1)
            .unwrap();
        let d = &d[..d.find('"').unwrap()];
        // Two runs, each closed.
        assert_eq!(d.matches('M').count(), 2, "{d}");
        assert_eq!(d.matches('Z').count(), 2, "{d}");
        // The chart reaches the highest upper bound (40 cm) at its top edge.
        assert!(d.contains(&format!(" {TOP:.1}L")), "{d}");
        assert!(svg.contains("calibration &lt;lab&gt;"), "{svg}");
        // The band is drawn behind the error line.
        assert!(svg.find("error-interval").unwrap() < svg.find("error-line").unwrap());
        // Without a band the chart is as before.
        let plain = error_over_time(&subs, t, &[], 100.0, "error (cm)", None);
        assert!(!plain.contains("interval"));
    }

    #[test]
    fn ticks_are_round() {
        assert_eq!(tick_step(10.0, 5.0), 2.0);
        assert_eq!(tick_step(0.3, 4.0), 0.1);
        assert_eq!(tick_step(700.0, 6.0), 200.0);
    }

    #[test]
    fn the_history_chart_has_one_point_per_estimate_on_its_axes() {
        let t = Thresholds {
            medium: 0.05,
            high: 0.1,
        };
        let svg = history(
            &[(2.0, 0.08, 0.3), (3.0, 0.06, 0.2), (5.0, 0.04, 0.1)],
            t,
            100.0,
            "error (cm)",
        );
        assert_eq!(svg.matches(r#"class="history-mean""#).count(), 3);
        assert_eq!(svg.matches(r#"class="history-max""#).count(), 3);
        assert!(svg.contains("<title>5 trials: 4</title>"), "{svg}");
        // The first estimate sits on the left edge, the last on the right one; the largest
        // max (30 cm) on the top edge.
        assert!(
            svg.contains(&format!(r#"id="history-max" d="M{LEFT:.1} {TOP:.1}"#)),
            "{svg}"
        );
        assert!(svg.contains(&format!("L{:.1} ", 420.0 - RIGHT)), "{svg}");
    }

    #[test]
    fn a_long_walk_is_grouped_keeping_each_groups_worst() {
        let subs: Vec<(f64, f64, Option<f64>)> = (0..39_000)
            .map(|i| {
                let t = f64::from(i) / 3.0;
                let e = if i % 7 == 0 {
                    None
                } else {
                    Some(f64::from(i % 100) / 1000.0)
                };
                (t, t + 1.0 / 3.0, e)
            })
            .collect();
        let steps = grouped(&subs);
        assert!(steps.len() <= MAX_CHART_STEPS, "{}", steps.len());
        assert_eq!(steps[0].0, 0.0);
        assert_eq!(steps.last().unwrap().1, subs.last().unwrap().1);
        // Groups of 39: each holds an i % 100 == 99 or reaches 0.099 only where it does.
        let max_all = steps.iter().filter_map(|s| s.2).fold(0.0, f64::max);
        assert_eq!(max_all, 0.099);
        let short = &subs[..500];
        assert_eq!(grouped(short), short.to_vec());
        let t = Thresholds {
            medium: 0.05,
            high: 0.1,
        };
        let svg = error_over_time(&subs, t, &[], 100.0, "error (cm)", None);
        assert!(svg.len() < 120_000, "{} bytes", svg.len());
        // With an interval per sub-trajectory: the band is grouped alike, still bounded.
        let intervals: Vec<Option<(f64, f64)>> = subs
            .iter()
            .map(|s| s.2.map(|e| (e * 0.5, e * 2.0)))
            .collect();
        let band = Band {
            intervals: &intervals,
            title: "80 % interval".into(),
        };
        let banded = error_over_time(&subs, t, &[], 100.0, "error (cm)", Some(&band));
        assert!(banded.len() < 2 * 120_000, "{} bytes", banded.len());
        assert!(banded.contains(r#"id="error-interval""#));
    }

    #[test]
    fn the_histogram_counts_every_error() {
        let t = Thresholds {
            medium: 0.05,
            high: 0.1,
        };
        let svg = histogram(&[0.01, 0.02, 0.07, 0.5], t, 100.0, "error (cm)");
        let total: usize = svg
            .split("<title>")
            .skip(1)
            .map(|s| s.split('<').next().unwrap().parse::<usize>().unwrap())
            .sum();
        assert_eq!(total, 4);
    }
}
