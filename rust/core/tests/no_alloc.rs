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
