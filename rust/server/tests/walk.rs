//! The backend starts from the walk (issue 41): over loopback against a real server, a
//! session with a calibration publishes first results from the phone's `walk.txt` the moment
//! it arrives, before any replay (`"source": "walk"`, `"runs": 1`, `"target": "live"`);
//! replays refine them (`"source": "replays"`, the runs counting the walk); the route is the
//! owner's, bounded and checked whole; sessions without a calibration keep their results from
//! the replays; the report names the source and the runs, and says when the colours are a
//! guess.

use std::time::{Duration, Instant};

use glam::{DQuat, DVec3};
use serde_json::{Value, json};
use sitar_core::calibration::{
    CALIBRATION_FORMAT, Calibration, CalibrationModel, Feature, FittedOn, IntervalModel, RunCount,
    Target,
};
use sitar_server::{PlaybackKind, Role, Server, ServerConfig, ServerHandle};

mod support;
use support::http::{Answer, call};

/// Poses of the walk and of each trial: 2 s at 30 fps.
const POSES: usize = 60;
/// The walk's first stamp: an ARCore clock 200 s after boot (integer nanoseconds above
/// 100 s, as every reader of TUM text takes them).
const START_NS: i64 = 200_000_000_000;
/// The server's bound on a trial and on the walk, small enough to pass in a test.
const MAX_RUN_BYTES: u64 = 16 << 10;

/// A model of `target` from `runs` runs: ln error = `intercept` + Σ ln(feature + offset),
/// interval ×0.5 … ×2.
fn model(target: Target, runs: RunCount, features: &[Feature], intercept: f64) -> CalibrationModel {
    CalibrationModel {
        target,
        runs,
        kind: "log_linear".into(),
        features: features.to_vec(),
        offsets: features.iter().map(|f| f.offset()).collect(),
        smoothing_windows: 0,
        coefficients: std::iter::once(intercept)
            .chain(features.iter().map(|_| 1.0))
            .collect(),
        spread_match: 0.0,
        center: 0.0,
        stretch: 1.0,
        interval: IntervalModel {
            method: "in_sample".into(),
            log_lower: 0.5f64.ln(),
            log_upper: 2.0f64.ln(),
            residuals: 100,
        },
        informative: true,
        scores: None,
    }
}

/// A version-2 calibration for the default settings (trim_mean_30, 10 frames, trans_part):
/// one run's error is half its path over the window; with replays, twice their spread.
fn calibration(informative: bool) -> Calibration {
    let mut models = vec![
        model(Target::Live, RunCount::One, &[Feature::PathM], 0.5f64.ln()),
        model(
            Target::Live,
            RunCount::Several,
            &[Feature::Spread],
            2.0f64.ln(),
        ),
        model(
            Target::Expected,
            RunCount::Several,
            &[Feature::Spread],
            2.0f64.ln(),
        ),
    ];
    for m in &mut models {
        m.informative = informative;
    }
    Calibration {
        format: CALIBRATION_FORMAT.into(),
        version: 2,
        fitted_on: FittedOn {
            sequences: Vec::new(),
            setting: "trim_mean_30".into(),
            window_frames: 10,
            pose_relation: "trans_part".into(),
            unit: "m".into(),
            coverage: 0.8,
            t_max_diff_s: 0.01,
        },
        informative,
        models,
    }
}

/// The walk (`seed` 0) or a replay of it: 2 cm a frame along x, replays off by a few mm
/// that vary along the walk. TUM text with integer nanoseconds.
fn run(seed: u64) -> String {
    (0..POSES)
        .map(|k| {
            let wobble = if seed == 0 {
                0.0
            } else {
                ((k as u64 * 7 + seed * 13) % 11) as f64 * 1e-3
            };
            let p = DVec3::new(k as f64 * 0.02 + wobble, wobble, 0.0);
            let q = DQuat::from_rotation_y(k as f64 * 0.01);
            format!(
                "{} {} {} {} {} {} {} {}\n",
                START_NS + k as i64 * 33_333_333,
                p.x,
                p.y,
                p.z,
                q.x,
                q.y,
                q.z,
                q.w
            )
        })
        .collect()
}

