//! Playback hosts for real: `sitar serve --playback-workers 0` and several `sitar worker
//! --playback sim` processes on loopback. Sessions end `done` with results byte-identical to
//! the in-process server's; a worker killed with SIGKILL mid-trial loses its lease and the
//! trial is played elsewhere; a worker stopped (SIGSTOP) past its lease and let go on has its
//! late trial refused, so every trial is committed once; a server killed with SIGKILL in the
//! middle of a session resumes it and the hosts finish it; an adb host plays on its phones
//! and a failing phone leaves service; worker tokens stay in their routes.

mod support;

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use sitar_client::{Client, NewSession};
use support::process::{Proc, create_token, sim_host};
use support::sessions::{embedded_results, sim_session};

/// `sitar token create --data`: the token.
fn token(data: &Path, role: &str, name: &str) -> String {
    create_token(&["--data", data.to_str().unwrap()], role, name)
}

/// `sitar serve` with remote playback on a free port: the process and its URL.
fn serve(data: &Path, lease_s: &str) -> (Proc, String) {
    serve_kind(data, lease_s, "sim")
}

fn serve_kind(data: &Path, lease_s: &str, playback: &str) -> (Proc, String) {
    serve_on(data, lease_s, playback, "127.0.0.1:0")
}

fn serve_on(data: &Path, lease_s: &str, playback: &str, addr: &str) -> (Proc, String) {
    let mut server = Proc::sitar(&[
        "serve",
        "--addr",
        addr,
        "--playback",
        playback,
        "--playback-workers",
        "0",
        "--lease-s",
        lease_s,
        "--jobs-per-token",
        "4",
        "--data",
        data.to_str().unwrap(),
    ]);
    let line = server.wait_for("listening on http://", Duration::from_secs(60));
    let url = line[line.find("http://").unwrap()..].trim().to_string();
    (server, url)
}

/// A sim host of `slots` phones at `speed`× real time, connected to `url`.
fn worker(url: &str, token: &str, name: &str, slots: &str, speed: &str, dir: &Path) -> Proc {
    sim_host(url, token, name, slots, speed, dir)
}

fn wait(client: &Client, id: &str, limit: Duration) -> sitar_client::SessionStatus {
    client
        .wait(id, Duration::from_millis(50), limit, &mut |_| {})
        .expect("the session finishes")
}

/// The raw status document (its `failed_trials` is not in the client's type).
fn status_json(url: &str, token: &str, id: &str) -> serde_json::Value {
    let mut answer = ureq::get(&format!("{url}/v1/sessions/{id}"))
        .header("authorization", &format!("Bearer {token}"))
        .call()
        .unwrap();
    serde_json::from_str(&answer.body_mut().read_to_string().unwrap()).unwrap()
}

