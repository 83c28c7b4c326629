//! Several `sitar serve` instances on one Postgres database and one S3-compatible bucket, as
//! real processes: who plays a session, and what happens when an instance dies. A session
//! uploaded to A is adopted by B after A is killed (SIGKILL) mid-playback and ends with
//! results byte-identical to the embedded server's; A started again plays nothing twice; a
//! cancel, an estimate and a delete sent to B reach the sessions A plays; B shows the queue
//! position and ETA of A's sessions as A does. Without the services of
//! `scripts/cluster-services` the test prints SKIPPED.
// The cluster backends are in a build with the `cluster` feature only.
#![cfg(feature = "cluster")]

mod instances;
mod support;

use std::path::Path;
use std::time::{Duration, Instant};

use instances::serving::{request, start};
use sitar_client::SessionState;
use support::cluster::{fresh_database, services};

/// Trials per session: long enough to kill an instance in the middle.
const TRIALS: u32 = 6;

/// The instances' `--instance-timeout-s`: B adopts within 4/3 of it.
const TIMEOUT_S: u64 = 3;

fn admin_token(data: &Path) -> String {
    std::fs::read_to_string(data.join("admin.token"))
        .unwrap()
        .trim()
        .to_string()
}

fn new_session() -> sitar_client::NewSession {
    sitar_client::NewSession {
        trials: TRIALS,
        setting: "trim_mean_30".into(),
        playback: "sim".into(),
        window_frames: None,
        pose_relation: None,
    }
}

/// Creates a session through `client` and uploads `recording` to it; its id.
fn start_session(client: &sitar_client::Client, recording: &Path) -> String {
    let id = client.create_session(&new_session()).unwrap();
    client
        .upload_recording(&id, recording, &mut |_, _| {})
        .unwrap();
    id
}

