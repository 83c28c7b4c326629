//! Tests of the anchors, the alignment and the map document.

use super::*;
use crate::{Convention, Error, ErrorClass, Pose};
use glam::{DQuat, DVec3};
use proptest::prelude::*;

fn obs(anchor: &str, pose: Pose, tracking: Tracking) -> AnchorObservation {
    AnchorObservation {
        t_ns: 0,
        anchor: anchor.to_owned(),
        pose,
        tracking,
    }
}

/// An image on a wall facing the venue's +Z (image +Y its normal, as AR Foundation and
/// ARCore report tracked images), turned about +Y by `heading`, at `t`.
fn wall_image(t: DVec3, heading: f64, tilt: f64) -> Pose {
    Pose::new(
        t,
        DQuat::from_rotation_y(heading) * DQuat::from_rotation_x(tilt),
    )
}

#[test]
fn one_exact_observation_is_the_alignment() {
    let t = DVec3::new(2.0, 1.4, -3.0);
    let heading = 0.9;
    let a = align(
        &[obs(
            "lobby",
            wall_image(t, heading, FRAC_PI_2),
            Tracking::Full,
        )],
        "lobby",
    )
    .unwrap();
    assert!((a.translation - t).length() < 1e-12);
    assert!((a.heading_rad - heading).abs() < 1e-12);
    assert_eq!((a.observations, a.rejected), (1, 0));
    assert_eq!((a.position_spread_m, a.heading_spread_deg), (0.0, 0.0));
    // The origin is the anchor; venue +X is the image's +X levelled; +Y is up.
    assert!(a.to_venue(t).length() < 1e-12);
    let x = DQuat::from_rotation_y(heading) * DVec3::X;
    assert!((a.to_venue(t + x) - DVec3::X).length() < 1e-12);
    assert!((a.to_venue(t + DVec3::Y) - DVec3::Y).length() < 1e-12);
    let p = DVec3::new(0.3, -1.0, 7.0);
    assert!((a.to_world(a.to_venue(p)) - p).length() < 1e-12);
}

use std::f64::consts::{FRAC_PI_2, PI};

#[test]
fn median_by_selection() {
    assert_eq!(median(&mut [3.0]), 3.0);
    assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
    assert_eq!(median(&mut [5.0, -1.0, 9.0, 0.0, 2.0]), 2.0);
    assert_eq!(median(&mut [1.0, 1.0, 7.0, 1.0]), 1.0);
}

#[test]
fn headings_of_a_levelled_image_x() {
    assert_eq!(heading_of(DQuat::IDENTITY), Some(0.0));
    // +X turned to −Z: +90° about +Y.
    let h = heading_of(DQuat::from_rotation_y(FRAC_PI_2)).unwrap();
    assert!((h - FRAC_PI_2).abs() < 1e-12);
    // A tilt about the image's own +X changes nothing; a roll to vertical has no heading.
    let h = heading_of(DQuat::from_rotation_y(-2.0) * DQuat::from_rotation_x(1.1)).unwrap();
    assert!((h + 2.0).abs() < 1e-12);
    assert_eq!(heading_of(DQuat::from_rotation_z(FRAC_PI_2)), None);
}

#[test]
fn headings_across_the_seam_have_a_median_near_pi() {
    let t = DVec3::ZERO;
    let list: Vec<AnchorObservation> = [PI - 0.01, -PI + 0.01, PI - 0.02, -PI + 0.03, PI]
        .iter()
        .map(|h| obs("a", wall_image(t, *h, 0.0), Tracking::Full))
        .collect();
    let a = align(&list, "a").unwrap();
    assert!(wrap(a.heading_rad - PI).abs() < 0.011, "{}", a.heading_rad);
}

