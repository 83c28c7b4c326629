//! The frame path through the C ABI allocates nothing on non-logging frames
//! (ARCHITECTURE: "Nothing on the frame path allocates or blocks").

use sitar::{
    sitar_session_frame, sitar_session_free, sitar_session_new, sitar_session_start, SitarPose,
};

#[path = "../../core/tests/support/counting_allocator.rs"]
mod counting_allocator;

use counting_allocator::allocations;

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
