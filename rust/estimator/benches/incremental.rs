//! Progressive estimates, as the backend publishes them: 100 trials × 2820 poses (every third
//! trial drops ~1 % of its frames, as `scripts/bench-vs-evo` makes them), `push` + `estimate()`
//! after each trial from the 2nd on, against one one-shot `estimate` of the 100 trials.
//! Prints medians of CPU time (all threads) and wall time, their ratio, `memory_bytes()` and
//! the peak RSS of each phase. Target: total CPU ≤ 1.5× one one-shot estimate.
//!
//! `cargo bench -p sitar-estimator --bench incremental [-- REPEATS [TRIALS POSES]]`;
//! `-- --progressive-only` or `-- --one-shot-only` runs one phase once in a fresh process
//! (`--setting NAME` picks the setting, default `trim_mean_30`; `--swapped` pushes the
//! progressive phase's trials in swapped pairs, 1 0 3 2 …, each at its place, as two parallel
//! phones may deliver them).

use std::time::Instant;

use sitar_estimator::{EstimateOptions, IncrementalEstimate, PoseRelation, Trajectory, estimate};

#[path = "../examples/support/synthetic.rs"]
mod synthetic;

/// CPU time of every thread of this process so far, in seconds (Linux schedstat: ns).
fn cpu_seconds() -> f64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return f64::NAN;
    };
    let ns: u64 = tasks
        .flatten()
        .filter_map(|t| std::fs::read_to_string(t.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .sum();
    ns as f64 * 1e-9
}

/// Peak resident set since the last [`reset_peak_rss`], in MB.
fn peak_rss_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn reset_peak_rss() {
    // "5" resets the peak RSS to the current RSS (Linux ≥ 4.0).
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

struct Run {
    cpu: f64,
    wall: f64,
    rss: f64,
    memory: usize,
    last_push_cpu: f64,
}

fn one_shot(trials: &[Trajectory], opts: &EstimateOptions) -> Run {
    reset_peak_rss();
    let (cpu, wall) = (cpu_seconds(), Instant::now());
    let result = estimate(trials, opts).expect("estimate");
    let run = Run {
        cpu: cpu_seconds() - cpu,
        wall: wall.elapsed().as_secs_f64(),
        rss: peak_rss_mb(),
        memory: 0,
        last_push_cpu: 0.0,
    };
    assert!(!result.windows.is_empty());
    run
}

fn progressive(trials: &[Trajectory], opts: &EstimateOptions, swapped: bool) -> Run {
    reset_peak_rss();
    let (cpu, wall) = (cpu_seconds(), Instant::now());
    let mut incremental = IncrementalEstimate::new(*opts).expect("options");
    let mut last_push_cpu = 0.0;
    let mut windows = 0;
    let arrivals = (0..trials.len()).map(|i| match (swapped, i % 2) {
        (true, 0) if i + 1 < trials.len() => i + 1,
        (true, 1) => i - 1,
        _ => i,
    });
    for i in arrivals {
        let before = cpu_seconds();
        incremental
            .push_ordered(trials[i].clone(), i as u64)
            .expect("push");
        if incremental.trials() >= 2 {
            windows = incremental.estimate().expect("estimate").windows.len();
        }
        last_push_cpu = cpu_seconds() - before;
    }
    let run = Run {
        cpu: cpu_seconds() - cpu,
        wall: wall.elapsed().as_secs_f64(),
        rss: peak_rss_mb(),
        memory: incremental.memory_bytes(),
        last_push_cpu,
    };
    assert!(windows > 0);
    run
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    // `--progressive-only` / `--one-shot-only`: one run of the first case in a fresh process
    // (for perf, and for a peak RSS that no earlier phase inflates).
    let only = |flag: &str| std::env::args().any(|a| a == flag);
    if only("--progressive-only") || only("--one-shot-only") {
        let trials = synthetic::trials(100, 2820, 11, true);
        let input_mb = peak_rss_mb();
        // `--setting NAME` (default trim_mean_30).
        let argv: Vec<String> = std::env::args().collect();
        let setting = argv
            .iter()
            .position(|a| a == "--setting")
            .and_then(|i| argv.get(i + 1))
            .map(|name| name.parse().expect("a setting name"));
        let opts = EstimateOptions {
            setting: setting.unwrap_or_default(),
            ..EstimateOptions::default()
        };
        let run = if only("--one-shot-only") {
            one_shot(&trials, &opts)
        } else {
            progressive(&trials, &opts, only("--swapped"))
        };
        println!(
            "CPU {:.3} s, wall {:.3} s, memory_bytes {:.1} MB, peak RSS {:.0} MB (trials alone {:.0} MB)",
            run.cpu,
            run.wall,
            run.memory as f64 / 1e6,
            run.rss,
            input_mb
        );
        return;
    }
    let repeats = args.first().copied().unwrap_or(5);
    let (count, poses) = match args[..] {
        [_, c, p, ..] => (c, p),
        _ => (100, 2820),
    };
    println!(
        "progressive estimates: {count} trials x {poses} poses, {repeats} runs each, medians; {} threads",
        rayon::current_num_threads()
    );
    println!(
        "{:<34} {:>9} {:>9} {:>9} {:>9} {:>10} {:>9} {:>10}",
        "case", "one CPU", "prog CPU", "ratio", "one wall", "prog wall", "last push", "mem/RSS"
    );
    for (name, drops, relation) in [
        ("trim_mean_30, drops", true, PoseRelation::TranslationPart),
        (
            "trim_mean_30, identical stamps",
            false,
            PoseRelation::TranslationPart,
        ),
        (
            "trim_mean_30, drops, angle_deg",
            true,
            PoseRelation::RotationAngleDeg,
        ),
    ] {
        let trials = synthetic::trials(count, poses, 11, drops);
        let opts = EstimateOptions {
            pose_relation: relation,
            ..EstimateOptions::default()
        };
        // Interleaved, so that load from other processes hits both alike.
        let (mut once, mut prog) = (Vec::new(), Vec::new());
        for _ in 0..repeats {
            once.push(one_shot(&trials, &opts));
            prog.push(progressive(&trials, &opts, false));
        }
        let m = |runs: &[Run], f: fn(&Run) -> f64| median(runs.iter().map(f).collect());
        let (once_cpu, prog_cpu) = (m(&once, |r| r.cpu), m(&prog, |r| r.cpu));
        println!(
            "{:<34} {:>8.3}s {:>8.3}s {:>8.2}x {:>8.3}s {:>9.3}s {:>8.4}s {:>4.0}/{:.0} MB",
            name,
            once_cpu,
            prog_cpu,
            prog_cpu / once_cpu,
            m(&once, |r| r.wall),
            m(&prog, |r| r.wall),
            m(&prog, |r| r.last_push_cpu),
            prog[0].memory as f64 / 1e6,
            m(&prog, |r| r.rss),
        );
        println!(
            "{:<34} one-shot peak RSS {:.0} MB; ratio of per-run CPU: {}",
            "",
            m(&once, |r| r.rss),
            once.iter()
                .zip(&prog)
                .map(|(o, p)| format!("{:.2}", p.cpu / o.cpu))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
}
