//! A floor for the simplest exact order a progressive trimmed mean could keep: after every
//! push, one pass over all of a window's values, counting those in two narrow intervals
//! (what finding the cuts' next values by scanning must at least read). Nothing is sorted,
//! summed or collected, so a real scan-based order costs more than this.
//!
//! `cargo run --release -p sitar-estimator --example order_scan_floor [-- --repeat 5]`
//!
//! The shape is the progressive benchmark's: 2 810 windows, 100 trials, push k adding k − 1
//! values to every window (4 950 values a window at the end, 468 M values read over the 99
//! passes). Values are the upper 32 bits of positive doubles (monotone in the value), random.
//! Printed: seconds in the passes (median of `--repeat`), and ns per value read.

use std::time::Instant;

const WINDOWS: usize = 2_810;
const TRIALS: usize = 100;

/// Seconds spent in the counting passes of one progressive run.
fn one_run(seed: u64) -> (f64, u64, u64) {
    let mut state = seed | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut windows: Vec<Vec<u32>> = (0..WINDOWS)
        .map(|_| Vec::with_capacity(TRIALS * (TRIALS - 1) / 2))
        .collect();
    // Two intervals about 1/2000 of the values wide, near the 15 % and 85 % quantiles.
    let (lower, upper) = ((0x3f40_0000u32, 0x3f40_0800u32), (0x3fc0_0000, 0x3fc0_0800));
    let (mut seconds, mut read, mut counted) = (0.0, 0u64, 0u64);
    for k in 1..TRIALS {
        for values in windows.iter_mut() {
            values.extend((0..k).map(|_| (next() >> 40) as u32 | 0x3f00_0000));
        }
        let started = Instant::now();
        for values in &windows {
            let (mut a, mut b) = (0u32, 0u32);
            for &v in values {
                a += u32::from((v > lower.0) & (v < lower.1));
                b += u32::from((v > upper.0) & (v < upper.1));
            }
            counted += u64::from(a + b);
            read += values.len() as u64;
        }
        seconds += started.elapsed().as_secs_f64();
    }
    (seconds, read, std::hint::black_box(counted))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let repeat: usize = args
        .iter()
        .position(|a| a == "--repeat")
        .and_then(|i| args.get(i + 1))
        .map_or(5, |v| v.parse().expect("--repeat takes a count"));
    let mut runs: Vec<(f64, u64)> = (0..repeat.max(1))
        .map(|r| {
            let (seconds, read, _) = one_run(0x9E37_79B9_7F4A_7C15 ^ r as u64);
            (seconds, read)
        })
        .collect();
    runs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (seconds, read) = runs[runs.len() / 2];
    println!(
        "{WINDOWS} windows x {TRIALS} trials: {read} values read in the passes, {seconds:.3} s \
         (median of {}), {:.2} ns a value",
        runs.len(),
        seconds * 1e9 / read as f64
    );
}
