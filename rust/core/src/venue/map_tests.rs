//! Tests of a session's contribution and of the cells: analytic cases, bad files, and
//! proptests (a session moved by a known translation and heading lands in the same cells).

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, FRAC_PI_8, PI};
use std::fmt::Write as _;

use glam::{DQuat, DVec3};
use proptest::prelude::*;

use super::*;
use crate::{Convention, Error, ErrorClass, Pose};

/// A session recorded in a world frame where the anchor's centre is at `translation` and the
/// venue is turned by `heading` (numbers of `convention`), built from venue-frame camera
/// poses given in Unity's numbers (physical scene), one per logged pose.
struct Recorded {
    anchors: String,
    trajectory: String,
    subs: String,
    results: String,
}

const T0: i64 = 1_700_000_000_000_000_000;
const HALF_NS: i64 = 166_666_665; // 5 frames at 30 fps

/// `mid_poses[k]`: the venue-frame (Unity numbers) camera pose at sub-trajectory k's midpoint;
/// `surfaces[k]`: its surface point; `errors[k]`: the window error at its start (`None`: no
/// window). Start and end poses repeat the midpoint's.
fn record(
    convention: Convention,
    translation: DVec3,
    heading: f64,
    mid_poses: &[Pose],
    surfaces: &[Option<DVec3>],
    errors: &[Option<f64>],
) -> Recorded {
    let to_world = |p: Pose| -> Pose {
        let p = Convention::Unity.convert_pose(p, convention);
        let turn = DQuat::from_rotation_y(heading);
        Pose::new(turn * p.position + translation, turn * p.rotation)
    };
    let point_to_world = |p: DVec3| {
        DQuat::from_rotation_y(heading) * Convention::Unity.convert_vector(p, convention)
            + translation
    };
    let image = to_world(Pose::new(DVec3::ZERO, DQuat::from_rotation_x(FRAC_PI_2)));
    let anchors = anchors_csv(&[AnchorObservation {
        t_ns: T0,
        anchor: "a".into(),
        pose: image,
        tracking: Tracking::Full,
    }]);
    let mut trajectory = String::new();
    let mut subs = format!("{}\n", crate::subtrajectory_columns::HEADER);
    let mut results = String::from("start,error\n");
    for (k, pose) in mid_poses.iter().enumerate() {
        let world = to_world(*pose);
        let start = T0 + 2 * k as i64 * HALF_NS;
        if k == 0 {
            crate::tum::push_line(&mut trajectory, start, &world);
        }
        crate::tum::push_line(&mut trajectory, start + HALF_NS, &world);
        crate::tum::push_line(&mut trajectory, start + 2 * HALF_NS, &world);
        let _ = write!(
            subs,
            "{k},{start},{},{},",
            start + HALF_NS,
            start + 2 * HALF_NS
        );
        match surfaces[k] {
            Some(s) => {
                let s = point_to_world(s);
                let _ = writeln!(
                    subs,
                    "valid,1,2,1,1,0,0,1,0,0,-1,{},{},{},0,1,0,,",
                    s.x, s.y, s.z
                );
            }
            None => {
                let _ = writeln!(subs, "no_depth,1,2{}", ",".repeat(16));
            }
        }
        if let Some(e) = errors[k] {
            let _ = writeln!(results, "{start},{e}");
        }
    }
    Recorded {
        anchors,
        trajectory,
        subs,
        results,
    }
}

fn files<'a>(r: &'a Recorded, convention: Convention, session: &'a str) -> SessionFiles<'a> {
    SessionFiles {
        session,
        convention,
        anchors_csv: Some(&r.anchors),
        trajectory_txt: Some(&r.trajectory),
        subtrajectories_csv: Some(&r.subs),
        results_json: Some(&r.results),
    }
}

/// A camera at `p` looking (Unity: along +Z turned by `yaw` about +Y, i.e. at heading
/// 90° − yaw counter-clockwise from +X seen from above).
fn camera(p: DVec3, yaw: f64) -> Pose {
    Pose::new(p, DQuat::from_rotation_y(yaw))
}

fn spec(convention: Convention) -> VenueSpec {
    VenueSpec {
        id: "v0000000000000001".into(),
        name: "Hall".into(),
        anchor: "a".into(),
        cell_m: 0.5,
        convention,
    }
}

