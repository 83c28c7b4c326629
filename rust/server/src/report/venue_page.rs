//! The venue report (`GET /v1/venues/{id}/report`): a static top view of path and surface
//! cells coloured by class with every aligned session's path, the sessions with their
//! alignment spread, the problem regions (surface cells with high error seen by ≥ 2
//! sessions, worst first, with the likely causes the sessions' evidence names), and the
//! coverage of each surface cell by direction; and the 3-D view of the same cells and paths
//! (`venue_view`, drawn by the report's bundled script). Thumbnails are the reader's own
//! sessions' only (an admin's: all). As one file (`?download=1`) the page carries its
//! script, style, view data and thumbnails inline.

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use serde_json::{Value, json};
use sitar_core::ErrorClass;
use sitar_core::venue::{CellKind, Contribution, VenueMap, VenueSession};

use crate::error::Error;
use crate::ingest::evidence::{EvidenceFiles, EvidenceRow};
use crate::model::{Caller, Session, Venue};
use crate::report::templates;
use crate::storage::{BlobStore, MetadataStore};

/// Most problem regions listed, and thumbnails per region.
const MAX_REGIONS: usize = 20;
const THUMBNAILS_PER_REGION: usize = 3;
/// Most surface cells in the coverage table (worst first).
const MAX_COVERAGE_ROWS: usize = 200;
/// The top view's drawing size (px) and the most path points per session drawn.
const VIEW_PX: f64 = 640.0;
const PATH_POINTS: usize = 2_000;

const INLINE_CSS: &str = include_str!("../../assets/site.css");

/// Where a camera looking into sector `k` stands: the opposite side, in compass words
/// (venue +X is "east", counter-clockwise seen from above).
fn seen_from(sector: usize) -> &'static str {
    const SIDES: [&str; 8] = [
        "east",
        "north-east",
        "north",
        "north-west",
        "west",
        "south-west",
        "south",
        "south-east",
    ];
    SIDES[(sector + 4) % 8]
}

/// "seen only from the east", "seen from the east and north", "seen from 5 of 8 sides".
pub(crate) fn coverage_words(directions: &[u32; 8]) -> String {
    let sides: Vec<&str> = (0..8)
        .filter(|&k| directions[k] > 0)
        .map(seen_from)
        .collect();
    match sides.len() {
        0 => "no camera heading known".into(),
        1 => format!("seen only from the {}", sides[0]),
        2 | 3 => format!("seen from the {}", sides.join(" and the ")),
        n => format!("seen from {n} of 8 sides"),
    }
}

fn class_colour(class: ErrorClass) -> &'static str {
    match class {
        ErrorClass::Low => "#2f6fde",
        ErrorClass::Medium => "#e0b100",
        ErrorClass::High => "#d62728",
        _ => "#9a9a9a",
    }
}

fn centre_text(c: &[f64; 3]) -> String {
    format!("({:.2}, {:.2}, {:.2})", c[0], c[1], c[2])
}

