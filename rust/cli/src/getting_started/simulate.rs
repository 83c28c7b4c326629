//! `sitar simulate`: synthetic trials with ground truth.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use rayon::prelude::*;
use sitar_core::{DisplayRotation, SessionConfig};
use sitar_estimator::{TimeUnit, Trajectory, write_tum};
use sitar_sim::{MAX_VENUE_USERS, Recording, Tracker, TrialOptions, Venue, play_trial_with};

use crate::io::input::progress_bar;

/// Simulates a walk through a room and N repeated SLAM-like trials, with ground truth.
///
/// The demo room has a blank wall and a glass pane among textured surfaces; the trials drift
/// and disagree most where the camera faces them.
///
/// Writes into DIR: ground_truth.txt, trials/trajectory_0.txt … (TUM), scene.json (room,
/// hard surfaces, surface faced and tracking difficulty per frame) and recording.sitarsim
/// (what the phone would upload; the backend's `sim` playback replays it). With
/// `--sequences N`: DIR/seq_00 … DIR/seq_{N-1}, each like the above with both trial sets
/// (trials = set A, trials-b = set B), and DIR/sequences.json listing them. With `--venue
/// --users N`: a printed anchor on the demo room's north wall and N users, each in
/// DIR/user_00 … like the above plus session/ (the phone's session folder, in the phone's own
/// world frame, with anchors.csv) and truth.json (its world-from-venue transform), and
/// DIR/venue.json listing them.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar simulate --out sim --trials 20 && sitar estimate sim/trials\n  sitar simulate --out eval --sequences 8 --trials 100 --seconds 30 --tracker ransac\n  sitar evaluate eval --trial_counts 5,10,20,30,100\n  sitar simulate --out venue --venue --users 3"
)]
pub struct Args {
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Number of trials.
    #[arg(short = 'n', long, default_value_t = 20)]
    trials: u32,
    /// Walk duration in seconds (default 15; 20 with --venue, so that every walk passes the
    /// anchor).
    #[arg(long)]
    seconds: Option<f64>,
    /// Camera frame rate.
    #[arg(long, default_value_t = 30.0)]
    fps: f64,
    /// Seed of everything random.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Probability that a trial misses a frame's pose (never the first or last).
    #[arg(long = "drop_frames", alias = "drop-frames", default_value_t = 0.0)]
    drop_frames: f64,
    /// Also write as many further, disjoint trials to DIR/trials-b (for `sitar evaluate`).
    #[arg(long = "second_set", alias = "second-set")]
    second_set: bool,
    /// Timestamps in the TUM files: ns (integers, as ARCore) or s (9 decimals).
    #[arg(long = "time_unit", alias = "time-unit", value_enum, default_value_t = Unit::Ns)]
    time_unit: Unit,
    /// Who plays the trials: `model` (the fast error model) or `ransac` (the mechanistic
    /// RANSAC visual-inertial tracker).
    #[arg(long, value_enum, default_value_t = TrackerArg::Model)]
    tracker: TrackerArg,
    /// Write N sequences (different rooms, walks, light and seeds), each with sets A and B.
    #[arg(long, value_name = "N")]
    sequences: Option<u32>,
    /// The room: `demo`, or `dark-wall` (the consistently-wrong scene: every trial coasts
    /// alike on the IMU while facing an unlit wall; implies the RANSAC tracker).
    #[arg(long, value_enum, default_value_t = SceneArg::Demo)]
    scene: SceneArg,
    /// Simulate a venue: the demo room with a printed A4 anchor, walked by --users users,
    /// each phone in its own world frame.
    #[arg(long, requires = "users", conflicts_with = "sequences")]
    venue: bool,
    /// Users of the venue (with --venue).
    #[arg(long, value_name = "N", requires = "venue")]
    users: Option<u32>,
}

impl Args {
    fn seconds(&self) -> f64 {
        self.seconds
            .unwrap_or(if self.venue { VENUE_SECONDS } else { 15.0 })
    }
}