#[test]
fn only_full_observations_count_and_outliers_are_rejected() {
    let t = DVec3::new(1.0, 1.0, 1.0);
    let mut list: Vec<AnchorObservation> = (0..9)
        .map(|i| {
            let e = 0.001 * (i as f64 - 4.0);
            obs(
                "a",
                wall_image(t + DVec3::splat(e), 0.5 + e, 0.0),
                Tracking::Full,
            )
        })
        .collect();
    // Far off but not full: ignored; one full outlier in position, one in heading.
    list.push(obs(
        "a",
        wall_image(DVec3::splat(9.0), 2.0, 0.0),
        Tracking::Limited,
    ));
    list.push(obs(
        "a",
        wall_image(DVec3::splat(5.0), 0.5, 0.0),
        Tracking::Full,
    ));
    list.push(obs("a", wall_image(t, -2.5, 0.0), Tracking::Full));
    list.push(obs(
        "other",
        wall_image(DVec3::splat(-7.0), 1.0, 0.0),
        Tracking::Full,
    ));
    let a = align(&list, "a").unwrap();
    assert_eq!((a.observations, a.rejected), (9, 2));
    assert!((a.translation - t).length() < 1e-12);
    assert!((a.heading_rad - 0.5).abs() < 1e-12);
    // RMS of 0.001·(i−4)·√3 over i = 0…8: 0.001·√(60/9)·√3.
    let expected = 0.001 * (60.0f64 / 9.0).sqrt() * 3f64.sqrt();
    assert!((a.position_spread_m - expected).abs() < 1e-12);
    let expected_deg = (0.001 * (60.0f64 / 9.0).sqrt()).to_degrees();
    assert!((a.heading_spread_deg - expected_deg).abs() < 1e-9);
}

#[test]
fn without_a_full_observation_a_session_is_not_aligned_and_says_why() {
    let p = wall_image(DVec3::ZERO, 0.0, 0.0);
    let e = align(&[], "a").unwrap_err();
    assert!(e.reason.contains("never observed"), "{e}");
    let e = align(
        &[obs("a", p, Tracking::Limited), obs("a", p, Tracking::None)],
        "a",
    )
    .unwrap_err();
    assert!(
        e.reason.contains("observed 2 times but never with full"),
        "{e}"
    );
    let vertical = Pose::new(DVec3::ZERO, DQuat::from_rotation_z(FRAC_PI_2));
    let e = align(&[obs("a", vertical, Tracking::Full)], "a").unwrap_err();
    assert!(e.reason.contains("heading"), "{e}");
}

/// The same physical scene recorded in Unity's and in ARCore's convention: the venue
/// coordinates of a point differ by the reflection z → −z, as the world coordinates do
/// (the venue frame's third axis follows each convention's handedness).
#[test]
fn the_third_axis_follows_the_conventions_handedness() {
    let image = wall_image(DVec3::new(1.0, 1.2, 4.0), 0.6, FRAC_PI_2);
    let point = DVec3::new(-2.0, 0.5, 3.0);
    let unity = align(&[obs("a", image, Tracking::Full)], "a").unwrap();
    let arcore_image = Convention::Unity.convert_pose(image, Convention::Arcore);
    let arcore = align(&[obs("a", arcore_image, Tracking::Full)], "a").unwrap();
    let in_arcore = Convention::Unity.convert_vector(point, Convention::Arcore);
    let (u, a) = (unity.to_venue(point), arcore.to_venue(in_arcore));
    assert!((a - DVec3::new(u.x, u.y, -u.z)).length() < 1e-12, "{u} {a}");
    // In each, +X is the image's right, +Y up, and the frame is a proper rotation of
    // the world's (so it has the world's handedness).
    let right = image.rotation * DVec3::X;
    assert!((unity.to_venue(image.position + right) - DVec3::X).length() < 1e-12);
    assert!((glam::DMat3::from_quat(unity.rotation()).determinant() - 1.0).abs() < 1e-12);
}