#[test]
fn sectors_are_half_open_and_counter_clockwise_from_x() {
    assert_eq!(sector_of(0.0), 0);
    assert_eq!(sector_of(FRAC_PI_8 - 1e-12), 0);
    assert_eq!(sector_of(FRAC_PI_8), 1);
    assert_eq!(sector_of(-FRAC_PI_8), 0);
    assert_eq!(sector_of(-FRAC_PI_8 - 1e-12), 7);
    assert_eq!(sector_of(FRAC_PI_2), 2);
    assert_eq!(sector_of(PI), 4);
    assert_eq!(sector_of(-PI + 1e-12), 4);
    assert_eq!(sector_of(-3.0 * FRAC_PI_4), 5);
    // North of east is counter-clockwise seen from above: Unity's +Z, ARCore's −Z.
    let north_unity = heading_seen_from_above(DVec3::Z, Convention::Unity).unwrap();
    let north_arcore = heading_seen_from_above(DVec3::NEG_Z, Convention::Arcore).unwrap();
    assert_eq!((north_unity, north_arcore), (FRAC_PI_2, FRAC_PI_2));
    assert_eq!(
        heading_seen_from_above(DVec3::NEG_Y, Convention::Unity),
        None
    );
}

#[test]
fn one_session_analytically() {
    // The venue turned by 90° and moved: a camera 1 m along venue +X looking along venue +Z
    // (north) at a wall 2 m away; a second looking along venue −X (west); a third without a
    // result window.
    let translation = DVec3::new(3.0, -1.0, 2.0);
    let mids = [
        camera(DVec3::new(1.1, 1.6, 0.2), 0.0),
        camera(DVec3::new(-0.3, 1.2, 0.7), -FRAC_PI_2),
        camera(DVec3::ZERO, 0.0),
    ];
    let surfaces = [Some(DVec3::new(1.1, 1.6, 2.2)), None, None];
    for convention in [Convention::Unity, Convention::Arcore] {
        let r = record(
            convention,
            translation,
            FRAC_PI_2,
            &mids,
            &surfaces,
            &[Some(0.12), Some(0.01), None],
        );
        let c = Contribution::from_files(&files(&r, convention, "s"), "a").unwrap();
        let Contribution::InMap { samples, .. } = &c else {
            panic!("{c:?}")
        };
        assert_eq!(samples.len(), 2);
        let mirror = |v: DVec3| Convention::Unity.convert_vector(v, convention);
        assert!((samples[0].position - mirror(mids[0].position)).length() < 1e-12);
        assert!((samples[0].surface.unwrap() - mirror(surfaces[0].unwrap())).length() < 1e-12);
        assert!((samples[0].heading_rad.unwrap() - FRAC_PI_2).abs() < 1e-12);
        assert_eq!(
            (samples[0].sector(), samples[1].sector()),
            (Some(2), Some(4))
        );
        assert_eq!((samples[0].error_m, samples[1].error_m), (0.12, 0.01));
        assert_eq!(samples[1].surface, None);

        let map = build_map(&spec(Convention::Unity), &[c], 1);
        // Path cells (−1, 2, 1) and (2, 3, 0) at 0.5 m, then the surface cell (2, 3, 4):
        // cells centred on multiples of 0.5 m.
        let centres: Vec<[f64; 3]> = map.cells.iter().map(|c| c.center).collect();
        assert_eq!(
            centres,
            [[-0.5, 1.0, 0.5], [1.0, 1.5, 0.0], [1.0, 1.5, 2.0]]
        );
        let kinds: Vec<CellKind> = map.cells.iter().map(|c| c.kind).collect();
        assert_eq!(kinds, [CellKind::Path, CellKind::Path, CellKind::Surface]);
        assert_eq!(map.cells[2].class, ErrorClass::High);
        assert_eq!(map.cells[2].directions, [0, 0, 1, 0, 0, 0, 0, 0]);
        assert_eq!(map.cells[0].directions, [0, 0, 0, 0, 1, 0, 0, 0]);
        assert!(matches!(
            map.sessions[0],
            VenueSession::Aligned {
                subtrajectories: 2,
                observations: 1,
                ..
            }
        ));
        assert_eq!(VenueMap::from_json(&map.to_json()).unwrap(), map);
    }
}

