//! Remote playback's rules, with the worker routes driven by hand (the server in process,
//! `playback_workers = 0`; `rust/cli/tests/worker_cluster.rs` runs real `sitar worker`
//! processes): a trial that cannot be parsed fails visibly in the session's status and is
//! played again; a phone failing twice in a row leaves service and the devices listing says
//! so; a late upload after the lease expired is refused and the trial committed once; cancel
//! and delete reach the hosts through their heartbeats.

use std::path::Path;
use std::time::{Duration, Instant};

use sitar_client::{Client, NewSession, WorkerLease};
use sitar_server::{PresetToken, Role, ServerConfig, ServerHandle};
use sitar_tests::{ADMIN_TOKEN, APP_TOKEN, sim_config, sim_recording, with_test_tokens};

const WORKER_TOKEN: &str = "sitar_test_worker_0c5e2b7d9a1f4e38b6d0c2a4";

fn start(data: &Path, lease: Duration) -> ServerHandle {
    let mut config: ServerConfig = with_test_tokens(sim_config(data, 100.0, 1));
    config.playback_workers = 0;
    config.lease_timeout = lease;
    config.preset_tokens.push(PresetToken {
        name: "test-host".into(),
        role: Role::Worker,
        token: WORKER_TOKEN.into(),
    });
    sitar_tests::start(config)
}

fn client(server: &ServerHandle, token: &str) -> Client {
    Client::new(&server.url())
        .unwrap()
        .with_server_token(token)
        .unwrap()
        .with_retries(0, Duration::from_millis(10))
}