#[test]
fn anchors_csv_round_trips_and_names_line_and_column() {
    let list = vec![
        obs(
            "lobby-a",
            wall_image(DVec3::new(0.1, 0.2, 0.3), 0.4, 0.5),
            Tracking::Full,
        ),
        AnchorObservation {
            t_ns: -5,
            ..obs("é", Pose::IDENTITY, Tracking::None)
        },
    ];
    let csv = anchors_csv(&list);
    assert!(csv.starts_with(&format!("{ANCHORS_HEADER}\n0,lobby-a,0.1,")));
    assert_eq!(parse_anchors_csv(&csv, "anchors.csv").unwrap(), list);
    let field = |text: &str| match parse_anchors_csv(text, "anchors.csv") {
        Err(Error::Parse { line, field, .. }) => (line, field),
        other => panic!("{other:?}"),
    };
    let h = ANCHORS_HEADER;
    assert_eq!(field("t,anchor\n"), (1, "header".into()));
    assert_eq!(
        field(&format!(
            "{h}\n1,a,0,0,0,0,0,0,1,full\nx,a,0,0,0,0,0,0,1,full\n"
        )),
        (3, "t_ns".into())
    );
    assert_eq!(
        field(&format!("{h}\n1,a,0,nan,0,0,0,0,1,full\n")),
        (2, "py".into())
    );
    assert_eq!(
        field(&format!("{h}\n1,a,0,0,0,0,0,0,1,good\n")),
        (2, "tracking".into())
    );
    assert_eq!(
        field(&format!("{h}\n1,,0,0,0,0,0,0,1,full\n")),
        (2, "anchor".into())
    );
    assert_eq!(
        field(&format!("{h}\n1,a,0,0,0,0,0,0,1\n")),
        (2, "row".into())
    );
    assert_eq!(
        field(&format!("{h}\n1,a,0,0,0,0,0,0,0,full\n")),
        (2, "qx".into())
    );
}

#[test]
fn anchor_ids_are_checked() {
    assert!(check_anchor_id("lobby").is_ok());
    assert!(check_anchor_id(&"x".repeat(64)).is_ok());
    for bad in ["", &"x".repeat(65), "a,b", "a\nb", "a\"b"] {
        let e = check_anchor_id(bad).unwrap_err();
        assert!(
            matches!(
                e,
                Error::InvalidArgument {
                    name: "anchor_id",
                    ..
                }
            ),
            "{e}"
        );
    }
    assert!(matches!(
        Tracking::from_code(3),
        Err(Error::InvalidArgument {
            name: "tracking",
            ..
        })
    ));
    assert_eq!(Tracking::from_code(2).unwrap(), Tracking::Full);
}

pub(crate) const MAP: &str = r#"{"id":"v0123456789abcdef","name":"Lobby","anchor":"lobby-a",
    "cell_m":0.25,"convention":"unity","unit":"m",
    "sessions":[{"id":"s1","aligned":true,"observations":40,"position_spread_m":0.01,
      "heading_spread_deg":0.4,"subtrajectories":12},
      {"id":"s2","aligned":false,"reason":"the anchor was never fully tracked"}],
    "cells":[{"center":[1.0,0.0,2.0],"kind":"path","sessions":1,"subtrajectories":3,
      "error_m":0.02,"class":"low","directions":[1,0,0,2,0,0,0,0]},
      {"center":[0.5,1.5,-1.0],"kind":"surface","sessions":2,"subtrajectories":4,
      "error_m":0.14,"class":"high","directions":[0,0,4,0,0,0,0,0]}]}"#;

#[test]
fn the_map_parses_round_trips_and_names_bad_keys() {
    let map = VenueMap::from_json(MAP).unwrap();
    assert_eq!(map.cells[1].kind, CellKind::Surface);
    assert_eq!(map.cells[1].class, ErrorClass::High);
    assert!(
        matches!(&map.sessions[1], VenueSession::NotAligned { reason, .. } if reason.contains("never"))
    );
    assert_eq!(VenueMap::from_json(&map.to_json()).unwrap(), map);
    let field = |text: String| match VenueMap::from_json(&text) {
        Err(Error::Parse { field, .. }) => field,
        other => panic!("{other:?}"),
    };
    assert_eq!(
        field(MAP.replace("\"surface\"", "\"wall\"")),
        "cells[1].kind"
    );
    assert_eq!(
        field(MAP.replace("\"unit\":\"m\"", "\"unit\":\"deg\"")),
        "unit"
    );
    assert_eq!(field(MAP.replace("0.25", "3")), "cell_m");
    assert_eq!(
        field(MAP.replace("[0,0,4,0,0,0,0,0]", "[0,0,4]")),
        "cells[1].directions"
    );
    assert_eq!(
        field(MAP.replace("\"class\":\"high\"", "\"class\":\"bad\"")),
        "cells[1].class"
    );
    assert_eq!(
        field(MAP.replace("\"aligned\":true", "\"aligned\":false")),
        "sessions[0].aligned"
    );
}

