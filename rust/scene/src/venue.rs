//! A venue map (`map.json`) as a GLB (`GET /v1/venues/{id}/map.glb`): surface cells as
//! translucent tiles coloured by class, path cells as small faint boxes, the anchor at the
//! origin, in the venue frame.

use glam::DVec3;
use gltf::json;
use sitar_core::Convention;
use sitar_core::venue::{CellKind, VenueMap};

use crate::Error;
use crate::builder::{Paint, ShapeKind, Writer, extras, f32_of, vec3};

/// A surface tile's edge as a share of the cell's (a gap shows where cells meet).
pub const SURFACE_TILE_SHARE: f64 = 0.9;
/// A path box's edge as a share of the cell's: a faint trail, not a wall.
pub const PATH_BOX_SHARE: f64 = 0.3;
/// The anchor node's size (m): an A4 sheet, 5 mm thick.
const ANCHOR_SIZE: [f32; 3] = [0.297, 0.21, 0.005];

/// The venue map as a binary glTF 2.0 file.
///
/// One scene, root node `sitar_venue` (extras: `id`, `name`, `anchor`, `cell_m`,
/// `source_convention`), children: `anchor` (a sheet-sized box at the origin), `surface_cells`
/// and `path_cells`, one node per cell named `surface_cell_i` / `path_cell_i` in the map's
/// order, a unit cube scaled to [`SURFACE_TILE_SHARE`] / [`PATH_BOX_SHARE`] of `cell_m`, its
/// extras the cell's `center` (venue frame, the map's convention), `error_m`, `class`,
/// `sessions`, `subtrajectories` and `directions`. Materials `surface_cell_<class>` (alpha
/// 0.55) and `path_cell_<class>` (alpha 0.25) blend. glTF is right-handed with +Y up:
/// an `arcore` map is written as it is, a `unity` map with `z → −z` (the same physical
/// place, as [`crate::to_glb`] does for sessions).
///
/// A coordinate too large for glTF's f32 is an [`Error::Encode`] naming it.
pub fn venue_to_glb(map: &VenueMap) -> Result<Vec<u8>, Error> {
    let to_gltf = |p: DVec3| map.convention.convert_vector(p, Convention::Arcore);
    let mut w = Writer::new();
    let mut groups: [Vec<json::Index<json::Node>>; 2] = [Vec::new(), Vec::new()];
    for cell in &map.cells {
        let (kind, share, paint) = match cell.kind {
            CellKind::Surface => (
                "surface_cell",
                SURFACE_TILE_SHARE,
                Paint::SurfaceCell(cell.class),
            ),
            CellKind::Path => ("path_cell", PATH_BOX_SHARE, Paint::PathCell(cell.class)),
        };
        let group = &mut groups[usize::from(cell.kind == CellKind::Path)];
        let edge = f32_of(share * map.cell_m, "cell_m")?;
        let mesh = w.mesh(ShapeKind::Cube, paint);
        let node = w.node(json::Node {
            name: Some(format!("{kind}_{}", group.len())),
            mesh: Some(mesh),
            translation: Some(vec3(
                to_gltf(DVec3::from_array(cell.center)),
                "cell center",
            )?),
            scale: Some([edge; 3]),
            extras: extras(serde_json::json!({
                "center": cell.center,
                "error_m": cell.error_m,
                "class": cell.class.name(),
                "sessions": cell.sessions,
                "subtrajectories": cell.subtrajectories,
                "directions": cell.directions,
            }))?,
            ..Default::default()
        });
        group.push(node);
    }
    let anchor_mesh = w.mesh(ShapeKind::Cube, Paint::Anchor);
    let anchor = w.node(json::Node {
        name: Some("anchor".into()),
        mesh: Some(anchor_mesh),
        scale: Some(ANCHOR_SIZE),
        extras: extras(serde_json::json!({"anchor": map.anchor}))?,
        ..Default::default()
    });
    let [surface, path] = groups;
    let children = vec![
        anchor,
        w.group("surface_cells", surface),
        w.group("path_cells", path),
    ];
    let root = w.node(json::Node {
        name: Some("sitar_venue".into()),
        children: Some(children),
        extras: extras(serde_json::json!({
            "id": map.id,
            "name": map.name,
            "anchor": map.anchor,
            "cell_m": map.cell_m,
            "source_convention": map.convention.name(),
        }))?,
        ..Default::default()
    });
    w.finish(root)
}
