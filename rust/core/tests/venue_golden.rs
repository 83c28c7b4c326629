//! The venue map against an independent numpy/scipy computation
//! (`scripts/golden/make_venue_goldens.py` wrote `tests/golden/venue/`): five sessions in
//! different world frames and both conventions, one with results in degrees, one never
//! fully tracking the anchor.
#![allow(missing_docs)]

use sitar_core::Convention;
use sitar_core::venue::{
    Contribution, MapBuilder, SessionFiles, VenueMap, VenueSession, VenueSpec, build_map,
};

fn dir() -> String {
    format!("{}/tests/golden/venue", env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &str) -> String {
    std::fs::read_to_string(format!("{}/{path}", dir())).unwrap()
}

/// The venue and each session's contribution, from the golden files.
fn venue() -> (VenueSpec, Vec<Contribution>) {
    let spec: serde_json::Value = serde_json::from_str(&read("spec.json")).unwrap();
    let convention =
        |v: &serde_json::Value| -> Convention { serde_json::from_value(v.clone()).unwrap() };
    let venue = VenueSpec {
        id: spec["id"].as_str().unwrap().into(),
        name: spec["name"].as_str().unwrap().into(),
        anchor: spec["anchor"].as_str().unwrap().into(),
        cell_m: spec["cell_m"].as_f64().unwrap(),
        convention: convention(&spec["convention"]),
    };
    let mut contributions = Vec::new();
    for s in spec["sessions"].as_array().unwrap() {
        let id = s["id"].as_str().unwrap();
        let (anchors, trajectory, subs, results) = (
            read(&format!("{id}/anchors.csv")),
            read(&format!("{id}/trajectory.txt")),
            read(&format!("{id}/subtrajectories.csv")),
            read(&format!("{id}/results.json")),
        );
        let files = SessionFiles {
            session: id,
            convention: convention(&s["convention"]),
            anchors_csv: Some(&anchors),
            trajectory_txt: Some(&trajectory),
            subtrajectories_csv: Some(&subs),
            results_json: Some(&results),
        };
        contributions.push(Contribution::from_files(&files, &venue.anchor).unwrap());
    }
    (venue, contributions)
}

fn close(a: f64, b: f64, what: &str) {
    assert!((a - b).abs() <= 1e-12, "{what}: {a} vs {b}");
}

fn assert_same_map(ours: &VenueMap, reference: &VenueMap) {
    assert_eq!(
        (
            &ours.id,
            &ours.name,
            &ours.anchor,
            ours.convention,
            &ours.unit
        ),
        (
            &reference.id,
            &reference.name,
            &reference.anchor,
            reference.convention,
            &reference.unit
        )
    );
    assert_eq!(ours.sessions.len(), reference.sessions.len());
    for (a, b) in ours.sessions.iter().zip(&reference.sessions) {
        match (a, b) {
            (
                VenueSession::Aligned {
                    id,
                    observations,
                    position_spread_m,
                    heading_spread_deg,
                    subtrajectories,
                    ..
                },
                VenueSession::Aligned {
                    id: id2,
                    observations: o2,
                    position_spread_m: p2,
                    heading_spread_deg: h2,
                    subtrajectories: s2,
                    ..
                },
            ) => {
                assert_eq!((id, observations, subtrajectories), (id2, o2, s2));
                close(*position_spread_m, *p2, "position spread");
                close(*heading_spread_deg, *h2, "heading spread");
            }
            _ => assert_eq!(a, b),
        }
    }
    assert_eq!(ours.cells.len(), reference.cells.len());
    for (i, (a, b)) in ours.cells.iter().zip(&reference.cells).enumerate() {
        let what = format!("cell {i} {:?}", b.center);
        for k in 0..3 {
            close(a.center[k], b.center[k], &what);
        }
        close(a.error_m, b.error_m, &what);
        assert_eq!(
            (a.kind, a.sessions, a.subtrajectories, a.class, a.directions),
            (b.kind, b.sessions, b.subtrajectories, b.class, b.directions),
            "{what}"
        );
    }
}

#[test]
fn the_map_matches_the_numpy_reference() {
    let (spec, contributions) = venue();
    // s1…s3 in the map (s2 in ARCore's convention, mirrored), s4 in degrees, s5 never full.
    assert!(matches!(
        contributions[1],
        Contribution::InMap {
            convention: Convention::Arcore,
            ..
        }
    ));
    assert!(
        matches!(&contributions[3], Contribution::Excluded { reason, .. } if reason.contains("angle_deg"))
    );
    assert!(
        matches!(&contributions[4], Contribution::NotAligned { reason, .. } if reason.contains("never with full"))
    );
    for min_sessions in [1, 2] {
        let reference = VenueMap::from_json(&read(&format!("map_min{min_sessions}.json"))).unwrap();
        // 226 and 17 cells (cells centred on multiples of cell_m).
        assert!(reference.cells.len() >= 15, "a venue worth comparing");
        assert_same_map(&build_map(&spec, &contributions, min_sessions), &reference);
    }
}

#[test]
fn the_incremental_builder_reaches_the_same_map_by_any_route() {
    let (spec, contributions) = venue();
    let reference = VenueMap::from_json(&read("map_min1.json")).unwrap();
    let mut builder = MapBuilder::new(spec.clone());
    // s3 first, a map in between, s1 twice (replaced in place), s2 added, removed, re-added.
    builder.add(&contributions[0]);
    builder.add(&contributions[2]);
    let _ = builder.map(1);
    builder.add(&contributions[0]);
    builder.add(&contributions[1]);
    let _ = builder.map(2);
    assert!(builder.remove("s2"));
    assert!(!builder.remove("s2"));
    let without_s2 = builder.map(1);
    assert!(without_s2.cells.len() < reference.cells.len());
    builder.add(&contributions[1]);
    builder.add(&contributions[3]);
    builder.add(&contributions[4]);
    let mut map = builder.map(1);
    // The order of the session list follows the adds (s1, s3, s2, …): compare cells, and
    // the sessions as a set.
    let key = |s: &VenueSession| match s {
        VenueSession::Aligned { id, .. } | VenueSession::NotAligned { id, .. } => id.clone(),
    };
    map.sessions.sort_by_key(key);
    assert_same_map(&map, &reference);
}