struct World {
    dir: tempfile::TempDir,
    server: ServerHandle,
    owner: String,
    stranger: String,
}

/// The server on `data` with the calibrations `lab` and `guess`.
fn spawn(data: &std::path::Path) -> ServerHandle {
    let mut config = ServerConfig::new(data);
    config.max_trajectory_bytes = MAX_RUN_BYTES;
    config
        .calibrations
        .insert("lab", calibration(true))
        .unwrap();
    config
        .calibrations
        .insert("guess", calibration(false))
        .unwrap();
    Server::spawn(config, "127.0.0.1:0".parse().unwrap()).unwrap()
}

fn start() -> World {
    let dir = tempfile::tempdir().unwrap();
    let server = spawn(dir.path());
    let token = |name| sitar_server::create_token(dir.path(), Role::App, name).unwrap();
    World {
        owner: token("owner"),
        stranger: token("stranger"),
        server,
        dir,
    }
}

impl World {
    fn call(&self, token: &str, method: &str, path: &str, body: &[u8]) -> Answer {
        let content_type = if body.starts_with(b"{") {
            "application/json"
        } else {
            "text/plain"
        };
        call(&self.server, token, method, path, Some(content_type), body)
    }

    fn session(&self, calibration: Option<&str>) -> String {
        let mut body = json!({"trials": 3, "playback": "upload"});
        if let Some(name) = calibration {
            body["calibration"] = json!(name);
        }
        let a = self.call(
            &self.owner,
            "POST",
            "/v1/sessions",
            body.to_string().as_bytes(),
        );
        assert_eq!(a.status, 201, "{}", a.body);
        a.json()["id"].as_str().unwrap().to_owned()
    }

    fn status(&self, id: &str) -> Value {
        let a = self.call(&self.owner, "GET", &format!("/v1/sessions/{id}"), b"");
        assert_eq!(a.status, 200, "{}", a.body);
        a.json()
    }

    fn results(&self, id: &str) -> Value {
        let a = self.call(
            &self.owner,
            "GET",
            &format!("/v1/sessions/{id}/results.json"),
            b"",
        );
        assert_eq!(a.status, 200, "{}", a.body);
        a.json()
    }

    fn put_walk(&self, token: &str, id: &str, text: &str) -> Answer {
        self.call(
            token,
            "PUT",
            &format!("/v1/sessions/{id}/walk.txt"),
            text.as_bytes(),
        )
    }

    fn add_trial(&self, id: &str, seed: u64) {
        let a = self.call(
            &self.owner,
            "POST",
            &format!("/v1/sessions/{id}/trials"),
            run(seed).as_bytes(),
        );
        assert_eq!(a.status, 201, "{}", a.body);
    }

