//! `sitar_session_frame` through the C ABI (target: ≤ 200 ns per non-logging frame).
//!
//! Every 5th frame logs a pose; the bench times only the other frames and
//! runs the logging frame outside the timed region.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use sitar::{
    sitar_session_frame, sitar_session_free, sitar_session_new, sitar_session_start, SitarPose,
};

fn pose_at(i: i64) -> SitarPose {
    SitarPose {
        px: i as f64 * 0.01,
        py: 1.5,
        pz: 0.0,
        qx: 0.0,
        qy: 0.0,
        qz: 0.0,
        qw: 1.0,
    }
}

fn bench_frame(c: &mut Criterion) {
    let mut h = 0u64;
    assert_eq!(sitar_session_new(c"{}".as_ptr(), &mut h), 0);
    assert_eq!(sitar_session_start(h, 0, &pose_at(0)), 0);
    let mut frame = 0i64;
    let mut flags = 0u32;
    c.bench_function("sitar_session_frame (non-logging)", |b| {
        b.iter_custom(|iters| {
            // Frames 5k+1 … 5k+4 are timed together (so clock reads add little);
            // frame 5k+5 logs and runs untimed.
            let mut total = Duration::ZERO;
            let mut done = 0u64;
            while done < iters {
                let poses: [(i64, SitarPose); 4] = std::array::from_fn(|i| {
                    let f = frame + 1 + i as i64;
                    (f * 33_333_333, pose_at(f))
                });
                let start = Instant::now();
                for (t, pose) in &poses {
                    let status = sitar_session_frame(
                        black_box(h),
                        black_box(*t),
                        black_box(pose),
                        &mut flags,
                    );
                    debug_assert_eq!(status, 0);
                }
                total += start.elapsed();
                assert_eq!(flags, 0, "a timed frame logged");
                frame += 5;
                assert_eq!(
                    sitar_session_frame(h, frame * 33_333_333, &pose_at(frame), &mut flags),
                    0
                );
                done += 4;
            }
            total.mul_f64(iters as f64 / done as f64)
        })
    });
    assert_eq!(sitar_session_free(h), 0);
}

criterion_group!(benches, bench_frame);
criterion_main!(benches);