fn sim_session(app: &Client, recording: &Path, trials: u32) -> String {
    let id = app
        .create_session(&NewSession {
            trials,
            setting: "median".into(),
            playback: "sim".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    app.upload_recording(&id, recording, &mut |_, _| {})
        .unwrap();
    id
}

/// Leases a trial for `phone`, waiting up to 10 s for one to be offered.
fn lease(worker: &Client, host: &str, phone: &str) -> WorkerLease {
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        if let Some(lease) = worker.worker_lease(host, phone, 1.0).unwrap() {
            return lease;
        }
        assert!(Instant::now() < deadline, "no trial offered to {phone}");
    }
}

/// The TUM text of sim trial `index` of `recording`, as a host plays it.
fn sim_trial(recording: &Path, index: u32) -> String {
    let rec = sitar_sim::Recording::from_bytes(&std::fs::read(recording).unwrap()).unwrap();
    let mut tum = Vec::new();
    sitar_estimator::write_tum(&sitar_sim::play_trial(&rec, index), &mut tum).unwrap();
    String::from_utf8(tum).unwrap()
}

fn status(server: &ServerHandle, id: &str) -> serde_json::Value {
    let text = ureq::get(&format!("{}/v1/sessions/{id}", server.url()))
        .header("authorization", &format!("Bearer {APP_TOKEN}"))
        .call()
        .unwrap()
        .body_mut()
        .read_to_string()
        .unwrap();
    serde_json::from_str(&text).unwrap()
}

fn wait_state(server: &ServerHandle, id: &str, states: &[&str]) -> serde_json::Value {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let doc = status(server, id);
        if states.iter().any(|s| doc["state"] == *s) {
            return doc;
        }
        assert!(
            Instant::now() < deadline,
            "{id} never reached {states:?}: {doc}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_garbage_trial_fails_visibly_and_a_phone_failing_twice_leaves_service() {
    let data = tempfile::tempdir().unwrap();
    let server = start(data.path(), Duration::from_secs(30));
    let (app, worker) = (client(&server, APP_TOKEN), client(&server, WORKER_TOKEN));
    let recording = sim_recording(data.path(), "walk.sitar", 1.0, 3);
    let host = worker
        .worker_register("bench", "sim", &["p0".into(), "p1".into()])
        .unwrap();
    assert_eq!(host.lease_s, 30.0);
    let id = sim_session(&app, &recording, 2);

    // p0 sends garbage: a 422 naming the line, the failure in the session's status.
    let first = lease(&worker, &host.host, "p0");
    assert_eq!(first.session, id);
    let err = worker
        .worker_upload_trial(&host.host, &first.lease, "0 0 0 0 0 0 0 1\nnot a pose\n")
        .unwrap_err();
    assert_eq!(err.status(), Some(422), "{err}");
    assert!(err.to_string().contains("trial:2"), "{err}");
    let failed = status(&server, &id)["failed_trials"].clone();
    assert_eq!(failed.as_array().unwrap().len(), 1, "{failed}");
    assert_eq!(failed[0]["index"], first.index);
    assert_eq!(failed[0]["source"], "bench/p0");
    assert!(
        failed[0]["error"].as_str().unwrap().contains("trial:2"),
        "{failed}"
    );
    // The lease is gone with it: a second upload on it is refused.
    let err = worker
        .worker_upload_trial(
            &host.host,
            &first.lease,
            &sim_trial(&recording, first.index),
        )
        .unwrap_err();
    assert_eq!(err.status(), Some(409), "{err}");

    // p0 fails again (its app crashed): twice in a row, out of service.
    let second = lease(&worker, &host.host, "p0");
    worker
        .worker_failure(&host.host, &second.lease, "the playback app crashed")
        .unwrap();
    let beat = worker
        .worker_heartbeat(&host.host, &["p0".into(), "p1".into()], &[])
        .unwrap();
    assert_eq!(beat.out_of_service, vec!["p0".to_string()]);
    assert!(
        worker
            .worker_lease(&host.host, "p0", 0.0)
            .unwrap()
            .is_none()
    );
    let devices: serde_json::Value =
        serde_json::from_str(&client(&server, ADMIN_TOKEN).devices_json().unwrap()).unwrap();
    let p0 = devices["devices"]
        .as_array()
        .unwrap()
        .iter()
        .find(|d| d["serial"] == "bench/p0")
        .unwrap_or_else(|| panic!("{devices}"));
    assert_eq!(p0["state"], "out_of_service", "{devices}");

    // p1 plays both trials; the session ends done with them, each once.
    for _ in 0..2 {
        let next = lease(&worker, &host.host, "p1");
        worker
            .worker_upload_trial(&host.host, &next.lease, &sim_trial(&recording, next.index))
            .unwrap();
        let err = worker
            .worker_upload_trial(&host.host, &next.lease, &sim_trial(&recording, next.index))
            .unwrap_err();
        assert_eq!(err.status(), Some(409), "committed once: {err}");
    }
    let done = wait_state(&server, &id, &["done", "failed"]);
    assert_eq!(done["state"], "done", "{done}");
    assert_eq!(done["trials_done"], 2, "{done}");
    assert_eq!(done["failed_trials"].as_array().unwrap().len(), 2, "{done}");
    server.stop();
}

#[test]
fn a_late_upload_after_the_lease_expired_is_refused_and_the_trial_played_elsewhere() {
    let data = tempfile::tempdir().unwrap();
    let server = start(data.path(), Duration::from_millis(600));
    let (app, worker) = (client(&server, APP_TOKEN), client(&server, WORKER_TOKEN));
    let recording = sim_recording(data.path(), "walk.sitar", 1.0, 4);
    let a = worker
        .worker_register("host-a", "sim", &["p".into()])
        .unwrap();
    let b = worker
        .worker_register("host-b", "sim", &["p".into()])
        .unwrap();
    let id = sim_session(&app, &recording, 2);
    let held = lease(&worker, &a.host, "p");
    // Host a goes silent past its lease; the reaper gives the trial to host b.
    std::thread::sleep(Duration::from_millis(1_200));
    let mut taken = Vec::new();
    for _ in 0..2 {
        taken.push(lease(&worker, &b.host, "p"));
        let last = taken.last().unwrap();
        if last.index == held.index {
            break;
        }
        worker
            .worker_upload_trial(&b.host, &last.lease, &sim_trial(&recording, last.index))
            .unwrap();
    }
    let again = taken.last().unwrap();
    assert_eq!(again.index, held.index, "the expired trial is played again");
    // Host a comes back: its heartbeat tells it to drop the lease, its upload is refused.
    let beat = worker
        .worker_heartbeat(&a.host, &["p".into()], std::slice::from_ref(&held.lease))
        .unwrap();
    assert_eq!(beat.abort, vec![held.lease.clone()]);
    let err = worker
        .worker_upload_trial(&a.host, &held.lease, &sim_trial(&recording, held.index))
        .unwrap_err();
    assert_eq!(err.status(), Some(409), "{err}");
    worker
        .worker_upload_trial(&b.host, &again.lease, &sim_trial(&recording, again.index))
        .unwrap();
    // Whatever is left of the session, host b plays too.
    while status(&server, &id)["trials_done"] != 2 {
        if let Some(rest) = worker.worker_lease(&b.host, "p", 0.5).unwrap() {
            worker
                .worker_upload_trial(&b.host, &rest.lease, &sim_trial(&recording, rest.index))
                .unwrap();
        }
    }
    let done = wait_state(&server, &id, &["done", "failed"]);
    assert_eq!(done["state"], "done", "{done}");
    assert_eq!(done["trials_done"], 2, "each trial once: {done}");
    server.stop();
}

#[test]
fn cancel_and_delete_reach_the_hosts_and_sessions_wait_their_turn() {
    let data = tempfile::tempdir().unwrap();
    let mut config = with_test_tokens(sim_config(data.path(), 100.0, 1));
    config.playback_workers = 0;
    config.jobs_per_token = 1;
    config.preset_tokens.push(PresetToken {
        name: "test-host".into(),
        role: Role::Worker,
        token: WORKER_TOKEN.into(),
    });
    let server = sitar_tests::start(config);
    let (app, worker) = (client(&server, APP_TOKEN), client(&server, WORKER_TOKEN));
    let recording = sim_recording(data.path(), "walk.sitar", 1.0, 5);
    let host = worker
        .worker_register("host", "sim", &["p0".into(), "p1".into()])
        .unwrap();
    let first = sim_session(&app, &recording, 4);
    let second = sim_session(&app, &recording, 4);
    // One session of this token at a time: the second waits, first in line.
    let held = lease(&worker, &host.host, "p0");
    assert_eq!(held.session, first);
    assert_eq!(status(&server, &second)["queue_position"], 1);

    // Cancel: the host is told to drop the trial; with no trial played the session fails.
    let cancel = ureq::post(&format!("{}/v1/sessions/{first}/cancel", server.url()))
        .header("authorization", &format!("Bearer {APP_TOKEN}"))
        .send_empty()
        .unwrap();
    assert_eq!(cancel.status().as_u16(), 202);
    let ended = wait_state(&server, &first, &["done", "failed"]);
    assert_eq!(ended["state"], "failed", "{ended}");
    let beat = worker
        .worker_heartbeat(
            &host.host,
            &["p0".into(), "p1".into()],
            std::slice::from_ref(&held.lease),
        )
        .unwrap();
    assert_eq!(beat.abort, vec![held.lease.clone()]);

    // The second session plays now; delete it while a trial is out: the lease is withdrawn.
    let next = lease(&worker, &host.host, "p1");
    assert_eq!(next.session, second);
    app.delete_session(&second).unwrap();
    let beat = worker
        .worker_heartbeat(
            &host.host,
            &["p0".into(), "p1".into()],
            std::slice::from_ref(&next.lease),
        )
        .unwrap();
    assert_eq!(beat.abort, vec![next.lease.clone()]);
    let err = worker
        .worker_upload_trial(&host.host, &next.lease, &sim_trial(&recording, next.index))
        .unwrap_err();
    assert_eq!(err.status(), Some(409), "{err}");
    assert!(
        worker
            .worker_lease(&host.host, "p0", 0.0)
            .unwrap()
            .is_none()
    );
    server.stop();
}
