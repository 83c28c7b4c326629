//! The calibration's costs: reading the windows of the three real sequences and fitting on
//! them (the target: the whole `sitar calibrate` ≤ 3 s), applying it to an estimate of 100
//! trials × 2820 poses against computing that estimate (applying must cost far less), and
//! estimating one run of 2 820 poses from its own motion (target ≤ 5 ms).

use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use rayon::prelude::*;
use sitar_estimator::{
    ApplyCalibration, CalibrationSequence, DEFAULT_SMOOTHING_WINDOWS, EstimateOptions, FitOptions,
    Trajectory, estimate, estimate_live, fit_calibration, read_tum,
};

#[path = "../examples/support/synthetic.rs"]
mod synthetic;

fn read_all(files: &[PathBuf]) -> Vec<Trajectory> {
    files
        .par_iter()
        .map(|f| read_tum(f))
        .collect::<Result<Vec<_>, _>>()
        .expect("read")
}

/// The real runs' sequences, read and turned into windows (None without the shared data).
fn real_sequences(root: &Path) -> Option<Vec<CalibrationSequence>> {
    if !root.join("MH_04/ground_truth.txt").is_file() {
        println!(
            "SKIPPED the fit on real runs: {} is missing",
            root.display()
        );
        return None;
    }
    Some(
        ["MH_04", "MH_05", "V1_02"]
            .iter()
            .map(|name| {
                let dir = root.join(name);
                let gt = read_tum(&dir.join("ground_truth.txt")).expect("ground truth");
                let runs = read_all(
                    &(0..10)
                        .map(|i| dir.join(format!("runs/run{i}.txt")))
                        .collect::<Vec<_>>(),
                );
                CalibrationSequence::new(
                    name,
                    &gt,
                    &runs[..5],
                    &runs[5..],
                    &EstimateOptions::default(),
                    DEFAULT_SMOOTHING_WINDOWS,
                )
                .expect("sequence")
            })
            .collect(),
    )
}

fn benches(c: &mut Criterion) {
    let real =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/real-runs/euroc-vio");
    let mut group = c.benchmark_group("calibration");
    group.sample_size(10);
    if let Some(sequences) = real_sequences(&real) {
        group.bench_function("windows_of_3_real_sequences", |b| {
            b.iter(|| real_sequences(&real).expect("data").len())
        });
        group.bench_function("fit_3_real_sequences", |b| {
            b.iter(|| fit_calibration(&sequences, &FitOptions::default()).expect("fit"))
        });
    }
    let root = std::env::temp_dir().join(format!("sitar-calibration-bench-{}", std::process::id()));
    let files = synthetic::write_trials(&root, 100, 2820, 11, true);
    let trials = read_all(&files);
    let opts = EstimateOptions::default();
    // Any valid calibration costs the same to apply: fit one on a few of these trials.
    let calibration = fit_calibration(
        &[CalibrationSequence::new(
            "synthetic",
            &trials[0],
            &trials[1..6],
            &trials[6..11],
            &opts,
            DEFAULT_SMOOTHING_WINDOWS,
        )
        .expect("windows")],
        &FitOptions::default(),
    )
    .expect("fit");
    let base = estimate(&trials, &opts).expect("estimate");
    group.bench_function("estimate_100x2820", |b| {
        b.iter(|| estimate(&trials, &opts).expect("estimate").windows.len())
    });
    group.bench_function("apply_100x2820", |b| {
        b.iter(|| {
            let mut e = base.clone();
            calibration.apply(&mut e, &trials, "bench").expect("apply");
            e.windows.len()
        })
    });
    group.bench_function("one_run_2820", |b| {
        b.iter(|| {
            estimate_live(&calibration, &trials[0], &[], &opts, "bench")
                .expect("one run")
                .windows
                .len()
        })
    });
    group.finish();
    let _ = std::fs::remove_dir_all(&root);
}

criterion_group!(calibration_benches, benches);
criterion_main!(calibration_benches);