#[test]
fn cells_aggregate_sessions_and_min_sessions_drops_lonely_cells() {
    let p = DVec3::new(0.1, 0.1, 0.1);
    let one = |errors: &[Option<f64>], name: &str| {
        let r = record(
            Convention::Unity,
            DVec3::ZERO,
            0.0,
            &vec![camera(p, 0.0); errors.len()],
            &vec![None; errors.len()],
            errors,
        );
        Contribution::from_files(&files(&r, Convention::Unity, name), "a").unwrap()
    };
    let a = one(&[Some(0.01), Some(0.02), Some(0.03), Some(1.0)], "a");
    let b = one(&[Some(0.04), Some(0.05), Some(0.06)], "b");
    let c = one(&[Some(0.5)], "c");
    let far = {
        let r = record(
            Convention::Unity,
            DVec3::ZERO,
            0.0,
            &[camera(DVec3::splat(5.0), 0.0)],
            &[None],
            &[Some(0.3)],
        );
        Contribution::from_files(&files(&r, Convention::Unity, "far"), "a").unwrap()
    };
    let map = build_map(&spec(Convention::Unity), &[a, b, c, far], 2);
    assert_eq!(map.cells.len(), 1);
    let cell = &map.cells[0];
    assert_eq!((cell.sessions, cell.subtrajectories), (3, 8));
    // trim_mean of [0.01 … 0.06, 0.5, 1.0] cutting int(2.4) = 2 per end: mean of 0.03…0.06.
    assert!((cell.error_m - 0.045).abs() < 1e-15);
    assert_eq!(cell.class, ErrorClass::Low);
    assert_eq!(cell.directions, [0, 0, 8, 0, 0, 0, 0, 0]);
    assert_eq!(map.sessions.len(), 4);
}

#[test]
fn sessions_out_of_the_map_say_why() {
    let r = record(
        Convention::Unity,
        DVec3::ZERO,
        0.0,
        &[camera(DVec3::ZERO, 0.0)],
        &[None],
        &[Some(0.1)],
    );
    let reason = |f: SessionFiles<'_>| match Contribution::from_files(&f, "a").unwrap() {
        Contribution::NotAligned { reason, .. } => format!("not aligned: {reason}"),
        Contribution::Excluded { reason, .. } => format!("excluded: {reason}"),
        other => panic!("{other:?}"),
    };
    let base = files(&r, Convention::Unity, "s");
    assert!(
        reason(SessionFiles {
            anchors_csv: None,
            ..base
        })
        .contains("no anchors.csv")
    );
    assert!(
        reason(SessionFiles {
            results_json: None,
            ..base
        })
        .contains("excluded: it has no results")
    );
    assert!(
        reason(SessionFiles {
            trajectory_txt: None,
            ..base
        })
        .contains("no trajectory.txt")
    );
    let other = Contribution::from_files(&base, "b").unwrap();
    assert!(
        matches!(&other, Contribution::NotAligned { reason, .. } if reason.contains("`b` was never observed"))
    );
    let degrees = r#"{"pose_relation":"angle_deg","windows":[{"start":0,"error_deg":3.0}]}"#;
    assert!(
        reason(SessionFiles {
            results_json: Some(degrees),
            ..base
        })
        .contains("angle_deg")
    );
    let map = build_map(&spec(Convention::Unity), &[other], 1);
    assert!(map.cells.is_empty());
    assert!(matches!(
        &map.sessions[0],
        VenueSession::NotAligned { aligned: false, .. }
    ));
}

