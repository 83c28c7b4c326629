//! `sitar_session_guide` through the C ABI for 3 markers + 50 high venue surface cells (53
//! targets), and `sitar_session_venue_cells` for the 50 cells: thread CPU time (the cost of
//! the call, robust on a shared machine) and wall time.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use sitar::{
    sitar_session_free, sitar_session_guide, sitar_session_venue_cells, SitarGuide, SitarPose,
    SitarVenueCell,
};

#[path = "../tests/support/venue_session.rs"]
#[allow(dead_code)]
mod venue_session;

#[path = "support/cpu_time.rs"]
mod cpu_time;

use cpu_time::thread_cpu_time;

fn bench_guide(c: &mut Criterion) {
    let h = venue_session::venue_session(&venue_session::map_json(50, true));
    let mut out = [SitarGuide::default(); 64];
    let mut cells = [SitarVenueCell::default(); 64];
    let mut len = 0usize;
    let camera = |i: u64| SitarPose {
        px: 0.001 * (i % 1000) as f64,
        py: 1.5,
        qy: 0.2,
        qw: 0.98,
        ..SitarPose::default()
    };
    let guide = |i: u64, out: &mut [SitarGuide; 64], len: &mut usize| {
        let status = sitar_session_guide(
            black_box(h),
            &camera(i),
            60.0,
            1080,
            1920,
            40.0,
            out.as_mut_ptr(),
            out.len(),
            len,
        );
        debug_assert_eq!(status, 0);
    };
    guide(0, &mut out, &mut len);
    assert_eq!(len, 53);
    c.bench_function(
        "sitar_session_guide 3 markers + 50 cells (thread CPU time)",
        |b| {
            b.iter_custom(|iters| {
                let start = thread_cpu_time();
                for i in 0..iters {
                    guide(i, &mut out, &mut len);
                }
                thread_cpu_time() - start
            })
        },
    );
    c.bench_function(
        "sitar_session_guide 3 markers + 50 cells (wall time)",
        |b| {
            let mut i = 0u64;
            b.iter(|| {
                i += 1;
                guide(i, &mut out, &mut len);
            })
        },
    );
    c.bench_function("sitar_session_venue_cells 50 cells (wall time)", |b| {
        b.iter(|| {
            let status =
                sitar_session_venue_cells(black_box(h), cells.as_mut_ptr(), cells.len(), &mut len);
            debug_assert_eq!(status, 0);
        })
    });
    assert_eq!(sitar_session_free(h), 0);
}

criterion_group! {
    name = benches;
    config = Criterion::default().measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    targets = bench_guide
}
criterion_main!(benches);
