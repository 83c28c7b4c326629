//! The venue map as GLB: one named node per cell at its centre in glTF's frame, class
//! materials that blend, and no error or warning from the Khronos glTF validator
//! (npm `gltf-validator`, pinned in `tools/npm`).
#![allow(missing_docs)]

use sitar_core::Convention;
use sitar_core::venue::{CellKind, VenueMap};
use sitar_scene::{PATH_BOX_SHARE, SURFACE_TILE_SHARE, venue_to_glb};
use support::document;

mod support;

/// A map with cells of every class and both kinds.
fn map(convention: Convention) -> VenueMap {
    let mut cells = Vec::new();
    for i in 0..12 {
        let error = [0.01, 0.07, 0.2][i % 3];
        let kind = if i % 2 == 0 { "path" } else { "surface" };
        let class = ["low", "medium", "high"][i % 3];
        cells.push(format!(
            r#"{{"center":[{},{},{}],"kind":"{kind}","sessions":{},"subtrajectories":{},"error_m":{error},"class":"{class}","directions":[1,0,0,2,0,0,0,{i}]}}"#,
            0.25 * i as f64 + 0.125,
            1.375,
            -0.5 * i as f64 - 0.125,
            1 + i % 3,
            3 + i
        ));
    }
    let json = format!(
        r#"{{"id":"v0123456789abcdef","name":"Hall","anchor":"hall-a","cell_m":0.25,"convention":"{}","unit":"m","sessions":[],"cells":[{}]}}"#,
        convention.name(),
        cells.join(",")
    );
    VenueMap::from_json(&json).unwrap()
}

fn children<'a>(
    doc: &'a serde_json::Value,
    node: &'a serde_json::Value,
) -> Vec<&'a serde_json::Value> {
    let nodes = doc["nodes"].as_array().unwrap();
    node["children"]
        .as_array()
        .map(|c| {
            c.iter()
                .map(|i| &nodes[i.as_u64().unwrap() as usize])
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn cells_are_named_nodes_at_their_centres_in_gltf_frame() {
    for convention in [Convention::Unity, Convention::Arcore] {
        let map = map(convention);
        let doc = document(&venue_to_glb(&map).unwrap());
        let nodes = doc["nodes"].as_array().unwrap();
        let root = &nodes[doc["scenes"][0]["nodes"][0].as_u64().unwrap() as usize];
        assert_eq!(root["name"], "sitar_venue");
        assert_eq!(root["extras"]["source_convention"], convention.name());
        let top = children(&doc, root);
        let names: Vec<&str> = top.iter().map(|n| n["name"].as_str().unwrap()).collect();
        assert_eq!(names, ["anchor", "surface_cells", "path_cells"]);
        let (surface, path) = (children(&doc, top[1]), children(&doc, top[2]));
        let expected = |kind| map.cells.iter().filter(move |c| c.kind == kind);
        assert_eq!(surface.len(), expected(CellKind::Surface).count());
        assert_eq!(path.len(), expected(CellKind::Path).count());
        // glTF is right-handed +Y up: Unity's z is negated, ARCore's kept.
        let flip = if convention == Convention::Unity {
            -1.0
        } else {
            1.0
        };
        let materials = doc["materials"].as_array().unwrap();
        let meshes = doc["meshes"].as_array().unwrap();
        for (nodes, kind, share) in [
            (&surface, CellKind::Surface, SURFACE_TILE_SHARE),
            (&path, CellKind::Path, PATH_BOX_SHARE),
        ] {
            for (i, (node, cell)) in nodes.iter().zip(expected(kind)).enumerate() {
                let prefix = if kind == CellKind::Surface {
                    "surface_cell"
                } else {
                    "path_cell"
                };
                assert_eq!(node["name"], format!("{prefix}_{i}"));
                let t: Vec<f64> = node["translation"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_f64().unwrap())
                    .collect();
                let c = cell.center;
                assert!(
                    (t[0] - c[0]).abs() < 1e-6
                        && (t[1] - c[1]).abs() < 1e-6
                        && (t[2] - flip * c[2]).abs() < 1e-6,
                    "{t:?} {c:?}"
                );
                assert!((node["scale"][0].as_f64().unwrap() - share * map.cell_m).abs() < 1e-6);
                assert_eq!(node["extras"]["class"], cell.class.name());
                assert_eq!(node["extras"]["error_m"], cell.error_m);
                assert_eq!(node["extras"]["directions"][7], cell.directions[7]);
                let mesh = &meshes[node["mesh"].as_u64().unwrap() as usize];
                let material =
                    &materials[mesh["primitives"][0]["material"].as_u64().unwrap() as usize];
                assert_eq!(material["name"], format!("{prefix}_{}", cell.class.name()));
                assert_eq!(material["alphaMode"], "BLEND");
            }
        }
    }
}

#[test]
fn an_empty_map_is_still_a_scene_and_huge_coordinates_are_errors() {
    let mut empty = map(Convention::Unity);
    empty.cells.clear();
    let doc = document(&venue_to_glb(&empty).unwrap());
    assert_eq!(doc["nodes"].as_array().unwrap().len(), 4);
    let mut huge = map(Convention::Unity);
    huge.cells[3].center[1] = 1e300;
    let e = venue_to_glb(&huge).unwrap_err();
    assert!(e.to_string().contains("cell center"), "{e}");
}

#[test]
fn the_khronos_validator_finds_no_errors_in_a_venue_map() {
    let mut empty = map(Convention::Arcore);
    empty.cells.clear();
    support::assert_khronos_clean(&[
        ("unity", venue_to_glb(&map(Convention::Unity)).unwrap()),
        ("arcore", venue_to_glb(&map(Convention::Arcore)).unwrap()),
        ("empty", venue_to_glb(&empty).unwrap()),
    ]);
}
