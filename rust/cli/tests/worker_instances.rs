//! Playback hosts across instances, for real: two `sitar serve --database … --store …
//! --playback-workers 0` on one Postgres and bucket (a data folder each), sessions created on
//! instance A, sim worker hosts connected to instance B and one to A. The worker store is the
//! shared database: hosts on B lease what A's jobs offer, their trials reach A's jobs through
//! the store, every session ends `done` with every trial committed once, and the results are
//! byte-identical to the embedded server's. Without `SITAR_TEST_DATABASE_URL` and
//! `SITAR_TEST_S3_URL` (`scripts/cluster-services start`) the test prints SKIPPED.
// The cluster backends are in a build with the `cluster` feature only.
#![cfg(feature = "cluster")]

mod support;

use std::collections::HashMap;
use std::path::Path;
use std::time::{Duration, Instant};

use sitar_client::Client;

use support::cluster::{fresh_database, services};
use support::process::{Proc, create_token, sim_host};
use support::sessions::{embedded_results, sim_session, trials_in_zip};

/// `sitar serve` on the shared database and store, remote playback only: process and URL.
fn serve(data: &Path, database: &str, store: &str) -> (Proc, String) {
    let mut server = Proc::sitar(&[
        "serve",
        "--addr",
        "127.0.0.1:0",
        "--playback",
        "sim",
        "--playback-workers",
        "0",
        "--lease-s",
        "5",
        "--jobs-per-token",
        "4",
        "--database",
        database,
        "--store",
        store,
        "--data",
        data.to_str().unwrap(),
    ]);
    let line = server.wait_for("listening on http://", Duration::from_secs(60));
    let url = line[line.find("http://").unwrap()..].trim().to_string();
    (server, url)
}

/// `sitar token create --database`: the token.
fn token(database: &str, role: &str, name: &str) -> String {
    create_token(&["--database", database], role, name)
}

/// A sim host of 2 phones at 50× real time, connected to `url`.
fn worker(url: &str, token: &str, name: &str, dir: &Path) -> Proc {
    sim_host(url, token, name, "2", "50", dir)
}

/// The raw status document (its `failed_trials` is not in the client's type).
fn status_json(url: &str, token: &str, id: &str) -> serde_json::Value {
    let mut answer = ureq::get(&format!("{url}/v1/sessions/{id}"))
        .header("authorization", &format!("Bearer {token}"))
        .call()
        .unwrap();
    serde_json::from_str(&answer.body_mut().read_to_string().unwrap()).unwrap()
}

#[test]
fn hosts_on_another_instance_play_the_sessions_of_the_first() {
    let Some((database, store)) = services("worker_instances") else {
        return;
    };
    let Some(database) = fresh_database("worker_instances", &database) else {
        return;
    };
    let store = format!("{store}/worker-instances-{}", std::process::id());
    let dir = tempfile::tempdir().unwrap();
    let (a_data, b_data) = (dir.path().join("instance-a"), dir.path().join("instance-b"));
    let (mut a, a_url) = serve(&a_data, &database, &store);
    a.wait_for("metadata in Postgres", Duration::from_secs(10));
    let (_b, b_url) = serve(&b_data, &database, &store);
    // The worker store is the database: neither instance keeps one in its folder.
    assert!(!a_data.join("sitar.db").exists());
    assert!(!b_data.join("sitar.db").exists());
    let app = token(&database, "app", "lab-app");
    let work = token(&database, "worker", "lab-hosts");

    let recording = sitar_tests::sim_recording(dir.path(), "walk.sitar", 3.0, 11);
    let client = Client::new(&a_url)
        .unwrap()
        .with_server_token(&app)
        .unwrap();
    let hosts = tempfile::tempdir().unwrap();
    let mut references = HashMap::new();
    let mut check = |id: &str, trials: u32| {
        let status = client
            .wait(
                id,
                Duration::from_millis(50),
                Duration::from_secs(180),
                &mut |_| {},
            )
            .expect("the session finishes");
        assert_eq!(status.state.as_str(), "done", "{status:?}");
        assert_eq!(status.trials_done, trials, "{status:?}");
        let doc = status_json(&a_url, &app, id);
        assert_eq!(doc["failed_trials"], serde_json::json!([]), "{doc}");
        // Every trial committed once: as many trial files as trials, on either instance.
        assert_eq!(trials_in_zip(&a_url, &app, id), trials as usize, "{id}");
        assert_eq!(trials_in_zip(&b_url, &app, id), trials as usize, "{id}");
        let expected = references
            .entry(trials)
            .or_insert_with(|| embedded_results(&recording, trials, "trim_mean_30"));
        assert_eq!(client.results_json(id).unwrap(), expected.0, "{id}");
        assert_eq!(client.results_csv(id).unwrap(), expected.1, "{id}");
    };

    // Hosts on B only, their lease requests already waiting (20 s long polls): A's offers
    // wake nobody on B, so they find them by looking at the store again (every 1 s).
    let mut on_b: Vec<Proc> = ["host-b1", "host-b2"]
        .iter()
        .map(|name| worker(&b_url, &work, name, hosts.path()))
        .collect();
    std::thread::sleep(Duration::from_millis(1500));
    let offered = Instant::now();
    let first: Vec<(String, u32)> = (0..2)
        .map(|k| {
            (
                sim_session(&client, &recording, 4 + k, "trim_mean_30"),
                4 + k,
            )
        })
        .collect();
    for (id, trials) in &first {
        check(id, *trials);
    }
    let took = offered.elapsed();
    println!("two sessions offered on A, played by B's hosts: done in {took:?}");
    assert!(
        took < Duration::from_secs(15),
        "B's hosts took {took:?}: they saw A's offers only when their long polls ended"
    );

    // Then a host on A too, and more sessions: every trial once, whoever played it.
    let mut on_a = worker(&a_url, &work, "host-a1", hosts.path());
    let second: Vec<(String, u32)> = (0..4)
        .map(|k| {
            (
                sim_session(&client, &recording, 4 + k % 2, "trim_mean_30"),
                4 + k % 2,
            )
        })
        .collect();
    for (id, trials) in &second {
        check(id, *trials);
    }
    // The hosts connected to B played trials of A's sessions.
    let played_on_b = on_b
        .iter_mut()
        .flat_map(|w| {
            w.drain();
            w.seen.clone()
        })
        .filter(|l| l.contains("playing trial"))
        .count();
    assert!(played_on_b > 0, "no trial played by B's hosts");
    on_a.drain();
    // Both instances list the three hosts' phones (the store is shared).
    for url in [&a_url, &b_url] {
        let admin = std::fs::read_to_string(a_data.join("admin.token")).unwrap();
        let devices = Client::new(url)
            .unwrap()
            .with_server_token(admin.trim())
            .unwrap()
            .devices_json()
            .unwrap();
        let devices: serde_json::Value = serde_json::from_str(&devices).unwrap();
        assert_eq!(devices["devices"].as_array().unwrap().len(), 6, "{devices}");
    }
}
