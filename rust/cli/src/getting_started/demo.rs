//! `sitar demo`: the whole system end to end on one machine, no set-up.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use sitar_client::{Client, NewSession, SessionFrame, SessionOptions, SessionState};
use sitar_core::{DisplayRotation, ErrorClass, Session as PhoneSession, SessionConfig};
use sitar_estimator::Calibration;
use sitar_server::{PlaybackKind, PresetToken, Role, Server, ServerConfig};
use sitar_sim::Recording;

use crate::getting_started::demo_walk;

/// Runs the whole system in one process: a simulated user walks a room with a blank wall and
/// a glass pane, the phone logic (sitar-core) records the walk with depth and, with a
/// calibration fitted for the simulated SLAM, colours it the moment it stops; the phone's log
/// (its walk among it) and the recording go to an in-process server (sim playback) through
/// the HTTP client, which publishes first results from the walk and refines them with the
/// replays; the results come back and markers are placed; prints what was found (how many
/// sub-trajectories the replays changed the class of) and writes the report page (one file
/// that opens from disk).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar demo\n  sitar demo --serve   # then open the printed address\n  sitar demo --venue   # three users, one venue map"
)]
pub struct Args {
    /// Data directory of the in-process server (default: DEMO_DIR in the system temp dir).
    #[arg(long, value_name = "DIR")]
    data: Option<PathBuf>,
    /// Playback trials.
    #[arg(short = 'n', long, default_value_t = 8)]
    trials: u32,
    /// Walk duration in seconds (30 fps; default 15, with --venue 20).
    #[arg(long)]
    seconds: Option<f64>,
    /// Playback speed: the simulated phones replay this many times faster than real time.
    #[arg(long, default_value_t = 8.0)]
    speed: f64,
    /// Simulated playback phones.
    #[arg(long, default_value_t = DEMO_DEVICES)]
    devices: u32,
    /// Seed of the walk and the trials.
    #[arg(long, default_value_t = 42)]
    seed: u64,
    /// Adaptive stopping: finish once no sub-trajectory changed class over 3 trials, after this many.
    #[arg(long, value_name = "MIN_TRIALS")]
    adaptive: Option<u32>,
    /// How the phone is held: the clockwise turn (degrees) from the landscape depth image to
    /// the screen; 90 is a phone held upright, 0 one held sideways.
    #[arg(long, default_value_t = 90, value_parser = parse_display_rotation)]
    display_rotation: i32,
    /// After the demo, keep the backend running with its data and print the served
    /// report's address (with its token) until Ctrl-C.
    #[arg(long)]
    serve: bool,
    /// Three users walk the demo room with a printed anchor on its wall; their sessions join
    /// one venue, and its map is checked against the room's truth (see `demo_venue.rs`).
    #[arg(long, conflicts_with_all = ["serve", "adaptive"])]
    venue: bool,
}

fn parse_display_rotation(text: &str) -> Result<i32, String> {
    let degrees: i32 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number of degrees"))?;
    DisplayRotation::from_degrees(degrees)
        .map(|_| degrees)
        .map_err(|_| format!("{degrees} is not 0, 90, 180 or 270"))
}

const DEMO_DIR: &str = "sitar-demo";

/// The demo's simulated playback phones (also `sitar serve --sim-devices`'s default).
pub const DEMO_DEVICES: u32 = 2;

/// The in-process backend: sim playback on `data`, the demo's own admin token, the demo's
/// calibration.
fn server_config(
    args: &Args,
    data: &Path,
    token: &str,
    calibration: Option<&Calibration>,
) -> Result<ServerConfig> {
    let mut config = ServerConfig::new(data);
    if let Some(calibration) = calibration {
        config
            .calibrations
            .insert(demo_walk::CALIBRATION_NAME, calibration.clone())?;
    }
    config.playback = PlaybackKind::Sim;
    config.sim.speed = args.speed;
    config.sim.devices = args.devices;
    // The demo's own server plays what it is asked for.
    config.max_trials = config.max_trials.max(args.trials);
    config.preset_tokens = vec![PresetToken {
        name: "demo".into(),
        role: Role::Admin,
        token: token.to_owned(),
    }];
    Ok(config)
}