#[test]
fn bad_files_name_file_line_and_column() {
    let r = record(
        Convention::Unity,
        DVec3::ZERO,
        0.0,
        &[camera(DVec3::ZERO, 0.0), camera(DVec3::X, 0.0)],
        &[Some(DVec3::Z), Some(DVec3::Z)],
        &[Some(0.1), Some(0.2)],
    );
    let base = files(&r, Convention::Unity, "s");
    let error = |f: SessionFiles<'_>| match Contribution::from_files(&f, "a") {
        Err(Error::Parse {
            source_name,
            line,
            field,
            ..
        }) => (source_name, line, field),
        other => panic!("{other:?}"),
    };
    let bad_x = {
        let mut lines: Vec<String> = r.subs.lines().map(str::to_owned).collect();
        let mut cells: Vec<&str> = lines[2].split(',').collect();
        cells[15] = "inf";
        lines[2] = cells.join(",");
        lines.join("\n")
    };
    assert_eq!(
        error(SessionFiles {
            subtrajectories_csv: Some(&bad_x),
            ..base
        }),
        ("subtrajectories.csv".into(), 3, "x".into())
    );
    let bad_mid = r.subs.replacen(&format!(",{},", T0 + HALF_NS), ",7,", 1);
    assert_eq!(
        error(SessionFiles {
            subtrajectories_csv: Some(&bad_mid),
            ..base
        }),
        ("subtrajectories.csv".into(), 2, "mid_ns".into())
    );
    let bad_depth = r.subs.replacen("valid", "great", 1);
    assert_eq!(
        error(SessionFiles {
            subtrajectories_csv: Some(&bad_depth),
            ..base
        }),
        ("subtrajectories.csv".into(), 2, "depth".into())
    );
    let bad_anchor = r.anchors.replace(",full", ",fine");
    assert_eq!(
        error(SessionFiles {
            anchors_csv: Some(&bad_anchor),
            ..base
        }),
        ("anchors.csv".into(), 2, "tracking".into())
    );
    let bad_tum = format!("{}1 2 3\n", r.trajectory);
    let (source, line, _) = error(SessionFiles {
        trajectory_txt: Some(&bad_tum),
        ..base
    });
    assert_eq!((source.as_str(), line), ("trajectory.txt", 6));
    let bad_results = format!("{}{T0},abc\n", r.results);
    assert_eq!(
        error(SessionFiles {
            results_json: Some(&bad_results),
            ..base
        }),
        ("results.csv".into(), 4, "error".into())
    );
    // A bad file is an error even when the session could not be aligned anyway.
    assert_eq!(
        error(SessionFiles {
            subtrajectories_csv: Some(&bad_depth),
            anchors_csv: None,
            ..base
        })
        .0,
        "subtrajectories.csv"
    );
}

#[test]
fn removing_every_session_empties_the_map() {
    let r = record(
        Convention::Unity,
        DVec3::ZERO,
        0.0,
        &[camera(DVec3::ZERO, 0.0)],
        &[Some(DVec3::Z)],
        &[Some(0.1)],
    );
    let c = Contribution::from_files(&files(&r, Convention::Unity, "s"), "a").unwrap();
    let mut b = MapBuilder::new(spec(Convention::Unity));
    b.add(&c);
    b.add(&c);
    assert_eq!(b.len(), 1);
    let spec = spec(Convention::Unity);
    assert_eq!(
        build_map(&spec, &[c.clone(), c.clone()], 1),
        build_map(&spec, &[c], 1)
    );
    assert_eq!(b.map(1).cells.len(), 2);
    assert_eq!(b.map(1).cells[0].subtrajectories, 1);
    assert!(b.remove("s"));
    let map = b.map(1);
    assert!(map.cells.is_empty() && map.sessions.is_empty() && b.is_empty());
}