#[test]
fn world_cells_follow_the_alignment() {
    let map = VenueMap::from_json(MAP).unwrap();
    let a = align(
        &[obs(
            "lobby-a",
            wall_image(DVec3::new(3.0, 0.0, 1.0), FRAC_PI_2, 0.0),
            Tracking::Full,
        )],
        "lobby-a",
    )
    .unwrap();
    let cells = world_cells(&map, &a);
    // R_y(90°)·(1, 0, 2) = (2, 0, −1).
    assert!((cells[0].position - DVec3::new(5.0, 0.0, 0.0)).length() < 1e-12);
    assert_eq!(
        (cells[1].kind, cells[1].class, cells[1].sessions),
        (CellKind::Surface, ErrorClass::High, 2)
    );
}

fn noise(seed: u64, i: usize, scale: f64) -> f64 {
    // A deterministic, roughly uniform value in [−scale, scale] from (seed, i).
    let mut x = seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
    x ^= x >> 33;
    scale * (2.0 * (x as f64 / u64::MAX as f64) - 1.0)
}

proptest! {
    /// A known translation and heading, observed with noise (≤ 1 cm, ≤ 1°) and up to 30 %
    /// gross outliers, is recovered within the noise, in both conventions.
    #[test]
    fn a_known_alignment_is_recovered(t in prop::array::uniform3(-20.0..20.0f64),
        heading in -PI..PI, n in 5usize..60, outlier_share in 0.0..0.3f64,
        seed in any::<u64>(), arcore in any::<bool>()) {
        let t = DVec3::from_array(t);
        let outliers = (n as f64 * outlier_share) as usize;
        let mut list = Vec::new();
        for i in 0..n {
            let (p, h) = if i < outliers {
                (t + DVec3::new(1.0 + noise(seed, 5 * i, 3.0).abs(), noise(seed, 5 * i + 1, 3.0), 0.5),
                    heading + 0.5 + noise(seed, 5 * i + 2, 2.0).abs())
            } else {
                (t + DVec3::new(noise(seed, 5 * i, 0.01), noise(seed, 5 * i + 1, 0.01),
                    noise(seed, 5 * i + 3, 0.01)) / 3f64.sqrt(),
                    heading + noise(seed, 5 * i + 2, 1f64.to_radians()))
            };
            let tilt = noise(seed, 5 * i + 4, PI);
            list.push(obs("a", wall_image(p, h, tilt), Tracking::Full));
            list.push(obs("a", wall_image(p * 3.0, h + 1.0, tilt), Tracking::Limited));
        }
        let (list, t) = if arcore {
            let c = |o: AnchorObservation| AnchorObservation {
                pose: Convention::Unity.convert_pose(o.pose, Convention::Arcore), ..o };
            (list.into_iter().map(c).collect::<Vec<_>>(),
                Convention::Unity.convert_vector(t, Convention::Arcore))
        } else { (list, t) };
        let heading = if arcore { -heading } else { heading };
        let a = align(&list, "a").unwrap();
        prop_assert!((a.translation - t).length() < 0.01, "{} vs {}", a.translation, t);
        prop_assert!(wrap(a.heading_rad - heading).abs() < 1f64.to_radians());
        prop_assert!(a.position_spread_m < 0.01 && a.heading_spread_deg < 1.0);
        prop_assert!(a.rejected >= outliers);
        prop_assert_eq!(a.observations + a.rejected, n);
    }
}
