//! Simulator speed: building a recording, playing trials (error model and RANSAC tracker),
//! recording the RANSAC front end's observations, rendering depth images.

use criterion::{Criterion, criterion_group, criterion_main};
use sitar_sim::{DepthCamera, Recording, Tracker, play_trial};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    c.bench_function("recording_demo_15s_30fps", |b| {
        b.iter(|| Recording::demo(black_box(15.0), 30.0, 1).unwrap())
    });
    let short = Recording::demo(15.0, 30.0, 1).unwrap();
    c.bench_function("play_trial_450_frames", |b| {
        b.iter(|| play_trial(&short, black_box(3)))
    });
    let ransac = short.clone().with_tracker(Tracker::Ransac);
    c.bench_function("play_trial_ransac_450_frames", |b| {
        b.iter(|| play_trial(&ransac, black_box(3)))
    });
    c.bench_function("record_ransac_observations_450_frames", |b| {
        b.iter(|| short.clone().with_tracker(black_box(Tracker::Ransac)))
    });
    let long = Recording::demo(94.0, 30.0, 1).unwrap();
    c.bench_function("play_trial_2820_frames", |b| {
        b.iter(|| play_trial(&long, black_box(3)))
    });
    let camera = DepthCamera::phone();
    let gt = &short.walk().ground_truth;
    c.bench_function("render_depth_160x120", |b| {
        b.iter(|| {
            short.room().render_depth_mm(
                gt.positions[100],
                gt.orientations[100],
                black_box(&camera),
            )
        })
    });
    let bytes = short.to_bytes();
    c.bench_function("recording_from_bytes_450", |b| {
        b.iter(|| Recording::from_bytes(black_box(&bytes)).unwrap())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
