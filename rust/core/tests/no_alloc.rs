//! The frame path must not allocate: counted with a wrapping global allocator.
#![allow(missing_docs)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use glam::{DQuat, DVec3};
use sitar_core::{Pose, Session, SessionConfig};

struct Counting;

thread_local! {
    // Per thread: the test harness's own threads may allocate meanwhile.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: same contract as our caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as our caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: same contract as our caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

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