    /// Waits until session `id`'s results have `runs` runs (`results_trials`).
    fn wait_runs(&self, id: &str, runs: u64) -> Value {
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let status = self.status(id);
            if status["results_trials"].as_u64() == Some(runs) {
                return status;
            }
            assert!(Instant::now() < deadline, "{status}");
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    fn report(&self, id: &str) -> String {
        let a = self.call(
            &self.owner,
            "GET",
            &format!("/v1/sessions/{id}/report"),
            b"",
        );
        assert_eq!(a.status, 200, "{}", a.body);
        a.body
    }
}

/// Every window of calibrated results has its bounds around its error.
fn assert_calibrated(results: &Value, windows: usize) {
    let all = results["windows"].as_array().unwrap();
    assert_eq!(all.len(), windows, "{results}");
    for w in all {
        let v = |key: &str| w[key].as_f64().unwrap_or_else(|| panic!("{key} in {w}"));
        assert!(0.0 < v("lower_m") && v("lower_m") <= v("error_m"), "{w}");
        assert!(v("error_m") <= v("upper_m"), "{w}");
    }
}

#[test]
fn first_results_come_from_the_walk_before_any_replay_and_replays_refine_them() {
    let w = start();
    let id = w.session(Some("lab"));
    let no_results = w.call(
        &w.owner,
        "GET",
        &format!("/v1/sessions/{id}/results.json"),
        b"",
    );
    assert_eq!(no_results.status, 409, "{}", no_results.body);

    let a = w.put_walk(&w.owner, &id, &run(0));
    assert_eq!(a.status, 200, "{}", a.body);
    assert_eq!(
        a.json(),
        json!({"poses": POSES, "runs": 1, "source": "walk"}),
        "{}",
        a.body
    );
    // Published at once: no trial, no recording, still `created`.
    let status = w.status(&id);
    assert_eq!(
        (
            &status["state"],
            &status["results_trials"],
            &status["trials_done"]
        ),
        (&json!("created"), &json!(1), &json!(0)),
        "{status}"
    );
    let first = w.results(&id);
    assert_eq!(
        (
            &first["source"],
            &first["runs"],
            &first["target"],
            &first["informative"],
            &first["calibration"],
        ),
        (
            &json!("walk"),
            &json!(1),
            &json!("live"),
            &json!(true),
            &json!("lab")
        ),
        "{first}"
    );
    // One window per start frame with 10 frames after it; half its path (0.2 m): 10 cm.
    assert_calibrated(&first, POSES - 10);
    let error = first["windows"][0]["error_m"].as_f64().unwrap();
    assert!((error - 0.5 * (0.2 + 1e-3)).abs() < 1e-9, "{error}");
    let csv = w.call(
        &w.owner,
        "GET",
        &format!("/v1/sessions/{id}/results.csv"),
        b"",
    );
    assert_eq!(csv.status, 200, "{}", csv.body);
    assert!(
        csv.body.starts_with(&format!("start,error\n{START_NS},")),
        "{}",
        csv.body
    );
    let report = w.report(&id);
    assert!(report.contains("from the walk alone"), "{report}");
    assert!(!report.contains("colours are a guess"), "{report}");

    // Each replay refines it: the walk is the live run, the trials its replays.
    w.add_trial(&id, 1);
    w.wait_runs(&id, 2);
    let refined = w.results(&id);
    assert_eq!(
        (&refined["source"], &refined["runs"], &refined["target"]),
        (&json!("replays"), &json!(2), &json!("live")),
        "{refined}"
    );
    assert_calibrated(&refined, POSES - 10);
    assert_ne!(refined["windows"], first["windows"]);
    w.add_trial(&id, 2);
    w.wait_runs(&id, 3);
    let refined = w.results(&id);
    assert_eq!(
        (&refined["source"], &refined["runs"], &refined["trials"]),
        (&json!("replays"), &json!(3), &json!(3)),
        "{refined}"
    );
    let report = w.report(&id);
    assert!(report.contains("from the walk and 2 replays"), "{report}");

    // The final estimate keeps the walk as the live run.
    w.add_trial(&id, 3);
    let a = w.call(
        &w.owner,
        "POST",
        &format!("/v1/sessions/{id}/estimate"),
        b"",
    );
    assert_eq!(a.status, 202, "{}", a.body);
    let deadline = Instant::now() + Duration::from_secs(60);
    while w.status(&id)["state"] != "done" {
        assert!(Instant::now() < deadline, "{}", w.status(&id));
        std::thread::sleep(Duration::from_millis(20));
    }
    let last = w.results(&id);
    assert_eq!(
        (&last["source"], &last["runs"], &last["target"]),
        (&json!("replays"), &json!(4), &json!("live")),
        "{last}"
    );
    // A walk sent once the session is done is kept, and the results stay as they are.
    let a = w.put_walk(&w.owner, &id, &run(0));
    assert_eq!(a.status, 200, "{}", a.body);
    assert!(
        a.json()["not_estimated"].as_str().unwrap().contains("done"),
        "{}",
        a.body
    );
    assert_eq!(w.results(&id), last);
}

#[test]
fn the_walk_route_is_the_owners_bounded_and_checked_whole() {
    let w = start();
    let id = w.session(Some("lab"));
    // Another app token is told the session does not exist; no token at all is a 401.
    let a = w.put_walk(&w.stranger, &id, &run(0));
    assert_eq!(a.status, 404, "{}", a.body);
    let a = w.put_walk("", &id, &run(0));
    assert_eq!(a.status, 401, "{}", a.body);
    // Checked whole: a stamp that goes back, a fraction of a nanosecond, a short row.
    let walk = run(0);
    let lines: Vec<&str> = walk.lines().collect();
    for (bad, needle) in [
        (
            walk.replacen(
                lines[2],
                &lines[2].replacen("200066666666", "200000000001", 1),
                1,
            ),
            "walk.txt line 3, column `timestamp`",
        ),
        (
            walk.replacen("200033333333 ", "200033333333.5 ", 1),
            "line 2",
        ),
        (walk.replacen(lines[4], "200133333332 0 0 0", 1), "line 5"),
        (String::new(), "walk.txt: no poses"),
    ] {
        let a = w.put_walk(&w.owner, &id, &bad);
        assert_eq!(a.status, 422, "{needle}: {}", a.body);
        assert!(a.message().contains(needle), "{needle}: {}", a.body);
    }
    // Bounded as a trial is: a walk over the bound is refused before anything is stored.
    let long: String = std::iter::repeat_n(walk.as_str(), 8).collect();
    assert!(long.len() as u64 > MAX_RUN_BYTES);
    let a = w.put_walk(&w.owner, &id, &long);
    assert_eq!(a.status, 413, "{}", a.body);
    assert!(a.message().contains("walk.txt"), "{}", a.body);
    let a = w.call(
        &w.owner,
        "GET",
        &format!("/v1/sessions/{id}/results.json"),
        b"",
    );
    assert_eq!(a.status, 409, "nothing published: {}", a.body);
    // Too short for a window: kept, and why there are no results said.
    let a = w.put_walk(&w.owner, &id, &lines[..5].concat_lines());
    assert_eq!(a.status, 200, "{}", a.body);
    let why = a.json()["not_estimated"].as_str().unwrap().to_owned();
    assert!(why.contains("5 poses") && why.contains("11"), "{why}");
}

#[test]
fn without_a_calibration_the_walk_is_kept_and_results_come_from_the_replays() {
    let w = start();
    let id = w.session(None);
    let a = w.put_walk(&w.owner, &id, &run(0));
    assert_eq!(a.status, 200, "{}", a.body);
    assert_eq!(a.json()["poses"], json!(POSES));
    assert!(
        a.json()["not_estimated"]
            .as_str()
            .unwrap()
            .contains("no calibration"),
        "{}",
        a.body
    );
    assert_eq!(w.status(&id)["results_trials"], json!(0));
    w.add_trial(&id, 1);
    w.add_trial(&id, 2);
    w.wait_runs(&id, 2);
    let results = w.results(&id);
    // As before the walk: the paper's spread, no calibration, no source.
    for key in ["source", "runs", "target", "calibration"] {
        assert!(results.get(key).is_none(), "{key}: {results}");
    }
    assert_eq!(results["trials"], json!(2));

    // A calibrated session without a walk: the expected error, from the replays.
    let id = w.session(Some("lab"));
    w.add_trial(&id, 1);
    w.add_trial(&id, 2);
    w.wait_runs(&id, 2);
    let results = w.results(&id);
    assert_eq!(
        (&results["source"], &results["runs"], &results["target"]),
        (&json!("replays"), &json!(2), &json!("expected")),
        "{results}"
    );
}

#[test]
fn after_a_restart_the_stored_walk_is_the_live_run_again() {
    let w = start();
    let id = w.session(Some("lab"));
    assert_eq!(w.put_walk(&w.owner, &id, &run(0)).status, 200);
    w.add_trial(&id, 1);
    w.wait_runs(&id, 2);
    let World {
        dir,
        server,
        owner,
        stranger,
    } = w;
    server.stop();
    let w = World {
        server: spawn(dir.path()),
        dir,
        owner,
        stranger,
    };
    // Read again with the trials: the next estimate has it as the live run.
    w.add_trial(&id, 2);
    w.wait_runs(&id, 3);
    let results = w.results(&id);
    assert_eq!(
        (&results["source"], &results["runs"], &results["target"]),
        (&json!("replays"), &json!(3), &json!("live")),
        "{results}"
    );
}

/// A sim session whose calibration reads the walk's motion alone, with replays too: the
/// replays change no class, and adaptive stopping ends playback at its minimum, the walk
/// still the live run.
#[test]
fn adaptive_stopping_stops_once_the_replays_change_no_class_of_the_walk() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = ServerConfig::new(dir.path());
    config.playback = PlaybackKind::Sim;
    config.sim.speed = 50.0;
    config.sim.devices = 1;
    let mut motion = calibration(true);
    motion.models[1] = model(
        Target::Live,
        RunCount::Several,
        &[Feature::PathM],
        0.5f64.ln(),
    );
    config.calibrations.insert("motion", motion).unwrap();
    let server = Server::spawn(config, "127.0.0.1:0".parse().unwrap()).unwrap();
    let owner = sitar_server::create_token(dir.path(), Role::App, "owner").unwrap();
    let recording = sitar_sim::Recording::demo(4.0, 30.0, 3).unwrap();
    let phone = recording
        .phone_session(
            sitar_core::SessionConfig::from_json(r#"{"convention":"arcore","images":false}"#)
                .unwrap(),
            sitar_core::DisplayRotation::Deg90,
        )
        .unwrap();
    let send = |method: &str, path: &str, content_type: &str, body: &[u8]| {
        call(&server, &owner, method, path, Some(content_type), body)
    };
    let body = json!({"trials": 20, "playback": "sim", "calibration": "motion",
                      "adaptive_min_trials": 3, "adaptive_k": 2});
    let a = send(
        "POST",
        "/v1/sessions",
        "application/json",
        body.to_string().as_bytes(),
    );
    assert_eq!(a.status, 201, "{}", a.body);
    let id = a.json()["id"].as_str().unwrap().to_owned();
    let a = send(
        "PUT",
        &format!("/v1/sessions/{id}/walk.txt"),
        "text/plain",
        phone.walk_tum().as_bytes(),
    );
    assert_eq!(a.json()["source"], json!("walk"), "{}", a.body);
    let a = send(
        "PUT",
        &format!("/v1/sessions/{id}/recording"),
        "application/octet-stream",
        &recording.to_bytes(),
    );
    assert_eq!(a.status, 202, "{}", a.body);
    let deadline = Instant::now() + Duration::from_secs(120);
    let status = loop {
        let status = send("GET", &format!("/v1/sessions/{id}"), "text/plain", b"").json();
        if status["state"] == "done" || status["state"] == "failed" {
            break status;
        }
        assert!(Instant::now() < deadline, "{status}");
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(status["state"], "done", "{status}");
    let done = status["trials_done"].as_u64().unwrap();
    assert!(
        status["stop_reason"]
            .as_str()
            .unwrap_or_default()
            .starts_with("adaptive stop"),
        "{status}"
    );
    assert!((3..20).contains(&done), "{status}");
    let results = send(
        "GET",
        &format!("/v1/sessions/{id}/results.json"),
        "text/plain",
        b"",
    )
    .json();
    assert_eq!(
        (&results["source"], &results["target"], &results["runs"]),
        (&json!("replays"), &json!("live"), &json!(done + 1)),
        "{results}"
    );
    server.stop();
}

#[test]
fn the_report_says_when_the_colours_are_a_guess() {
    let w = start();
    let id = w.session(Some("guess"));
    let a = w.put_walk(&w.owner, &id, &run(0));
    assert_eq!(a.json()["source"], json!("walk"), "{}", a.body);
    assert_eq!(w.results(&id)["informative"], json!(false));
    let report = w.report(&id);
    assert!(
        report.contains("this system's error cannot be told from its runs: colours are a guess"),
        "{report}"
    );
    assert!(report.contains("from the walk alone"), "{report}");
}

trait ConcatLines {
    fn concat_lines(&self) -> String;
}

impl ConcatLines for [&str] {
    fn concat_lines(&self) -> String {
        self.iter().map(|l| format!("{l}\n")).collect()
    }
}
