//! `estimate_files gen DIR TRIALS POSES [SEED] [uniform]` writes synthetic trials (every third
//! with dropped frames, unless `uniform`);
//! `estimate_files run [--setting S] [--repeat N] FILE...` reads them and prints the legacy CSV
//! (stdout) and the wall time per run (stderr). Used by `scripts/bench-vs-evo`.

use std::path::PathBuf;
use std::time::Instant;

use rayon::prelude::*;
use sitar_estimator::{EstimateOptions, PairwiseValues, Setting, read_tum};

#[path = "support/synthetic.rs"]
mod synthetic;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("gen") if args.len() >= 4 => {
            let seed = args.get(4).map_or(Ok(1), |s| s.parse())?;
            let drops = args.get(5).map(String::as_str) != Some("uniform");
            let paths =
                synthetic::write_trials(&PathBuf::from(&args[1]), args[2].parse()?, args[3].parse()?, seed, drops);
            eprintln!("wrote {} trials", paths.len());
            Ok(())
        }
        Some("run") => {
            let mut opts = EstimateOptions::default();
            let mut repeat = 1;
            let mut files = Vec::new();
            let mut rest = args[1..].iter();
            while let Some(arg) = rest.next() {
                match arg.as_str() {
                    "--setting" => opts.setting = rest.next().ok_or("--setting needs a value")?.parse::<Setting>()?,
                    "--repeat" => repeat = rest.next().ok_or("--repeat needs a value")?.parse()?,
                    file => files.push(PathBuf::from(file)),
                }
            }
            let mut csv = String::new();
            for _ in 0..repeat {
                let start = Instant::now();
                let cpu0 = cpu_seconds();
                let trials = files.par_iter().map(|f| read_tum(f)).collect::<Result<Vec<_>, _>>()?;
                let read = start.elapsed().as_secs_f64();
                let cpu1 = cpu_seconds();
                let values = PairwiseValues::compute(&trials, &opts)?;
                let pairwise = start.elapsed().as_secs_f64();
                let cpu2 = cpu_seconds();
                csv = values.estimate(opts.setting).to_legacy_csv();
                let total = start.elapsed().as_secs_f64();
                let cpu3 = cpu_seconds();
                eprintln!(
                    "cpu_s {:.2} (read {:.2}, pairwise {:.2}, aggregate {:.2})",
                    cpu3 - cpu0,
                    cpu1 - cpu0,
                    cpu2 - cpu1,
                    cpu3 - cpu2
                );
                eprintln!("elapsed_s {total:.6} (read {read:.6}, pairwise {:.6}, aggregate {:.6})", pairwise - read, total - pairwise);
            }
            print!("{csv}");
            Ok(())
        }
        _ => Err("usage: estimate_files gen DIR TRIALS POSES [SEED] | run [--setting S] [--repeat N] FILE...".into()),
    }
}

/// User + system CPU seconds of this process (Linux `/proc/self/stat`; 0 elsewhere).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    // Fields 14 and 15 of stat (utime, stime) are 11 and 12 after the command name; 100 Hz.
    (ticks(11) + ticks(12)) / 100.0
}
