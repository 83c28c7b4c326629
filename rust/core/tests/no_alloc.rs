//! The frame path must not allocate: counted with a wrapping global allocator.
#![allow(missing_docs)]

use glam::{DQuat, DVec3};
use sitar_core::{Pose, Session, SessionConfig};

#[path = "support/counting_allocator.rs"]
mod counting_allocator;

use counting_allocator::allocations;

#[test]
fn ten_minutes_of_frames_allocate_nothing() {
    let poses: Vec<Pose> = (0..18_001)
        .map(|i| {
            Pose::new(
                DVec3::new(0.01 * i as f64, 1.5, 0.0),
                DQuat::from_rotation_y(0.001 * i as f64),
            )
        })
        .collect();
    let mut session = Session::new(SessionConfig::default());
    session.start(0, poses[0]).unwrap();
    let before = allocations();
    let mut midpoints = 0;
    for (i, pose) in poses.iter().enumerate().skip(1) {
        if session
            .frame(i as i64 * 33_333_333, *pose)
            .unwrap()
            .is_midpoint()
        {
            midpoints += 1;
        }
    }
    let after = allocations();
    assert_eq!(midpoints, 1_800);
    assert_eq!(after - before, 0, "frame() allocated");
}

#[test]
fn image_properties_allocate_nothing() {
    let plane: Vec<u8> = (0..640 * 480u64)
        .map(|i| ((i * 7919) % 251) as u8)
        .collect();
    let image = sitar_core::LumaImage::new(&plane, 640, 480, 640).unwrap();
    let before = allocations();
    let p = sitar_core::ImageProperties::measure(&image);
    let after = allocations();
    assert!(p.corners_per_10k > 0.0);
    assert_eq!(after - before, 0, "ImageProperties::measure allocated");
}

#[test]
fn guide_and_venue_cells_allocate_nothing() {
    use sitar_core::{Convention, Guide, ScreenView, Tracking};
    let cells: Vec<String> = (0..50)
        .map(|i| {
            format!(
                r#"{{"center":[{},1.0,{}],"kind":"{}","sessions":2,"subtrajectories":3,"error_m":0.2,"class":"high","directions":[0,0,0,0,0,0,0,3]}}"#,
                0.25 * f64::from(i % 10),
                0.25 * f64::from(i / 10),
                if i % 2 == 0 { "surface" } else { "path" }
            )
        })
        .collect();
    let map = format!(
        r#"{{"id":"v0123456789abcdef","name":"Hall","anchor":"hall","cell_m":0.25,"convention":"unity","unit":"m","sessions":[],"cells":[{}]}}"#,
        cells.join(",")
    );
    let mut session = Session::new(SessionConfig::default());
    session.start(0, Pose::IDENTITY).unwrap();
    session.load_venue(&map).unwrap();
    session
        .anchor(
            1,
            "hall",
            Pose::new(DVec3::new(0.0, 0.0, 2.0), DQuat::IDENTITY),
            Tracking::Full,
        )
        .unwrap();
    let camera = Pose::new(DVec3::new(0.5, 1.5, -1.0), DQuat::from_rotation_y(0.3));
    let mut out = vec![Guide::default(); 64];
    let before = allocations();
    let view = ScreenView::new(camera, Convention::Unity, 60.0, 1080, 1920, 40.0).unwrap();
    let mut n = 0;
    for _ in 0..1_000 {
        n = session.guide_into(&view, &mut out);
        n += session.venue_cells().unwrap().len();
    }
    let after = allocations();
    assert_eq!(n, 25 + 50);
    assert!(out[..25].iter().any(|g| g.on_screen) && out[..25].iter().any(|g| !g.on_screen));
    assert_eq!(after - before, 0, "guide_into / venue_cells allocated");
}
