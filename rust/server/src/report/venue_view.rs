//! The venue report's 3-D view data (`venue-data` in the page, drawn by
//! `assets/venue_view.js`): the map's cells and every aligned session's path in glTF's frame,
//! as `map.glb` places them (`sitar_scene::venue_to_glb`: right-handed, +Y up, metres, the
//! anchor at the origin; a `unity` venue's z is mirrored). Bounded for any venue: at most
//! [`MAX_CELLS`] cells of each kind (the worst kept first) and [`MAX_PATH_POINTS`] path points
//! in all, thinned evenly per session.

use glam::DVec3;
use serde_json::{Value, json};
use sitar_core::Convention;
use sitar_core::venue::{CellKind, Contribution, VenueMap};

use crate::report::thinning::thin;

/// Most cells of one kind drawn (a 400 m² hall of 0.25 m cells, walls 3 m high, has ~20 000).
pub(crate) const MAX_CELLS: usize = 50_000;
/// Most path points drawn, over all sessions.
pub(crate) const MAX_PATH_POINTS: usize = 60_000;
/// Most path points drawn for one session.
const MAX_POINTS_PER_SESSION: usize = 2_000;

/// Rounded to the millimetre: the JSON stays short, the drawing the same.
fn mm(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

/// The 3-D view's data for `map`, built from `contributions`.
pub(crate) fn view_data(map: &VenueMap, contributions: &[Contribution]) -> Value {
    let to_gltf = |p: DVec3| map.convention.convert_vector(p, Convention::Arcore);
    let flat = |p: DVec3| {
        let p = to_gltf(p);
        [mm(p.x), mm(p.y), mm(p.z)]
    };
    let kind = |wanted: CellKind| {
        let mut cells: Vec<_> = map.cells.iter().filter(|c| c.kind == wanted).collect();
        let total = cells.len();
        // The worst are the ones a reader looks for: they are kept when a venue is too big.
        cells.sort_by(|a, b| b.error_m.total_cmp(&a.error_m));
        cells.truncate(MAX_CELLS);
        let centres: Vec<f64> = cells
            .iter()
            .flat_map(|c| flat(DVec3::from_array(c.center)))
            .collect();
        let classes: Vec<u8> = cells.iter().map(|c| c.class as u8).collect();
        (
            json!({"centres": centres, "classes": classes}),
            cells.len(),
            total,
        )
    };
    let (surface, surface_shown, surface_total) = kind(CellKind::Surface);
    let (path, path_shown, path_total) = kind(CellKind::Path);
    let drawn: Vec<&Contribution> = contributions
        .iter()
        .filter(|c| c.samples().len() > 1)
        .collect();
    let budget = (MAX_PATH_POINTS / drawn.len().max(1)).clamp(2, MAX_POINTS_PER_SESSION);
    let (mut shown, mut total) = (0, 0);
    let paths: Vec<Vec<f64>> = drawn
        .iter()
        .map(|c| {
            let samples = c.samples();
            total += samples.len();
            let kept = thin(samples.len(), budget);
            shown += kept.len();
            kept.iter()
                .flat_map(|&i| flat(samples[i].position))
                .collect()
        })
        .collect();
    json!({
        "cell_m": map.cell_m,
        "surface_share": sitar_scene::SURFACE_TILE_SHARE,
        "path_share": sitar_scene::PATH_BOX_SHARE,
        "surface": surface,
        "path": path,
        "paths": paths,
        "downsampled": {
            "surface_cells": {"shown": surface_shown, "total": surface_total},
            "path_cells": {"shown": path_shown, "total": path_total},
            "path_points": {"shown": shown, "total": total},
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(convention: &str, cells: usize) -> VenueMap {
        let cells: Vec<String> = (0..cells)
            .map(|i| {
                let (kind, class) = if i % 2 == 0 { ("surface", "high") } else { ("path", "low") };
                format!(
                    r#"{{"center":[{i},1.0,2.0],"kind":"{kind}","sessions":1,"subtrajectories":1,"error_m":{},"class":"{class}","directions":[0,0,0,0,0,0,0,0]}}"#,
                    i as f64 / 100.0
                )
            })
            .collect();
        VenueMap::from_json(&format!(
            r#"{{"id":"v0123456789abcdef","name":"Hall","anchor":"a","cell_m":0.25,"convention":"{convention}","unit":"m","sessions":[],"cells":[{}]}}"#,
            cells.join(",")
        ))
        .unwrap()
    }

    #[test]
    fn cells_are_in_gltf_frame_by_kind_with_class_codes() {
        let unity = view_data(&map("unity", 2), &[]);
        assert_eq!(unity["surface"]["centres"], json!([0.0, 1.0, -2.0]));
        assert_eq!(unity["surface"]["classes"], json!([3]));
        assert_eq!(unity["path"]["centres"], json!([1.0, 1.0, -2.0]));
        assert_eq!(unity["path"]["classes"], json!([1]));
        let arcore = view_data(&map("arcore", 2), &[]);
        assert_eq!(arcore["surface"]["centres"], json!([0.0, 1.0, 2.0]));
        assert_eq!(arcore["paths"], json!([]));
    }

    #[test]
    fn a_huge_venue_is_drawn_bounded_worst_first() {
        let data = view_data(&map("arcore", 2 * MAX_CELLS + 10), &[]);
        let classes = data["surface"]["classes"].as_array().unwrap();
        assert_eq!(classes.len(), MAX_CELLS);
        assert_eq!(
            data["downsampled"]["surface_cells"],
            json!({"shown": MAX_CELLS, "total": MAX_CELLS + 5})
        );
        // The worst surface cell (the last one, error highest) comes first.
        let x = data["surface"]["centres"][0].as_f64().unwrap();
        assert_eq!(x, (2 * MAX_CELLS + 8) as f64);
    }
}
