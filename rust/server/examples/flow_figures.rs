//! What progressive results and adaptive stopping give on the simulated flow.
//!
//! `cargo run --release -p sitar-server --example flow_figures`
//!
//! Sessions run on one simulated phone at `SPEED`× real time; times are scaled back to
//! real time (a 15 s walk, like the paper's 5-trial, one-phone setup that took 89 s).

use std::collections::HashMap;
use std::time::{Duration, Instant};

use sitar_client::{Client, NewSession, SessionOptions, SessionState};
use sitar_server::{PlaybackKind, Server, ServerConfig};

const SPEED: f64 = 60.0;

struct Run {
    first_results_s: f64,
    done_s: f64,
    trials: u32,
    classes: HashMap<i64, String>,
}

fn run(client: &Client, recording: &std::path::Path, trials: u32, adaptive: Option<u32>) -> Run {
    let id = client
        .create_session_with(
            &NewSession {
                trials,
                setting: "trim_mean_30".into(),
                playback: "sim".into(),
                window_frames: None,
                pose_relation: None,
            },
            &SessionOptions {
                adaptive_min_trials: adaptive,
                adaptive_k: Some(3),
                ..SessionOptions::default()
            },
        )
        .unwrap();
    client
        .upload_recording(&id, recording, &mut |_, _| {})
        .unwrap();
    let started = Instant::now();
    let mut first = None;
    let status = client
        .wait(
            &id,
            Duration::from_millis(5),
            Duration::from_secs(600),
            &mut |s| {
                if s.results_trials >= 2 && first.is_none() {
                    first = Some(started.elapsed().as_secs_f64());
                }
            },
        )
        .unwrap();
    assert_eq!(status.state, SessionState::Done);
    let done = started.elapsed().as_secs_f64();
    let json: serde_json::Value = serde_json::from_str(&client.results_json(&id).unwrap()).unwrap();
    let classes = json["windows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| {
            (
                w["start"].as_i64().unwrap(),
                w["class"].as_str().unwrap_or("").to_string(),
            )
        })
        .collect();
    Run {
        first_results_s: first.unwrap_or(done) * SPEED,
        done_s: done * SPEED,
        trials: status.trials_done,
        classes,
    }
}

fn agreement(a: &HashMap<i64, String>, b: &HashMap<i64, String>) -> f64 {
    let same = a.iter().filter(|(k, v)| b.get(*k) == Some(*v)).count();
    same as f64 / a.len().max(1) as f64
}

fn main() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = ServerConfig::new(dir.path().join("data"));
    config.playback = PlaybackKind::Sim;
    config.sim.speed = SPEED;
    let server = Server::spawn(config, "127.0.0.1:0".parse().unwrap()).unwrap();
    let admin =
        std::fs::read_to_string(dir.path().join("data").join(sitar_server::ADMIN_TOKEN_FILE))
            .unwrap();
    let client = Client::new(&server.url())
        .unwrap()
        .with_server_token(&admin)
        .unwrap();

    println!("Progressive results (one phone, 15 s walk, real-time seconds):");
    println!("| seed | trials | first results | all trials done | first / done |");
    println!("|---|---|---|---|---|");
    let mut adaptive_rows = Vec::new();
    for seed in [1u64, 2, 3, 42] {
        let path = dir.path().join(format!("walk{seed}.rec"));
        std::fs::write(
            &path,
            sitar_sim::Recording::demo(15.0, 30.0, seed)
                .unwrap()
                .to_bytes(),
        )
        .unwrap();
        let five = run(&client, &path, 5, None);
        println!(
            "| {seed} | 5 | {:.1} s | {:.1} s | {:.2} |",
            five.first_results_s,
            five.done_s,
            five.first_results_s / five.done_s
        );
        let full = run(&client, &path, 20, None);
        println!(
            "| {seed} | 20 | {:.1} s | {:.1} s | {:.2} |",
            full.first_results_s,
            full.done_s,
            full.first_results_s / full.done_s
        );
        let early = run(&client, &path, 20, Some(5));
        adaptive_rows.push(format!(
            "| {seed} | {} of 20 | {:.1} s | {:.1} s | {:.0} % | {:.1} % |",
            early.trials,
            early.done_s,
            full.done_s,
            100.0 * (1.0 - early.done_s / full.done_s),
            100.0 * agreement(&full.classes, &early.classes)
        ));
        // How close the first progressive picture (2 trials) already is, for reference.
        let two = run(&client, &path, 2, None);
        adaptive_rows.push(format!(
            "| {seed} (2 trials only) | 2 of 20 | {:.1} s | {:.1} s | {:.0} % | {:.1} % |",
            two.done_s,
            full.done_s,
            100.0 * (1.0 - two.done_s / full.done_s),
            100.0 * agreement(&full.classes, &two.classes)
        ));
    }
    println!();
    println!(
        "Adaptive stopping (min 5 trials, k = 3; class agreement with the full 20-trial estimate, all windows):"
    );
    println!("| seed | trials run | done after | full run | time saved | same class |");
    println!("|---|---|---|---|---|---|");
    for row in adaptive_rows {
        println!("{row}");
    }
}