/// Step 1: the user walks the room; the phone logic records poses and depth like on a phone.
fn walk(args: &Args) -> Result<(Recording, PhoneSession)> {
    let recording = Recording::demo(args.seconds.unwrap_or(15.0), 30.0, args.seed)
        .context("cannot simulate the walk")?;
    let display = DisplayRotation::from_degrees(args.display_rotation)?;
    let session = recording.phone_session(
        SessionConfig::from_json(r#"{"convention":"arcore"}"#)?,
        display,
    )?;
    let summary = session
        .summary()
        .context("the phone session has no summary after stop")?;
    println!(
        "walk        {} frames, {:.1} s, {:.1} m; {} sub-trajectories, {} depth samples (mean {:.2} m)",
        summary.frames,
        summary.duration_s,
        summary.length_m,
        summary.subtrajectories,
        summary.depth_samples,
        summary.mean_depth_m
    );
    Ok((recording, session))
}

/// Step 2: the recording and the camera evidence go up through the client, as the phone's
/// native library sends them. The session's id.
fn upload(
    client: &Client,
    args: &Args,
    data: &Path,
    recording: &Recording,
    session: &PhoneSession,
) -> Result<String> {
    let rec_path = data.join("demo-recording.sitarsim");
    std::fs::write(&rec_path, recording.to_bytes())
        .with_context(|| format!("cannot write {}", rec_path.display()))?;
    let request = NewSession {
        trials: args.trials,
        setting: sitar_core::DEFAULT_SETTING.into(),
        playback: "sim".into(),
        window_frames: None,
        pose_relation: None,
    };
    let options = SessionOptions {
        adaptive_min_trials: args.adaptive,
        calibration: Some(demo_walk::CALIBRATION_NAME.into()),
        ..SessionOptions::default()
    };
    let frame = SessionFrame {
        convention: Some("arcore".into()),
        ..SessionFrame::default()
    };
    let id = client.create_session_in(&request, &options, &frame)?;
    // The phone's log before the recording, as the phone sends it: with the walk, the
    // backend publishes first results at once.
    let phone_dir = data.join("demo-phone-session");
    session
        .save(&phone_dir)
        .with_context(|| format!("cannot save the phone session to {}", phone_dir.display()))?;
    client.upload_phone_logs(&id, &phone_dir)?;
    let first = client.results_json(&id)?;
    println!(
        "backend     first results at upload, from {}, before any replay",
        demo_walk::source_of(&first)
    );
    let mut uploaded = 0;
    client.upload_recording(&id, &rec_path, &mut |sent, _| uploaded = sent)?;
    println!(
        "session     {id}: {uploaded} bytes uploaded, {} trials playing",
        args.trials
    );
    // The camera evidence (thumbnails, image properties, likely causes): the report's
    // regions show it.
    if let Some(thumbnails) = client.upload_evidence(&id, &phone_dir)? {
        println!("evidence    {thumbnails} camera thumbnails and their image properties sent");
    }
    Ok(id)
}

/// Step 3: progress while the phones play, progressive results as they come; fails unless
/// the session ends done.
fn wait(client: &Client, id: &str) -> Result<()> {
    let started = Instant::now();
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template("playback    [{bar:30}] {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut last_results = 0;
    let mut first_results_s = None;
    let status = client.wait(
        id,
        Duration::from_millis(100),
        Duration::from_secs(600),
        &mut |s| {
            bar.set_position((s.progress * 1000.0) as u64);
            let eta = s
                .eta_s
                .map(|e| format!(", ETA {e:.1} s"))
                .unwrap_or_default();
            bar.set_message(format!(
                "{} {}/{} trials{eta}",
                s.state, s.trials_done, s.trials_total
            ));
            if s.results_trials > last_results {
                last_results = s.results_trials;
                let t = started.elapsed().as_secs_f64();
                first_results_s.get_or_insert(t);
                let from = client
                    .results_json(id)
                    .map(|json| demo_walk::source_of(&json))
                    .unwrap_or_else(|_| format!("{} runs", s.results_trials));
                let line = format!("results     after {t:.1} s: from {from}");
                if bar.is_hidden() {
                    println!("{line}")
                } else {
                    bar.println(line)
                }
            }
        },
    )?;
    bar.finish_and_clear();
    if status.state != SessionState::Done {
        bail!(
            "session {id} {}: {}",
            status.state,
            status.error.unwrap_or_default()
        );
    }
    let total_s = started.elapsed().as_secs_f64();
    println!(
        "done        {} trials in {total_s:.1} s (first results after {:.1} s){}",
        status.trials_done,
        first_results_s.unwrap_or(total_s),
        status
            .stop_reason
            .map(|r| format!("; {r}"))
            .unwrap_or_default()
    );
    Ok(())
}

/// Step 4: results back on the phone, replacing its instant colours (how many changed
/// class), markers placed, and checked against the room's truly hard surfaces.
fn markers(
    client: &Client,
    id: &str,
    recording: &Recording,
    session: &mut PhoneSession,
    instant: &[ErrorClass],
) -> Result<()> {
    let json = client.results_json(id)?;
    session.load_results(&json)?;
    let refined = demo_walk::classes(session);
    println!(
        "refined     from {} (backend): {}; {} of {} sub-trajectories changed class",
        demo_walk::source_of(&json),
        demo_walk::counts(&refined),
        demo_walk::changed(instant, &refined),
        refined.len()
    );
    let markers = session.markers()?;
    println!(
        "regions     {}{}",
        plural(markers.len(), "marker"),
        if session.results_unreliable() {
            " (results flagged unreliable)"
        } else {
            ""
        }
    );
    let room = recording.room();
    let hard: Vec<&str> = room
        .hard_surfaces()
        .iter()
        .map(|s| s.name.as_str())
        .collect();
    let mut on_hard = 0;
    let mut found = std::collections::BTreeSet::new();
    for (i, m) in markers.iter().enumerate() {
        let class = match m.class {
            ErrorClass::High => "high",
            ErrorClass::Medium => "medium",
            _ => "low",
        };
        let (name, kind_hard, distance) = match room.nearest_surface(m.position) {
            Some((s, d)) => (s.name.clone(), s.kind.is_hard(), d),
            None => ("nothing".into(), false, f64::NAN),
        };
        if kind_hard {
            on_hard += 1;
            found.insert(name.clone());
        }
        let causes = session
            .evidence_of(m.subtrajectory)
            .map(|e| e.causes.to_string())
            .unwrap_or_default();
        println!(
            "  {}. sub-trajectory {:>3}: error {:5.1} cm ({class:6}) → {name} ({}, {:.2} m off) {}",
            i + 1,
            m.subtrajectory,
            m.error_m * 100.0,
            if kind_hard { "hard" } else { "not hard" },
            distance,
            if causes.is_empty() {
                "no cause seen"
            } else {
                causes.as_str()
            }
        );
    }
    let missed: Vec<&str> = hard
        .iter()
        .copied()
        .filter(|h| !found.contains(*h))
        .collect();
    println!(
        "match       {on_hard}/{} markers on truly hard surfaces; hard surfaces found: {}/{}{}",
        markers.len(),
        found.len(),
        hard.len(),
        if missed.is_empty() {
            String::new()
        } else {
            format!(" (missed: {})", missed.join(", "))
        }
    );
    Ok(())
}

/// `1 marker`, `3 markers`.
fn plural(n: usize, one: &str) -> String {
    format!("{n} {one}{}", if n == 1 { "" } else { "s" })
}

/// Step 5: the report as one file that opens from disk (`GET …/report?download=1`: script,
/// style, scene data and thumbnails inline), written into `data`.
fn write_report(server_url: &str, token: &str, id: &str, data: &Path) -> Result<PathBuf> {
    let url = format!("{server_url}/v1/sessions/{id}/report?download=1");
    let html = ureq::get(&url)
        .header("authorization", &format!("Bearer {token}"))
        .call()
        .and_then(|mut r| r.body_mut().with_config().limit(256 << 20).read_to_string())
        .with_context(|| format!("cannot fetch the report of {id}"))?;
    let report = data.join(format!("report-{id}.html"));
    std::fs::write(&report, html).with_context(|| format!("cannot write {}", report.display()))?;
    Ok(report)
}

pub fn run(args: Args) -> Result<()> {
    let started = Instant::now();
    if args.trials < 2 {
        bail!("--trials must be at least 2 (an estimate compares pairs of trials)");
    }
    let data = args.data.clone().unwrap_or_else(|| {
        std::env::temp_dir().join(if args.venue {
            crate::getting_started::demo_venue::DEMO_DIR
        } else {
            DEMO_DIR
        })
    });
    std::fs::create_dir_all(&data).with_context(|| format!("cannot create {}", data.display()))?;
    // The demo's own token, fresh each run (a new hash under the same name).
    let token = sitar_server::new_token()?;
    // The calibration for the simulated SLAM: the phone's and the backend's (the venue demo
    // goes without).
    let fitted = match args.venue {
        true => None,
        false => Some(demo_walk::fit(args.seed)?),
    };
    // The backend, in-process on a free loopback port.
    let config = server_config(&args, &data, &token, fitted.as_ref().map(|(c, _)| c))?;
    let server = Server::spawn(config, "127.0.0.1:0".parse()?)
        .context("cannot start the in-process server")?;
    println!(
        "server      {} (sim playback, {} phones at {}×, data {})",
        server.url(),
        args.devices,
        args.speed,
        data.display()
    );
    if args.venue {
        let options = crate::getting_started::demo_venue::Options {
            data: data.clone(),
            users: crate::getting_started::demo_venue::VENUE_USERS,
            trials: args.trials,
            seconds: args
                .seconds
                .unwrap_or(crate::getting_started::demo_venue::VENUE_SECONDS),
            seed: args.seed,
        };
        let result = crate::getting_started::demo_venue::run(&options, &server.url(), &token);
        server.stop();
        return result;
    }
    let (calibration, took) = fitted.context("no calibration")?;
    println!(
        "calibration {} for the simulated SLAM: fitted on {} other simulated walks with ground truth in {:.1} s",
        demo_walk::CALIBRATION_NAME,
        calibration.fitted_on.sequences.len(),
        took.as_secs_f64()
    );
    let (recording, mut session) = walk(&args)?;
    let instant = demo_walk::colour_walk(&mut session, &calibration)?;
    let client = Client::new(&server.url())?.with_server_token(&token)?;
    let id = upload(&client, &args, &data, &recording, &session)?;
    wait(&client, &id)?;
    markers(&client, &id, &recording, &mut session, &instant)?;
    let report = write_report(&server.url(), &token, &id, &data)?;
    println!("report      {} (opens from disk)", report.display());
    println!("total       {:.1} s", started.elapsed().as_secs_f64());
    let url = server.url();
    server.stop();
    if args.serve {
        serve(&args, &data, &token, &url, &id, &calibration)?;
    }
    Ok(())
}

/// `--serve`: the backend again on the same address, until Ctrl-C, with the served report's
/// URL (its token included: the page keeps it in a cookie).
fn serve(
    args: &Args,
    data: &Path,
    token: &str,
    url: &str,
    id: &str,
    calibration: &Calibration,
) -> Result<()> {
    let addr: std::net::SocketAddr = url
        .trim_start_matches("http://")
        .parse()
        .with_context(|| format!("the demo's server address {url}"))?;
    println!("served      {url}/v1/sessions/{id}/report?token={token}");
    println!("            (the backend keeps running with the demo's data: Ctrl-C stops it)");
    Server::run(server_config(args, data, token, Some(calibration))?, addr)
        .context("the demo's server stopped")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_short_demo_runs_end_to_end_and_writes_the_report() {
        let dir = tempfile::tempdir().unwrap();
        let args = Args {
            data: Some(dir.path().to_path_buf()),
            trials: 3,
            seconds: Some(4.0),
            speed: 40.0,
            devices: 2,
            seed: 7,
            adaptive: None,
            display_rotation: 90,
            serve: false,
            venue: false,
        };
        run(args).unwrap();
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        let report = names
            .iter()
            .find(|n| n.starts_with("report-s") && n.ends_with(".html"))
            .unwrap_or_else(|| panic!("{names:?}"));
        assert!(names.iter().any(|n| n == "sitar.db"));
        demo_walk::tests::assert_started_from_the_walk(dir.path(), report, 3);
        // The page stands alone: its script, style and scene inline, nothing to fetch.
        let html = std::fs::read_to_string(dir.path().join(report)).unwrap();
        assert!(html.contains("<script type=\"module\">"));
        assert!(html.contains("<script type=\"application/json\" id=\"scene-data\">"));
        assert!(html.contains("<style>"));
        assert!(!html.contains("src=\"/"), "a server path in the saved page");
        assert!(
            !html.contains("href=\"/"),
            "a server link in the saved page"
        );
    }

    #[test]
    fn the_recorded_walk_has_a_depth_sample_at_every_midpoint_not_facing_glass() {
        let recording = Recording::demo(4.0, 30.0, 1).unwrap();
        let session = recording
            .phone_session(
                SessionConfig::from_json(r#"{"convention":"arcore"}"#).unwrap(),
                DisplayRotation::Deg90,
            )
            .unwrap();
        let summary = session.summary().unwrap();
        assert_eq!(summary.frames as usize, recording.frames() - 2);
        assert_eq!(summary.subtrajectories, summary.frames / 10);
        let gt = &recording.walk().ground_truth;
        let logged = session.logged();
        for sub in session.subtrajectories() {
            let mid = &logged[2 * sub.index as usize + 1];
            let i = gt.stamps.iter().position(|&t| t == mid.t_ns).unwrap();
            let facing = recording
                .room()
                .raycast(gt.positions[i], gt.orientations[i] * -glam::DVec3::Z)
                .unwrap();
            if facing.surface != sitar_sim::SurfaceKind::Glass {
                assert!(
                    sub.depth.sample().is_some(),
                    "{sub:?} facing {}",
                    facing.surface_name
                );
            }
        }
        // Every midpoint also has its camera image.
        assert!(session.midpoint_inputs().iter().all(|m| m.image.is_some()));
        assert!(summary.mean_depth_m > 0.5 && summary.mean_depth_m < 6.0);
    }

    /// On the simulated walk, the sub-trajectories whose midpoint faces the blank wall are
    /// `low_texture` and those facing the glass `no_depth`, while views of the painting,
    /// bookshelf and rug are neither.
    #[test]
    fn the_causes_name_the_blank_wall_and_the_glass() {
        let recording = Recording::demo(15.0, 30.0, 7).unwrap();
        let session = recording
            .phone_session(
                SessionConfig::from_json(r#"{"convention":"arcore"}"#).unwrap(),
                DisplayRotation::Deg90,
            )
            .unwrap();
        let gt = &recording.walk().ground_truth;
        let logged = session.logged();
        let mut by_kind: std::collections::BTreeMap<String, (usize, usize, usize)> =
            Default::default();
        for e in session.evidence() {
            let mid = &logged[2 * e.index as usize + 1];
            let i = gt.stamps.iter().position(|&t| t == mid.t_ns).unwrap();
            let facing = recording
                .room()
                .raycast(gt.positions[i], gt.orientations[i] * -glam::DVec3::Z)
                .unwrap();
            let entry = by_kind.entry(format!("{:?}", facing.surface)).or_default();
            entry.0 += 1;
            entry.1 += usize::from(e.causes.contains(sitar_core::Causes::LOW_TEXTURE));
            entry.2 += usize::from(e.causes.contains(sitar_core::Causes::NO_DEPTH));
        }
        println!("facing kind: (sub-trajectories, low_texture, no_depth) {by_kind:?}");
        let share = |kind: &str, f: fn(&(usize, usize, usize)) -> usize| {
            let c = by_kind.get(kind).copied().unwrap_or_default();
            assert!(c.0 > 0, "the walk never faces {kind}: {by_kind:?}");
            f(&c) as f64 / c.0 as f64
        };
        assert!(share("Blank", |c| c.1) >= 0.8, "{by_kind:?}");
        assert!(share("Glass", |c| c.2) >= 0.8, "{by_kind:?}");
        assert!(share("Textured", |c| c.1) <= 0.2, "{by_kind:?}");
        assert!(share("Textured", |c| c.2) <= 0.2, "{by_kind:?}");
    }

    /// However the phone is held, the centre of the depth image is the same ray: every
    /// display rotation finds the same surface points and normals.
    #[test]
    fn the_walk_finds_the_same_surfaces_for_every_display_rotation() {
        let recording = Recording::demo(4.0, 30.0, 3).unwrap();
        let samples = |display| {
            let session = recording
                .phone_session(
                    SessionConfig::from_json(r#"{"convention":"arcore"}"#).unwrap(),
                    display,
                )
                .unwrap();
            session
                .subtrajectories()
                .iter()
                .filter_map(|k| k.depth.sample().copied())
                .collect::<Vec<_>>()
        };
        let upright = samples(DisplayRotation::Deg0);
        assert!(!upright.is_empty());
        for display in [
            DisplayRotation::Deg90,
            DisplayRotation::Deg180,
            DisplayRotation::Deg270,
        ] {
            let turned = samples(display);
            assert_eq!(turned.len(), upright.len());
            for (a, b) in upright.iter().zip(&turned) {
                assert!(
                    (a.point - b.point).length() < 1e-9,
                    "{display:?}: {a:?} vs {b:?}"
                );
                assert!(
                    a.normal.angle_between(b.normal) < 1e-6,
                    "{display:?}: {a:?} vs {b:?}"
                );
            }
        }
    }
}
