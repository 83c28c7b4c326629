//! `sitar_session_frame` through the C ABI (target: ≤ 200 ns per non-logging frame).
//!
//! Two measurements of the same call:
//! - **thread CPU time** of batches of non-logging frames: the cost of the call
//!   itself, robust when the machine is shared (preemption is not counted);
//! - **wall time** with the default cadence (every 5th frame logs): frames
//!   5k+1 … 5k+4 are timed together, the logging frame runs untimed.
//!
//! For the first, the session uses `subtrajectory_frames = 40000`, so no
//! frame of a batch reaches a midpoint or endpoint, and it is recreated
//! (untimed) every 16 000 frames to stay within the pre-reserved buffers.

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

#[path = "support/cpu_time.rs"]
mod cpu_time;

use cpu_time::thread_cpu_time;

/// A started session whose frames never log (see the module docs).
struct QuietSession {
    h: u64,
    frame: i64,
}

impl QuietSession {
    const FRAMES_PER_SESSION: i64 = 16_000;

    fn new() -> Self {
        let mut h = 0u64;
        assert_eq!(
            sitar_session_new(c"{\"subtrajectory_frames\":40000}".as_ptr(), &mut h),
            0
        );
        assert_eq!(sitar_session_start(h, 0, &pose_at(0)), 0);
        QuietSession { h, frame: 0 }
    }

    /// Runs `n` frames, renewing the session between batches when needed.
    fn batch(&mut self, n: i64) -> Duration {
        if self.frame + n > Self::FRAMES_PER_SESSION {
            *self = QuietSession::new();
        }
        let poses: Vec<(i64, SitarPose)> = (1..=n)
            .map(|i| ((self.frame + i) * 33_333_333, pose_at(self.frame + i)))
            .collect();
        let mut flags = 0u32;
        let start = thread_cpu_time();
        for (t, pose) in &poses {
            let status = sitar_session_frame(
                black_box(self.h),
                black_box(*t),
                black_box(pose),
                &mut flags,
            );
            debug_assert_eq!(status, 0);
        }
        let elapsed = thread_cpu_time() - start;
        assert_eq!(flags, 0, "a timed frame logged");
        self.frame += n;
        elapsed
    }
}

impl Drop for QuietSession {
    fn drop(&mut self) {
        assert_eq!(sitar_session_free(self.h), 0);
    }
}

fn bench_frame(c: &mut Criterion) {
    let mut quiet = QuietSession::new();
    c.bench_function("sitar_session_frame non-logging (thread CPU time)", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            let mut done = 0u64;
            while done < iters {
                let n = (iters - done).min(1_000);
                total += quiet.batch(n as i64);
                done += n;
            }
            total
        })
    });
    drop(quiet);

    let mut h = 0u64;
    assert_eq!(sitar_session_new(c"{}".as_ptr(), &mut h), 0);
    assert_eq!(sitar_session_start(h, 0, &pose_at(0)), 0);
    let mut frame = 0i64;
    let mut flags = 0u32;
    c.bench_function("sitar_session_frame non-logging (wall time)", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            let mut done = 0u64;
            while done < iters {
                if frame >= QuietSession::FRAMES_PER_SESSION {
                    assert_eq!(sitar_session_free(h), 0);
                    assert_eq!(sitar_session_new(c"{}".as_ptr(), &mut h), 0);
                    assert_eq!(sitar_session_start(h, 0, &pose_at(0)), 0);
                    frame = 0;
                }
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