/// The top view (x right, the third axis down the page), server-made SVG of numbers only.
fn top_view(map: &VenueMap, contributions: &[(Session, Contribution)]) -> String {
    let mut xs = Vec::new();
    let mut zs = Vec::new();
    for c in &map.cells {
        xs.push(c.center[0]);
        zs.push(c.center[2]);
    }
    for (_, c) in contributions {
        for s in c.samples() {
            xs.push(s.position.x);
            zs.push(s.position.z);
        }
    }
    let span = |v: &[f64]| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) }
    };
    let ((x0, x1), (z0, z1)) = (span(&xs), span(&zs));
    let pad = map.cell_m;
    let extent = (x1 - x0).max(z1 - z0).max(map.cell_m) + 2.0 * pad;
    let scale = VIEW_PX / extent;
    let px = |x: f64| (x - x0 + pad) * scale;
    let pz = |z: f64| (z - z0 + pad) * scale;
    let mut svg = format!(
        "<svg id=\"topview\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{VIEW_PX}\" height=\"{VIEW_PX}\" viewBox=\"0 0 {VIEW_PX} {VIEW_PX}\">"
    );
    let side = map.cell_m * scale;
    for c in &map.cells {
        let (x, y) = (px(c.center[0]) - side / 2.0, pz(c.center[2]) - side / 2.0);
        let colour = class_colour(c.class);
        let _ = match c.kind {
            CellKind::Path => write!(
                svg,
                "<rect x=\"{x:.1}\" y=\"{y:.1}\" width=\"{side:.1}\" height=\"{side:.1}\" fill=\"{colour}\" fill-opacity=\"0.55\"/>"
            ),
            CellKind::Surface => write!(
                svg,
                "<rect x=\"{x:.1}\" y=\"{y:.1}\" width=\"{side:.1}\" height=\"{side:.1}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"2\"/>"
            ),
        };
    }
    for (_, c) in contributions {
        let samples = c.samples();
        let step = samples.len().div_ceil(PATH_POINTS).max(1);
        let points: Vec<String> = samples
            .iter()
            .step_by(step)
            .map(|s| format!("{:.1},{:.1}", px(s.position.x), pz(s.position.z)))
            .collect();
        if points.len() > 1 {
            let _ = write!(
                svg,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"#555\" stroke-width=\"1\"/>",
                points.join(" ")
            );
        }
    }
    // The anchor: the venue origin.
    let _ = write!(
        svg,
        "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"4\" fill=\"#111\"/><text x=\"{:.1}\" y=\"{:.1}\" font-size=\"11\">anchor</text></svg>",
        px(0.0),
        pz(0.0),
        px(0.0) + 6.0,
        pz(0.0) - 6.0
    );
    svg
}

/// Everything the page needs.
pub(crate) struct VenueReport<'a> {
    pub db: &'a dyn MetadataStore,
    pub blobs: &'a dyn BlobStore,
    pub venue: &'a Venue,
    pub caller: &'a Caller,
    /// One file that opens from disk (thumbnails inline).
    pub standalone: bool,
}

