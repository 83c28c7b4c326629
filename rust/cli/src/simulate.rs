//! `sitar simulate`: synthetic trials with ground truth.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use rayon::prelude::*;
use sitar_estimator::{TimeUnit, Trajectory, write_tum};
use sitar_sim::{Recording, TrialOptions, play_trial_with};

use crate::input::progress_bar;

/// Simulates a walk through a room and N repeated SLAM-like trials, with ground truth.
///
/// The demo room has a blank wall and a glass pane among textured surfaces; the trials drift
/// and disagree most where the camera faces them.
///
/// Writes into DIR: ground_truth.txt, trials/trajectory_0.txt … (TUM), scene.json (room,
/// hard surfaces, surface faced and tracking difficulty per frame) and recording.sitarsim
/// (what the phone would upload; the backend's `sim` playback replays it).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example: sitar simulate --out sim --trials 20 && sitar estimate sim/trials"
)]
pub struct Args {
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Number of trials.
    #[arg(short = 'n', long, default_value_t = 20)]
    trials: u32,
    /// Walk duration in seconds.
    #[arg(long, default_value_t = 15.0)]
    seconds: f64,
    /// Camera frame rate.
    #[arg(long, default_value_t = 30.0)]
    fps: f64,
    /// Seed of everything random.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Probability that a trial misses a frame's pose (never the first or last).
    #[arg(long = "drop-frames", default_value_t = 0.0)]
    drop_frames: f64,
    /// Also write as many further, disjoint trials to DIR/trials-b (for `sitar evaluate`).
    #[arg(long = "second-set")]
    second_set: bool,
    /// Timestamps in the TUM files: ns (integers, as ARCore) or s (9 decimals).
    #[arg(long = "time-unit", value_enum, default_value_t = Unit::Ns)]
    time_unit: Unit,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Unit {
    /// Integer nanoseconds.
    Ns,
    /// Decimal seconds.
    S,
}

pub fn run(args: Args) -> Result<()> {
    if !(0.0..1.0).contains(&args.drop_frames) {
        bail!("--drop-frames must be in [0, 1), got {}", args.drop_frames);
    }
    let recording =
        Recording::demo(args.seconds, args.fps, args.seed).context("simulating the walk")?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create", args.out.display()))?;
    let unit = match args.time_unit {
        Unit::Ns => TimeUnit::Nanoseconds,
        Unit::S => TimeUnit::Seconds,
    };
    write_trajectory(
        &recording.walk().ground_truth,
        unit,
        &args.out.join("ground_truth.txt"),
    )?;
    write_file(
        &args.out.join("scene.json"),
        recording.scene_json().as_bytes(),
    )?;
    write_file(&args.out.join("recording.sitarsim"), &recording.to_bytes())?;

    let options = TrialOptions {
        drop_probability: args.drop_frames,
    };
    let mut sets = vec![(args.out.join("trials"), 0u32)];
    if args.second_set {
        sets.push((args.out.join("trials-b"), args.trials));
    }
    let bar = progress_bar(
        u64::from(args.trials) * sets.len() as u64,
        "simulating trials",
    );
    for (dir, first_index) in &sets {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create", dir.display()))?;
        (0..args.trials).into_par_iter().try_for_each(|k| {
            let trial = play_trial_with(&recording, first_index + k, &options);
            bar.inc(1);
            write_trajectory(&trial, unit, &dir.join(format!("trajectory_{k}.txt")))
        })?;
    }
    bar.finish_and_clear();
    eprintln!(
        "wrote {} frames ({:.2} s), ground truth and {} trial(s){} to {}",
        recording.frames(),
        recording.duration_s(),
        args.trials,
        if args.second_set { " per set" } else { "" },
        args.out.display()
    );
    Ok(())
}

fn write_trajectory(trajectory: &Trajectory, unit: TimeUnit, path: &Path) -> Result<()> {
    let mut trajectory = trajectory.clone();
    trajectory.time_unit = unit;
    let file = File::create(path).with_context(|| format!("{}: cannot create", path.display()))?;
    let mut out = BufWriter::new(file);
    write_tum(&trajectory, &mut out)
        .and_then(|()| std::io::Write::flush(&mut out))
        .with_context(|| format!("{}: cannot write", path.display()))
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).with_context(|| format!("{}: cannot write", path.display()))
}