fn status_of(url: &str, token: &str, method: &str, path: &str) -> u16 {
    let agent: ureq::Agent = ureq::Agent::config_builder()
        .http_status_as_error(false)
        .build()
        .into();
    let full = format!("{url}{path}");
    let auth = format!("Bearer {token}");
    let answer = match method {
        "GET" => agent.get(&full).header("authorization", &auth).call(),
        _ => agent
            .post(&full)
            .header("authorization", &auth)
            .header("content-type", "application/json")
            .send(r#"{"name":"x","playback":"sim","phones":["sim:0"]}"#),
    };
    answer.unwrap().status().as_u16()
}

#[test]
fn three_hosts_play_sessions_of_two_tokens_as_the_embedded_server_does() {
    let data = tempfile::tempdir().unwrap();
    let hosts = tempfile::tempdir().unwrap();
    let app1 = token(data.path(), "app", "lab-app-1");
    let app2 = token(data.path(), "app", "lab-app-2");
    let work = token(data.path(), "worker", "lab-hosts");
    let (_server, url) = serve(data.path(), "5");
    let admin = std::fs::read_to_string(data.path().join("admin.token")).unwrap();
    let admin = admin.trim();

    // Worker tokens stay in their routes; other tokens get 403 on them.
    assert_eq!(status_of(&url, &work, "GET", "/v1/sessions"), 403);
    assert_eq!(status_of(&url, &work, "GET", "/v1/devices"), 403);
    assert_eq!(status_of(&url, &app1, "POST", "/v1/worker/hosts"), 403);
    assert_eq!(status_of(&url, admin, "POST", "/v1/worker/hosts"), 403);

    let mut workers: Vec<Proc> = ["host-a", "host-b"]
        .iter()
        .map(|name| worker(&url, &work, name, "2", "50", hosts.path()))
        .collect();
    // The third host reads its token from a file.
    let token_file = hosts.path().join("worker.token");
    std::fs::write(&token_file, format!("{work}\n")).unwrap();
    let mut third = Proc::sitar(&[
        "worker",
        "--server",
        &url,
        "--token-file",
        token_file.to_str().unwrap(),
        "--playback",
        "sim",
        "--slots",
        "2",
        "--sim-speed",
        "50",
        "--name",
        "host-c",
        "--data",
        hosts.path().join("host-c").to_str().unwrap(),
    ]);
    third.wait_for("sitar worker: host", Duration::from_secs(30));
    workers.push(third);
    let dir = tempfile::tempdir().unwrap();
    let recording = sitar_tests::sim_recording(dir.path(), "walk.sitar", 3.0, 11);
    let clients = [&app1, &app2].map(|t| Client::new(&url).unwrap().with_server_token(t).unwrap());
    let sessions: Vec<(usize, String, u32)> = (0..6)
        .map(|k| {
            let trials = 4 + (k as u32 % 3);
            let id = sim_session(&clients[k % 2], &recording, trials, "trim_mean_30");
            (k % 2, id, trials)
        })
        .collect();
    let mut references = std::collections::HashMap::new();
    for (owner, id, trials) in &sessions {
        let status = wait(&clients[*owner], id, Duration::from_secs(180));
        assert_eq!(status.state.as_str(), "done", "{status:?}");
        assert_eq!(status.trials_done, *trials, "{status:?}");
        let doc = status_json(&url, [&app1, &app2][*owner], id);
        assert_eq!(doc["failed_trials"], serde_json::json!([]), "{doc}");
        let expected = references
            .entry(*trials)
            .or_insert_with(|| embedded_results(&recording, *trials, "trim_mean_30"));
        assert_eq!(
            clients[*owner].results_json(id).unwrap(),
            expected.0,
            "{id}"
        );
        assert_eq!(clients[*owner].results_csv(id).unwrap(), expected.1, "{id}");
    }
    // The devices listing shows the 6 phones of the 3 hosts, each ready.
    let admin_client = Client::new(&url).unwrap().with_server_token(admin).unwrap();
    let devices: serde_json::Value =
        serde_json::from_str(&admin_client.devices_json().unwrap()).unwrap();
    let listed: Vec<_> = devices["devices"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| {
            (
                d["serial"].as_str().unwrap().to_string(),
                d["state"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    assert_eq!(listed.len(), 6, "{devices}");
    assert!(
        listed.iter().all(|(_, state)| state == "ready"),
        "{devices}"
    );
    assert!(
        listed.iter().any(|(serial, _)| serial == "host-c/sim:1"),
        "{devices}"
    );
}

#[test]
fn a_killed_host_s_trial_is_played_elsewhere_and_a_stopped_host_s_late_trial_is_refused() {
    let data = tempfile::tempdir().unwrap();
    let hosts = tempfile::tempdir().unwrap();
    let app = token(data.path(), "app", "lab-app");
    let work = token(data.path(), "worker", "lab-hosts");
    let (_server, url) = serve(data.path(), "1.5");
    let client = Client::new(&url).unwrap().with_server_token(&app).unwrap();
    let dir = tempfile::tempdir().unwrap();
    // 6 s at 2× real time: a trial lasts 3 s on a host, twice the lease.
    let recording = sitar_tests::sim_recording(dir.path(), "walk.sitar", 6.0, 5);

    // One host first, so it surely leases a trial; kill -9 it mid-trial.
    let mut doomed = worker(&url, &work, "host-doomed", "1", "2", hosts.path());
    let first = sim_session(&client, &recording, 3, "median");
    doomed.wait_for("playing trial", Duration::from_secs(30));
    doomed.signal("KILL");
    let killed_at = Instant::now();
    let _b = worker(&url, &work, "host-b", "1", "2", hosts.path());
    let _c = worker(&url, &work, "host-c", "1", "2", hosts.path());
    let status = wait(&client, &first, Duration::from_secs(120));
    assert_eq!(status.state.as_str(), "done", "{status:?}");
    assert_eq!(status.trials_done, 3, "{status:?}");
    assert!(killed_at.elapsed() >= Duration::from_millis(1500));
    let expected = embedded_results(&recording, 3, "median");
    assert_eq!(client.results_json(&first).unwrap(), expected.0);

    // A host stopped past its lease, then let go on: its trial is played elsewhere, and
    // its late upload is refused (or the heartbeat tells it to drop the trial first).
    let mut stopped = worker(&url, &work, "host-stopped", "1", "2", hosts.path());
    let second = sim_session(&client, &recording, 3, "median");
    // Wait until the stopped-to-be host is playing one of the new session's trials.
    stopped.wait_for(&format!("of session {second}"), Duration::from_secs(60));
    stopped.signal("STOP");
    std::thread::sleep(Duration::from_secs(5));
    stopped.signal("CONT");
    let status = wait(&client, &second, Duration::from_secs(120));
    assert_eq!(status.state.as_str(), "done", "{status:?}");
    assert_eq!(status.trials_done, 3, "each trial once: {status:?}");
    assert_eq!(client.results_json(&second).unwrap(), expected.0);
    // What the stopped host did with its trial once it went on.
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        stopped.drain();
        if stopped
            .seen
            .iter()
            .any(|l| l.contains("refused") || l.contains("stopped"))
        {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "the stopped host neither dropped nor had its trial refused: {:#?}",
            stopped.seen
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    // Trials sent: every trial exactly once in trials.zip.
    let zip = {
        let mut answer = ureq::get(&format!("{url}/v1/sessions/{second}/trials.zip"))
            .header("authorization", &format!("Bearer {app}"))
            .call()
            .unwrap();
        answer.body_mut().read_to_vec().unwrap()
    };
    let archive = zip::ZipArchive::new(std::io::Cursor::new(zip)).unwrap();
    assert_eq!(archive.len(), 3);
}

#[test]
fn an_adb_host_plays_on_its_phones_and_a_failing_phone_leaves_service() {
    let data = tempfile::tempdir().unwrap();
    let root = tempfile::tempdir().unwrap();
    let app = token(data.path(), "app", "lab-app");
    let work = token(data.path(), "worker", "lab-hosts");
    let (_server, url) = serve_kind(data.path(), "5", "adb");
    // Two fake phones (tests/fake_adb.sh) with the playback app: GOOD plays, BAD's app fails.
    let rec = sitar_sim::Recording::demo(3.0, 30.0, 8).unwrap();
    let pool = root.path().join("pool");
    std::fs::create_dir_all(&pool).unwrap();
    for (k, trial) in sitar_sim::simulate_trials(&rec, 12).iter().enumerate() {
        std::fs::write(
            pool.join(format!("trial_{k}.txt")),
            sitar_tests::tum_text(trial),
        )
        .unwrap();
    }
    std::fs::write(root.path().join("counter"), "0\n").unwrap();
    for serial in ["GOOD", "BAD"] {
        let phone = root.path().join("phones").join(serial);
        std::fs::create_dir_all(&phone).unwrap();
        std::fs::write(
            phone.join(".installed"),
            "io.github.sitar.playback/.PlaybackActivity\n",
        )
        .unwrap();
    }
    std::fs::write(root.path().join("phones/BAD/.fail"), "camera blocked").unwrap();
    let fake_adb = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fake_adb.sh");
    let hosts = tempfile::tempdir().unwrap();
    let mut host = Proc::sitar_with(
        &[
            "worker",
            "--server",
            &url,
            "--token",
            &work,
            "--playback",
            "adb",
            "--adb",
            fake_adb.to_str().unwrap(),
            "--name",
            "adb-host",
            "--data",
            hosts.path().to_str().unwrap(),
        ],
        &[
            ("FAKE_ADB_ROOT", root.path().as_os_str()),
            ("FAKE_TRIAL_SECONDS", std::ffi::OsStr::new("0.4")),
        ],
    );
    host.wait_for("2 adb phone(s)", Duration::from_secs(30));
    let client = Client::new(&url).unwrap().with_server_token(&app).unwrap();
    let mp4 = root.path().join("recording.mp4");
    std::fs::write(&mp4, sitar_tests::minimal_mp4(300)).unwrap();
    let id = client
        .create_session(&NewSession {
            trials: 6,
            setting: "median".into(),
            playback: "adb".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    client.upload_recording(&id, &mp4, &mut |_, _| {}).unwrap();
    let status = wait(&client, &id, Duration::from_secs(120));
    assert_eq!(status.state.as_str(), "done", "{status:?}");
    assert_eq!(status.trials_done, 6, "{status:?}");
    // BAD failed its trials twice in a row: listed in the session, out of service.
    let doc = status_json(&url, &app, &id);
    let failed = doc["failed_trials"].as_array().unwrap();
    assert!(failed.len() >= 2, "{doc}");
    assert!(
        failed.iter().all(|f| f["source"] == "adb-host/BAD"),
        "{doc}"
    );
    assert!(
        failed
            .iter()
            .all(|f| f["error"].as_str().unwrap().contains("camera blocked")),
        "{doc}"
    );
    let admin = std::fs::read_to_string(data.path().join("admin.token")).unwrap();
    let admin = Client::new(&url)
        .unwrap()
        .with_server_token(admin.trim())
        .unwrap();
    let devices: serde_json::Value = serde_json::from_str(&admin.devices_json().unwrap()).unwrap();
    let state = |serial: &str| {
        devices["devices"]
            .as_array()
            .unwrap()
            .iter()
            .find(|d| d["serial"] == serial)
            .map(|d| d["state"].as_str().unwrap().to_string())
    };
    assert_eq!(
        state("adb-host/BAD").as_deref(),
        Some("out_of_service"),
        "{devices}"
    );
    assert_eq!(
        state("adb-host/GOOD").as_deref(),
        Some("ready"),
        "{devices}"
    );
}

#[test]
fn a_server_killed_mid_session_resumes_and_the_hosts_finish_it() {
    let data = tempfile::tempdir().unwrap();
    let hosts = tempfile::tempdir().unwrap();
    let app = token(data.path(), "app", "lab-app");
    let work = token(data.path(), "worker", "lab-hosts");
    // A fixed port, so the hosts find the restarted server where they left it.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let addr = format!("127.0.0.1:{port}");
    let (server, url) = serve_on(data.path(), "2", "sim", &addr);
    let _hosts: Vec<Proc> = ["host-a", "host-b"]
        .iter()
        .map(|name| worker(&url, &work, name, "1", "4", hosts.path()))
        .collect();
    let client = Client::new(&url).unwrap().with_server_token(&app).unwrap();
    let dir = tempfile::tempdir().unwrap();
    // 4 s at 4×: 1 s trials; 6 trials on 2 phones take about 3 s.
    let recording = sitar_tests::sim_recording(dir.path(), "walk.sitar", 4.0, 9);
    let id = sim_session(&client, &recording, 6, "trim_mean_30");
    let deadline = Instant::now() + Duration::from_secs(60);
    // Killed once 2 of the 6 trials are in (the 4 others take another 2 s).
    while client.status(&id).unwrap().trials_done < 2 {
        assert!(Instant::now() < deadline, "no trial arrived");
        std::thread::sleep(Duration::from_millis(20));
    }
    server.signal("KILL");
    drop(server);
    let before = client.status(&id);
    assert!(before.is_err(), "the server is down: {before:?}");
    let (_server, again) = serve_on(data.path(), "2", "sim", &addr);
    assert_eq!(again, url);
    let status = wait(&client, &id, Duration::from_secs(120));
    assert_eq!(status.state.as_str(), "done", "{status:?}");
    assert_eq!(status.trials_done, 6, "each trial once: {status:?}");
    let expected = embedded_results(&recording, 6, "trim_mean_30");
    assert_eq!(client.results_json(&id).unwrap(), expected.0);
}

#[test]
fn a_worker_with_a_token_the_server_refuses_ends_saying_why() {
    let data = tempfile::tempdir().unwrap();
    let app = token(data.path(), "app", "lab-app");
    let (_server, url) = serve(data.path(), "5");
    let hosts = tempfile::tempdir().unwrap();
    for (bad, status) in [
        (app.as_str(), "403"),
        ("sitar_0123456789abcdef0123456789", "401"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_sitar"))
            .args([
                "worker",
                "--server",
                &url,
                "--token",
                bad,
                "--playback",
                "sim",
            ])
            .arg("--data")
            .arg(hosts.path())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{stderr}");
        assert!(
            stderr.contains("registering host") && stderr.contains(status),
            "{stderr}"
        );
        assert!(
            !stderr.contains(bad),
            "the token is never printed: {stderr}"
        );
    }
    // The token from a file; an empty file is refused naming it.
    let file = hosts.path().join("worker.token");
    std::fs::write(&file, "\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_sitar"))
        .args([
            "worker",
            "--server",
            &url,
            "--playback",
            "sim",
            "--token-file",
        ])
        .arg(&file)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("worker.token"),
        "{stderr}"
    );
}