impl VenueReport<'_> {
    /// The page's HTML.
    pub(crate) fn render(&self) -> Result<String, Error> {
        let (spec, contributions) =
            crate::venue::map::contributions(self.db, self.blobs, self.venue)?;
        let list: Vec<Contribution> = contributions.iter().map(|(_, c)| c.clone()).collect();
        let map = sitar_core::venue::build_map(&spec, &list, 1);
        let yours: HashMap<&str, bool> = contributions
            .iter()
            .map(|(s, _)| (s.id.as_str(), self.caller.may_see(s)))
            .collect();
        let sessions: Vec<Value> = map
            .sessions
            .iter()
            .map(|s| match s {
                VenueSession::Aligned {
                    id,
                    observations,
                    position_spread_m,
                    heading_spread_deg,
                    subtrajectories,
                    ..
                } => json!({
                    "id": id, "aligned": true, "yours": yours.get(id.as_str()) == Some(&true),
                    "observations": observations,
                    "position_spread": format!("{:.1} cm", position_spread_m * 100.0),
                    "heading_spread": format!("{heading_spread_deg:.1}°"),
                    "subtrajectories": subtrajectories, "reason": "",
                }),
                VenueSession::NotAligned { id, reason, .. } => json!({
                    "id": id, "aligned": false, "yours": yours.get(id.as_str()) == Some(&true),
                    "observations": "", "position_spread": "", "heading_spread": "",
                    "subtrajectories": 0, "reason": reason,
                }),
            })
            .collect();
        let mut surfaces: Vec<_> = map
            .cells
            .iter()
            .filter(|c| c.kind == CellKind::Surface)
            .collect();
        surfaces.sort_by(|a, b| b.error_m.total_cmp(&a.error_m));
        // Each session's evidence is read once, and only when one of its samples is in a region.
        let mut evidence = HashMap::new();
        let mut regions: Vec<Value> = Vec::new();
        for cell in surfaces
            .iter()
            .filter(|c| c.class == ErrorClass::High && c.sessions >= 2)
            .take(MAX_REGIONS)
        {
            regions.push(self.region(cell, &contributions, &mut evidence)?);
        }
        let coverage: Vec<Value> = surfaces
            .iter()
            .take(MAX_COVERAGE_ROWS)
            .map(|c| {
                json!({"centre": centre_text(&c.center), "class": c.class.name(),
                       "coverage": coverage_words(&c.directions)})
            })
            .collect();
        // `<` only occurs inside JSON strings, where `\u003c` means the same: no `</script`.
        let view = super::venue_view::view_data(&map, &list)
            .to_string()
            .replace('<', "\\u003c");
        let standalone = self.standalone;
        let script = if standalone {
            Some(super::page::inline_script()?)
        } else {
            None
        };
        templates::render(
            "venue.html",
            &json!({
                "id": map.id, "name": map.name, "anchor": map.anchor, "cell_m": map.cell_m,
                "convention": map.convention.name(), "cells": map.cells.len(),
                "sessions": sessions, "topview": top_view(&map, &contributions),
                "regions": regions, "coverage": coverage,
                "view": view,
                "css": standalone.then_some(INLINE_CSS),
                "script": script,
                "csp": standalone.then(super::page::standalone_csp),
            }),
        )
    }

    /// One problem region: where, how bad, from which sides, the likely causes the
    /// sessions' evidence gives for the sub-trajectories whose surface point is in it, and
    /// the reader's own thumbnails of them.
    fn region(
        &self,
        cell: &sitar_core::venue::VenueCell,
        contributions: &[(Session, Contribution)],
        evidence: &mut HashMap<String, Vec<EvidenceRow>>,
    ) -> Result<Value, Error> {
        // The map's own rule (`sitar_core::venue::cell_index`: ⌊p / cell_m + ½⌋ on each
        // axis; the centre's index too, as the centre is k·cell_m).
        let c = self.venue.cell_m;
        let index = |v: f64| sitar_core::venue::cell_index(v, c);
        let inside = |p: glam::DVec3| {
            index(p.x) == index(cell.center[0])
                && index(p.y) == index(cell.center[1])
                && index(p.z) == index(cell.center[2])
        };
        let mut causes: BTreeMap<String, usize> = BTreeMap::new();
        let mut thumbnails = Vec::new();
        for (session, contribution) in contributions {
            let files = EvidenceFiles {
                blobs: self.blobs,
                id: &session.id,
            };
            for sample in contribution.samples() {
                if !sample.surface.is_some_and(inside) {
                    continue;
                }
                if !evidence.contains_key(&session.id) {
                    let read = files.evidence_rows()?.unwrap_or_default();
                    evidence.insert(session.id.clone(), read);
                }
                let rows = evidence.get(&session.id).map_or(&[][..], Vec::as_slice);
                let k = sample.subtrajectory as usize;
                if let Some(row) = rows.get(k) {
                    for cause in &row.causes {
                        *causes.entry(cause.clone()).or_default() += 1;
                    }
                }
                if self.caller.may_see(session)
                    && thumbnails.len() < THUMBNAILS_PER_REGION
                    && files.has_thumbnail(k)
                {
                    thumbnails.push(if self.standalone {
                        let jpeg = files.read_thumbnail(k)?.unwrap_or_default();
                        format!("data:image/jpeg;base64,{}", BASE64.encode(jpeg))
                    } else {
                        format!("/v1/sessions/{}/subtrajectories/{k}/image.jpg", session.id)
                    });
                }
            }
        }
        let mut ranked: Vec<(String, usize)> = causes.into_iter().collect();
        ranked.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
        Ok(json!({
            "centre": centre_text(&cell.center),
            "error_cm": format!("{:.1}", cell.error_m * 100.0),
            "sessions": cell.sessions,
            "subtrajectories": cell.subtrajectories,
            "coverage": coverage_words(&cell.directions),
            "causes": ranked.iter().take(3)
                .map(|(c, n)| format!("{} ({n} of {})", c.replace('_', " "), cell.subtrajectories))
                .collect::<Vec<_>>(),
            "thumbnails": thumbnails,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coverage_is_told_from_the_side_the_cameras_stood() {
        let mut d = [0; 8];
        assert_eq!(coverage_words(&d), "no camera heading known");
        d[4] = 3; // looking west (sector 4): standing east of the surface
        assert_eq!(coverage_words(&d), "seen only from the east");
        d[6] = 1; // looking south: standing north
        assert_eq!(coverage_words(&d), "seen from the east and the north");
        d = [1; 8];
        assert_eq!(coverage_words(&d), "seen from 8 of 8 sides");
    }
}
