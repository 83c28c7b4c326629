//! End-to-end estimation from files (read + estimate), the speed targets:
//! 100 trials × 2820 poses ≤ 0.3 s and 20 trials × 450 poses ≤ 20 ms on 2 cores.
//! The default data has dropped frames in every third trial (those pairs need a real
//! association); `_identical_stamps` is the playback case where all trials share stamps.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use rayon::prelude::*;
use sitar_estimator::{EstimateOptions, PairwiseValues, Setting, estimate, read_tum};

#[path = "../examples/support/synthetic.rs"]
mod synthetic;

fn end_to_end(files: &[PathBuf]) -> usize {
    let trials = files
        .par_iter()
        .map(|f| read_tum(f))
        .collect::<Result<Vec<_>, _>>()
        .expect("read");
    estimate(&trials, &EstimateOptions::default())
        .expect("estimate")
        .windows
        .len()
}

fn benches(c: &mut Criterion) {
    let root = std::env::temp_dir().join(format!("sitar-estimator-bench-{}", std::process::id()));
    let small = synthetic::write_trials(&root.join("small"), 20, 450, 7, true);
    let large = synthetic::write_trials(&root.join("large"), 100, 2820, 11, true);
    let uniform = synthetic::write_trials(&root.join("uniform"), 100, 2820, 11, false);

    let mut group = c.benchmark_group("estimate_from_files");
    group.sample_size(10);
    group.bench_function("20x450", |b| b.iter(|| end_to_end(&small)));
    group.bench_function("100x2820", |b| b.iter(|| end_to_end(&large)));
    group.bench_function("100x2820_identical_stamps", |b| {
        b.iter(|| end_to_end(&uniform))
    });
    group.finish();

    let trials = large
        .par_iter()
        .map(|f| read_tum(f))
        .collect::<Result<Vec<_>, _>>()
        .expect("read");
    let mut group = c.benchmark_group("stages_100x2820");
    group.sample_size(10);
    group.bench_function("read_files", |b| {
        b.iter(|| {
            large
                .par_iter()
                .map(|f| read_tum(f).expect("read").len())
                .sum::<usize>()
        })
    });
    let opts = EstimateOptions::default();
    group.bench_function("pairwise_values", |b| {
        b.iter(|| PairwiseValues::compute(&trials, &opts).expect("values"))
    });
    let values = PairwiseValues::compute(&trials, &opts).expect("values");
    group.bench_function("aggregate_trim_mean_30", |b| {
        b.iter(|| values.estimate(Setting::TrimMean(30)))
    });
    group.finish();
    let _ = std::fs::remove_dir_all(&root);
}

criterion_group!(estimate_benches, benches);
criterion_main!(estimate_benches);