/// The anchor's wall (the plane z = 0 of the venue frame) seen by three users, each
/// aligned to the venue with millimetres of error on either side of the plane: one row of
/// surface cells, each seen by all three (on a grid with faces at multiples of `cell_m`
/// the wall would split into two rows, each seen by one or two).
#[test]
fn the_anchor_wall_is_one_row_of_cells_seen_by_every_user() {
    let jitters = [-0.002, 0.0015, 0.0004];
    let mut contributions = Vec::new();
    for (u, jitter) in jitters.iter().enumerate() {
        // Along the wall, 12 mm or more from any cell face of the sizes below.
        let xs: Vec<f64> = (0..12).map(|i| 0.012 + 0.15 * f64::from(i)).collect();
        let mids: Vec<Pose> = xs
            .iter()
            .map(|x| camera(DVec3::new(*x, 1.5, -2.0), 0.0))
            .collect();
        // Each sample's own millimetre of depth noise around the user's offset.
        let surfaces: Vec<Option<DVec3>> = xs
            .iter()
            .enumerate()
            .map(|(i, x)| {
                let wobble = if i % 2 == 0 { 0.0005 } else { -0.0005 };
                Some(DVec3::new(*x, 1.4, jitter + wobble))
            })
            .collect();
        let errors = vec![Some(0.15); mids.len()];
        let heading = 0.3 * u as f64;
        let r = record(
            Convention::Unity,
            DVec3::new(u as f64, 0.0, -1.0),
            heading,
            &mids,
            &surfaces,
            &errors,
        );
        let id = format!("s{u}");
        contributions
            .push(Contribution::from_files(&files(&r, Convention::Unity, &id), "a").unwrap());
    }
    for cell_m in [0.05, 0.1, 0.25, 0.5, 1.0] {
        let spec = VenueSpec {
            cell_m,
            ..spec(Convention::Unity)
        };
        let map = build_map(&spec, &contributions, 1);
        let walls: Vec<_> = map
            .cells
            .iter()
            .filter(|c| c.kind == CellKind::Surface)
            .collect();
        assert!(!walls.is_empty());
        for c in &walls {
            assert_eq!(c.center[2], 0.0, "cell_m {cell_m}: {c:?}");
            assert_eq!(c.sessions, 3, "cell_m {cell_m}: {c:?}");
            assert_eq!(c.class, ErrorClass::High);
        }
    }
    // Whole metres are mid-cell for every cell size that divides a metre.
    for cell_m in [0.05, 0.1, 0.2, 0.25, 0.5, 1.0] {
        for metres in [-3.0, -1.0, 0.0, 1.0, 2.0, 4.0] {
            let i = cell_index(metres, cell_m);
            assert_eq!(
                cell_index(metres - 0.003, cell_m),
                i,
                "{metres} at {cell_m}"
            );
            assert_eq!(
                cell_index(metres + 0.003, cell_m),
                i,
                "{metres} at {cell_m}"
            );
            assert!((cell_centre(i, cell_m) - metres).abs() < 1e-9);
        }
    }
}

