//! The frame path through the C ABI allocates nothing on non-logging frames
//! (ARCHITECTURE: "Nothing on the frame path allocates or blocks").

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use sitar::{
    sitar_session_frame, sitar_session_free, sitar_session_new, sitar_session_start, SitarPose,
};

struct Counting;

thread_local! {
    // Per thread: the test harness's main thread allocates while the test runs (its channel
    // wait), which a process-wide count once blamed on a frame.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

// SAFETY: forwards to the system allocator, only counting.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn non_logging_frames_do_not_allocate() {
    let pose = |i: i64| SitarPose {
        px: i as f64 * 0.01,
        qw: 1.0,
        ..SitarPose::default()
    };
    let mut h = 0u64;
    assert_eq!(sitar_session_new(c"{}".as_ptr(), &mut h), 0);
    assert_eq!(sitar_session_start(h, 0, &pose(0)), 0);
    let mut flags = 0u32;
    let mut allocating_frames = Vec::with_capacity(10_000);
    for i in 1..=10_000i64 {
        let before = allocations();
        assert_eq!(
            sitar_session_frame(h, i * 33_333_333, &pose(i), &mut flags),
            0
        );
        if flags == 0 && allocations() != before {
            allocating_frames.push(i);
        }
    }
    assert_eq!(sitar_session_free(h), 0);
    assert!(
        allocating_frames.is_empty(),
        "non-logging frames that allocated: {allocating_frames:?}"
    );
}