/// A venue walk's default length: five stops, so every walk passes the anchor.
const VENUE_SECONDS: f64 = 20.0;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum TrackerArg {
    /// The error model: drift whose size and spread follow the view's difficulty.
    Model,
    /// The RANSAC visual-inertial tracker: the spread arises from its random sampling.
    Ransac,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum SceneArg {
    /// The demo room (blank wall, glass pane, painting, bookshelf).
    Demo,
    /// The demo room with the blank wall unlit.
    DarkWall,
}

/// The largest `--sequences`: each sequence is a full set of files.
const MAX_SEQUENCES: u32 = 1000;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Unit {
    /// Integer nanoseconds.
    Ns,
    /// Decimal seconds.
    S,
}

pub fn run(args: Args) -> Result<()> {
    if !(0.0..1.0).contains(&args.drop_frames) {
        bail!("--drop_frames must be in [0, 1), got {}", args.drop_frames);
    }
    let tracker = match args.tracker {
        TrackerArg::Model => Tracker::Model,
        TrackerArg::Ransac => Tracker::Ransac,
    };
    let unit = match args.time_unit {
        Unit::Ns => TimeUnit::Nanoseconds,
        Unit::S => TimeUnit::Seconds,
    };
    if args.venue {
        if args.scene != SceneArg::Demo {
            bail!("--venue walks the demo room; --scene does not apply");
        }
        return write_venue(&args, tracker, unit);
    }
    let Some(count) = args.sequences else {
        let recording = match args.scene {
            SceneArg::Demo => Recording::demo(args.seconds(), args.fps, args.seed)
                .map(|r| r.with_tracker(tracker)),
            SceneArg::DarkWall => Recording::dark_wall(args.seconds(), args.fps, args.seed),
        }
        .context("simulating the walk")?;
        write_sequence(&args, &recording, &args.out, args.second_set, unit)?;
        return Ok(());
    };
    if !(1..=MAX_SEQUENCES).contains(&count) {
        bail!("--sequences must be between 1 and {MAX_SEQUENCES}, got {count}");
    }
    if args.scene != SceneArg::Demo {
        bail!("--scene picks the room of a single sequence; --sequences makes its own rooms");
    }
    let mut names = Vec::new();
    for index in 0..count {
        let recording = Recording::sequence(index, args.seconds(), args.fps, args.seed, tracker)
            .with_context(|| format!("simulating sequence {index}"))?;
        let name = format!("seq_{index:02}");
        write_sequence(&args, &recording, &args.out.join(&name), true, unit)?;
        names.push(name);
    }
    let index = serde_json::json!({
        "format": "sitar-sequences",
        "version": 1,
        "tracker": tracker,
        "seed": args.seed,
        "trials_per_set": args.trials,
        "seconds": args.seconds(),
        "fps": args.fps,
        "sequences": names,
    });
    write_file(
        &args.out.join("sequences.json"),
        format!("{index:#}\n").as_bytes(),
    )
}

/// `--venue`: the venue's users, each a sequence plus the phone's session folder and the
/// truth, and venue.json listing them.
fn write_venue(args: &Args, tracker: Tracker, unit: TimeUnit) -> Result<()> {
    let users = args.users.unwrap_or(1) as usize;
    if !(1..=MAX_VENUE_USERS).contains(&users) {
        bail!("--users must be between 1 and {MAX_VENUE_USERS}, got {users}");
    }
    let venue = Venue::demo(users, args.seconds(), args.fps, args.seed)
        .context("simulating the venue's walks")?;
    let config = SessionConfig::from_json(r#"{"convention":"arcore"}"#)?;
    let mut listed = Vec::new();
    for user in &venue.users {
        let name = format!("user_{:02}", user.index);
        let dir = args.out.join(&name);
        let recording = user.recording.clone().with_tracker(tracker);
        write_sequence(args, &recording, &dir, args.second_set, unit)?;
        let session = user
            .phone_session(config.clone(), DisplayRotation::Deg90)
            .with_context(|| format!("recording user {}'s phone session", user.index))?;
        let session_dir = dir.join("session");
        session
            .save(&session_dir)
            .with_context(|| format!("{}: cannot save the session", session_dir.display()))?;
        write_file(
            &dir.join("truth.json"),
            user.truth_json(&venue.anchor.id).as_bytes(),
        )?;
        let full = user
            .observations
            .iter()
            .filter(|o| o.tracking == sitar_core::Tracking::Full)
            .count();
        eprintln!(
            "user {}: {} anchor observations ({full} full), world frame {:.2} m and {:.1}° from the venue's",
            user.index,
            user.observations.len(),
            user.truth.translation.length(),
            user.truth.heading_rad.to_degrees()
        );
        listed.push(serde_json::json!({
            "dir": name,
            "seed": user.seed,
            "observations": user.observations.len(),
            "full_observations": full,
        }));
    }
    let anchor = &venue.anchor;
    let index = serde_json::json!({
        "format": "sitar-venue-sim",
        "version": 1,
        "convention": "arcore",
        "anchor": {
            "id": anchor.id,
            "position": anchor.pose.position.to_array(),
            "rotation_xyzw": anchor.pose.rotation.to_array(),
            "width_m": anchor.width_m,
            "height_m": anchor.height_m,
        },
        "hard_surfaces": venue.room.hard_surfaces().iter().map(|s| &s.name).collect::<Vec<_>>(),
        "tracker": tracker,
        "seed": args.seed,
        "trials": args.trials,
        "seconds": args.seconds(),
        "fps": args.fps,
        "users": listed,
    });
    write_file(
        &args.out.join("venue.json"),
        format!("{index:#}\n").as_bytes(),
    )
}

/// One sequence's files: ground truth, scene, recording, set A and (optionally) set B.
fn write_sequence(
    args: &Args,
    recording: &Recording,
    out: &Path,
    second_set: bool,
    unit: TimeUnit,
) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
    write_trajectory(
        &recording.walk().ground_truth,
        unit,
        &out.join("ground_truth.txt"),
    )?;
    write_file(&out.join("scene.json"), recording.scene_json().as_bytes())?;
    write_file(&out.join("recording.sitarsim"), &recording.to_bytes())?;

    let options = TrialOptions {
        drop_probability: args.drop_frames,
    };
    let mut sets = vec![(out.join("trials"), 0u32)];
    if second_set {
        sets.push((out.join("trials-b"), args.trials));
    }
    let bar = progress_bar(
        u64::from(args.trials) * sets.len() as u64,
        "simulating trials",
    );
    for (dir, first_index) in &sets {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create", dir.display()))?;
        (0..args.trials).into_par_iter().try_for_each(|k| {
            let trial = play_trial_with(recording, first_index + k, &options);
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
        if second_set { " per set" } else { "" },
        out.display()
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