proptest! {
    /// The same walk recorded in any world frame (translation and heading) and either
    /// convention lands in the same cells with the same errors and directions. Points sit
    /// at least 2 mm from a cell face and headings at least 2.5° from a sector boundary, so
    /// rounding cannot move them.
    #[test]
    fn a_moved_session_maps_to_the_same_cells(
        t in prop::array::uniform3(-30.0..30.0f64), heading in -PI..PI,
        arcore in any::<bool>(),
        walk in prop::collection::vec((prop::array::uniform3(-8i32..8), prop::array::uniform3(-0.248..0.248f64),
            0u8..8, -20.0..20.0f64, prop::option::of(prop::array::uniform3(-8i32..8)), 0.0..0.3f64), 1..40),
    ) {
        let cell_m = 0.5;
        let at = |i: [i32; 3], f: [f64; 3]| {
            DVec3::new(f64::from(i[0]) * cell_m + f[0], f64::from(i[1]) * cell_m + f[1],
                f64::from(i[2]) * cell_m + f[2])
        };
        let mids: Vec<Pose> = walk.iter().map(|(i, f, sector, off, _, _)| {
            // Unity yaw θ looks at heading 90° − θ (counter-clockwise from +X).
            let heading = f64::from(*sector) * FRAC_PI_4 + off.to_radians();
            camera(at(*i, *f), FRAC_PI_2 - heading)
        }).collect();
        let surfaces: Vec<Option<DVec3>> = walk.iter().map(|(_, f, _, _, s, _)| s.map(|s| at(s, *f))).collect();
        let errors: Vec<Option<f64>> = walk.iter().map(|w| Some(w.5)).collect();
        let home = record(Convention::Unity, DVec3::ZERO, 0.0, &mids, &surfaces, &errors);
        let convention = if arcore { Convention::Arcore } else { Convention::Unity };
        let moved = record(convention, DVec3::from_array(t), heading, &mids, &surfaces, &errors);
        let a = Contribution::from_files(&files(&home, Convention::Unity, "s"), "a").unwrap();
        let b = Contribution::from_files(&files(&moved, convention, "s"), "a").unwrap();
        let (ma, mb) = (build_map(&spec(Convention::Unity), &[a], 1), build_map(&spec(Convention::Unity), &[b], 1));
        prop_assert_eq!(ma.cells.len(), mb.cells.len());
        for (x, y) in ma.cells.iter().zip(&mb.cells) {
            prop_assert_eq!(x.center, y.center);
            prop_assert_eq!((x.kind, x.sessions, x.subtrajectories, x.directions), (y.kind, y.sessions, y.subtrajectories, y.directions));
            prop_assert!((x.error_m - y.error_m).abs() < 1e-15);
        }
        let sectors: u32 = ma.cells.iter().filter(|c| c.kind == CellKind::Path).map(|c| c.directions.iter().sum::<u32>()).sum();
        prop_assert_eq!(sectors as usize, walk.len());
    }

    /// Garbage in any of the files (text inserted, the rest cut) is an error or a
    /// contribution, never a panic; an error names the file it is about.
    #[test]
    fn damaged_files_never_panic(which in 0usize..4, at in 0.0..1.0f64, cut in any::<bool>(),
        junk in "[0-9a-z,.\\- \n]{0,12}") {
        let r = record(Convention::Arcore, DVec3::new(1.0, 2.0, 3.0), 0.3,
            &[camera(DVec3::ZERO, 0.0), camera(DVec3::X, 1.0), camera(DVec3::Z, 2.0)],
            &[Some(DVec3::Z), None, Some(DVec3::X)], &[Some(0.1), Some(0.2), None]);
        let mut texts = [r.anchors.clone(), r.trajectory.clone(), r.subs.clone(), r.results.clone()];
        let text = &mut texts[which];
        let mut i = (at * text.len() as f64) as usize;
        while !text.is_char_boundary(i) { i -= 1; }
        if cut { text.truncate(i); } else { text.insert_str(i, &junk); }
        let f = SessionFiles { session: "s", convention: Convention::Arcore,
            anchors_csv: Some(&texts[0]), trajectory_txt: Some(&texts[1]),
            subtrajectories_csv: Some(&texts[2]), results_json: Some(&texts[3]) };
        match Contribution::from_files(&f, "a") {
            Ok(c) => { let _ = build_map(&spec(Convention::Unity), &[c], 1); }
            Err(Error::Parse { source_name, field, .. }) => {
                // The damaged file, or (a pose cut from the log) the row whose midpoint
                // trajectory.txt no longer has.
                let names = ["anchors.csv", "trajectory.txt", "subtrajectories.csv", "results.csv"];
                prop_assert!(source_name == names[which] || field == "mid_ns", "{} {}", source_name, field);
            }
            Err(other) => prop_assert!(false, "{other}"),
        }
    }

    /// The builder's incremental map equals a rebuild from scratch after any sequence of
    /// adds and removes.
    #[test]
    fn incremental_equals_rebuilt(ops in prop::collection::vec((0usize..4, any::<bool>()), 1..20)) {
        let contributions: Vec<Contribution> = (0..4).map(|s| {
            let mids: Vec<Pose> = (0..6).map(|k| camera(DVec3::new(0.3 * k as f64, 1.0, 0.2 * s as f64), 0.4 * k as f64)).collect();
            let surfaces: Vec<Option<DVec3>> = (0..6).map(|k| (k % 2 == 0).then(|| DVec3::new(0.3 * k as f64, 1.0, 1.0))).collect();
            let errors: Vec<Option<f64>> = (0..6).map(|k| Some(0.02 * (k + s) as f64)).collect();
            let r = record(Convention::Unity, DVec3::ZERO, 0.0, &mids, &surfaces, &errors);
            Contribution::from_files(&files(&r, Convention::Unity, &format!("s{s}")), "a").unwrap()
        }).collect();
        let mut builder = MapBuilder::new(spec(Convention::Unity));
        let mut present: Vec<usize> = Vec::new();
        for (s, add) in ops {
            if add {
                builder.add(&contributions[s]);
                if !present.contains(&s) { present.push(s); }
            } else {
                prop_assert_eq!(builder.remove(&format!("s{s}")), present.contains(&s));
                present.retain(|p| *p != s);
            }
            let _ = builder.map(1);
        }
        let again: Vec<Contribution> = present.iter().map(|s| contributions[*s].clone()).collect();
        for min_sessions in [1, 2] {
            prop_assert_eq!(builder.map(min_sessions), build_map(&spec(Convention::Unity), &again, min_sessions));
        }
    }
}