/// Waits (at most 60 s) until session `id` has `trials` trials stored.
fn wait_for_trials(client: &sitar_client::Client, id: &str, trials: u32) {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let status = client.status(id).unwrap();
        if status.trials_done >= trials {
            return;
        }
        assert!(
            Instant::now() < deadline && !status.state.is_finished(),
            "session {id} did not reach {trials} trials: {status:?}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn wait_done(client: &sitar_client::Client, id: &str) -> sitar_client::SessionStatus {
    client
        .wait(
            id,
            Duration::from_millis(50),
            Duration::from_secs(120),
            &mut |_| {},
        )
        .unwrap()
}

/// The (kind, state) of session `id`'s jobs, from its raw status document.
fn jobs(url: &str, token: &str, id: &str) -> Vec<(String, String)> {
    let (status, body) = request("GET", url, &format!("/v1/sessions/{id}"), token);
    assert_eq!(status, "200", "{body}");
    let doc: serde_json::Value = serde_json::from_str(&body).unwrap();
    doc["jobs"]
        .as_array()
        .unwrap_or_else(|| panic!("no jobs in {body}"))
        .iter()
        .map(|j| {
            let field = |k: &str| j[k].as_str().unwrap_or_default().to_string();
            (field("kind"), field("state"))
        })
        .collect()
}

#[test]
fn a_dead_instances_session_is_adopted_and_stops_reach_the_player() {
    let Some((database, store)) = services("serve_instances") else {
        return;
    };
    let Some(database) = fresh_database("serve_instances", &database) else {
        return;
    };
    let store = format!("{store}/serve-instances-{}", std::process::id());
    let dir = tempfile::tempdir().unwrap();
    let recording = dir.path().join("walk.rec");
    let rec = sitar_sim::Recording::demo(6.0, 30.0, 11).unwrap();
    std::fs::write(&recording, rec.to_bytes()).unwrap();

    // The embedded server, fast: the reference results.
    let embedded_data = dir.path().join("embedded");
    let embedded = start(&embedded_data, &["--sim-speed", "30", "--sim-devices", "1"]);
    let reference = embedded.client(&admin_token(&embedded_data));
    let id = start_session(&reference, &recording);
    assert_eq!(wait_done(&reference, &id).state, SessionState::Done);
    let (csv, json) = (
        reference.results_csv(&id).unwrap(),
        reference.results_json(&id).unwrap(),
    );
    drop(embedded);

    // Two instances on one database and bucket; a trial takes 3 s.
    let timeout = TIMEOUT_S.to_string();
    let cluster = [
        "--database",
        database.as_str(),
        "--store",
        store.as_str(),
        "--sim-speed",
        "2",
        "--sim-devices",
        "1",
        "--instance-timeout-s",
        timeout.as_str(),
        // One session plays at a time: a second one waits in the queue.
        "--playback-workers",
        "1",
    ];
    let a_data = dir.path().join("instance-a");
    let mut a = start(&a_data, &cluster);
    let admin = admin_token(&a_data);
    let mut b = start(&dir.path().join("instance-b"), &cluster);
    let a_id = std::fs::read_to_string(a_data.join("instance.id")).unwrap();
    let (from_a, from_b) = (a.client(&admin), b.client(&admin));

    // Uploaded to A, A plays it; A is killed after 2 of its trials.
    let played = start_session(&from_a, &recording);
    wait_for_trials(&from_b, &played, 2);
    a.kill();
    let killed = Instant::now();
    let adopted = b.wait_for(
        &format!("session {played}: adopted from {}", a_id.trim()),
        Duration::from_secs(30),
    );
    println!("adopted {:?} after the kill", killed.elapsed());
    let bound = Duration::from_secs(TIMEOUT_S * 4 / 3 + 2);
    assert!(
        killed.elapsed() <= bound,
        "adopted after {:?}, over {bound:?}: {adopted}",
        killed.elapsed()
    );
    // A starts again on its folder while B plays the session: it leaves it to B.
    let mut a = start(&a_data, &cluster);
    let from_a = a.client(&admin);
    let status = wait_done(&from_b, &played);
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert_eq!(
        (status.trials_done, status.results_trials),
        (TRIALS, TRIALS),
        "every trial stored once: {status:?}"
    );
    assert_eq!(from_a.results_csv(&played).unwrap(), csv, "CSV differs");
    assert_eq!(from_a.results_json(&played).unwrap(), json, "JSON differs");
    assert!(
        !a.said(&format!("session {played}: back in the playback queue")),
        "A played it again: {:#?}",
        a.seen
    );
    let played_jobs = jobs(&b.url, &admin, &played);
    let playback = |state: &str| {
        played_jobs
            .iter()
            .filter(|(kind, s)| kind == "playback" && s == state)
            .count()
    };
    assert_eq!(
        (
            playback("interrupted"),
            playback("done"),
            playback("running")
        ),
        (1, 1, 0),
        "{played_jobs:?}"
    );

    // A cancel sent to B stops the session A plays: an estimate of what was played.
    let cancelled = start_session(&from_a, &recording);
    wait_for_trials(&from_b, &cancelled, 2);
    let (code, body) = request(
        "POST",
        &b.url,
        &format!("/v1/sessions/{cancelled}/cancel"),
        &admin,
    );
    assert_eq!(code, "202", "{body}");
    let status = wait_done(&from_b, &cancelled);
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert!(status.trials_done < TRIALS, "{status:?}");
    let reason = status.stop_reason.clone().unwrap_or_default();
    assert!(reason.contains("cancelled by the client"), "{status:?}");
    assert!(!b.said(&format!("session {cancelled}: back in the playback queue")));

    // An estimate asked of B for a session A plays: A stops and estimates what it has.
    let estimated = start_session(&from_a, &recording);
    wait_for_trials(&from_b, &estimated, 2);
    let (code, body) = request(
        "POST",
        &b.url,
        &format!("/v1/sessions/{estimated}/estimate"),
        &admin,
    );
    assert_eq!(code, "202", "{body}");
    let status = wait_done(&from_b, &estimated);
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert!(status.trials_done < TRIALS, "{status:?}");
    let reason = status.stop_reason.clone().unwrap_or_default();
    assert!(reason.contains("estimate requested after"), "{status:?}");

    // A delete sent to B stops A's playback, and the session is gone for both.
    let deleted = start_session(&from_a, &recording);
    wait_for_trials(&from_b, &deleted, 1);
    from_b.delete_session(&deleted).unwrap();
    assert_eq!(from_a.status(&deleted).unwrap_err().status(), Some(404));
    a.wait_for(
        &format!("session {deleted}: playback stopped for its deletion"),
        Duration::from_secs(10),
    );

    // Two sessions on A: one plays, one waits. B answers their status as A does: the queue
    // position and the ETA A works out (A publishes them; B reads them).
    let playing = start_session(&from_a, &recording);
    wait_for_trials(&from_b, &playing, 1);
    let waiting = start_session(&from_a, &recording);
    let raw = |url: &str, id: &str| -> serde_json::Value {
        let (code, body) = request("GET", url, &format!("/v1/sessions/{id}"), &admin);
        assert_eq!(code, "200", "{body}");
        serde_json::from_str(&body).unwrap()
    };
    assert_eq!(raw(&a.url, &waiting)["queue_position"], 1);
    let deadline = Instant::now() + Duration::from_secs(10);
    while raw(&b.url, &waiting)["queue_position"] != 1 {
        assert!(
            Instant::now() < deadline,
            "B never showed the queue position A holds: {}",
            raw(&b.url, &waiting)
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let (eta_a, eta_b) = (
        raw(&a.url, &playing)["eta_s"].as_f64(),
        raw(&b.url, &playing)["eta_s"].as_f64(),
    );
    let (eta_a, eta_b) = (eta_a.expect("A knows the ETA"), eta_b.expect("B shows it"));
    assert!(
        eta_a > 0.0 && (eta_a - eta_b).abs() <= 1.5,
        "ETA from A {eta_a} s, from B {eta_b} s"
    );
    assert!(raw(&b.url, &playing)["progress"].as_f64().unwrap() > 0.0);
    from_b.delete_session(&waiting).unwrap();
    from_b.delete_session(&playing).unwrap();
    assert_eq!(from_a.status(&waiting).unwrap_err().status(), Some(404));
}
