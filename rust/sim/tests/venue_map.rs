//! A venue map of simulated users' played sessions puts its problem cells on the room's hard
//! surfaces: the whole chain (phone files, trials, estimate, alignment, cells) against truth.

use sitar_core::Convention;
use sitar_core::venue::{VenueSession, VenueSpec, build_map};
use sitar_sim::Venue;

#[test]
fn three_users_map_finds_the_blank_wall_with_sane_precision_and_recall() {
    let venue = Venue::demo(3, 20.0, 30.0, 1000).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let contributions: Vec<_> = venue
        .users
        .iter()
        .map(|u| {
            let id = format!("s{:016x}", u.seed);
            u.contribution(&id, &venue.anchor.id, 6, &dir.path().join(&id))
                .unwrap()
        })
        .collect();
    let spec = VenueSpec {
        id: "v0000000000000001".into(),
        name: "demo room".into(),
        anchor: venue.anchor.id.clone(),
        cell_m: 0.25,
        convention: Convention::Arcore,
    };
    let map = build_map(&spec, &contributions, 1);
    assert_eq!(map.sessions.len(), 3);
    assert!(
        map.sessions
            .iter()
            .all(|s| matches!(s, VenueSession::Aligned { .. })),
        "{:?}",
        map.sessions
    );
    let score = venue.score_problem_cells(&map);
    println!("{score:?}");
    assert!(
        score.hard_surfaces_found.contains(&"blank wall".to_owned()),
        "{score:?}"
    );
    assert!(score.precision().unwrap() >= 0.6, "{score:?}");
    assert!(score.recall().unwrap() >= 0.6, "{score:?}");
    // The cells lie on the room's surfaces: aligned maps of different frames agree.
    for cell in map
        .cells
        .iter()
        .filter(|c| c.kind == sitar_core::venue::CellKind::Surface)
    {
        let truth = venue
            .truth_at(glam::DVec3::from_array(cell.center))
            .unwrap();
        assert!(
            truth.distance_m <= 0.25 * 3f64.sqrt() / 2.0 + 1e-9,
            "{cell:?}: {truth:?}"
        );
    }
}
