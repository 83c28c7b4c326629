//! The freeze of issue 11 tried again: one client asks for 600 long sim jobs; they wait in
//! the queue holding no thread, and another client's 2-trial `upload` session still gets
//! its estimate within 2 s while devices and uploads answer at once. Bounded: 600 sessions,
//! about 20 s.

use std::time::{Duration, Instant};

use serde_json::Value;
use sitar_tests::*;

const LONG_JOBS: usize = 600;

/// The threads of this process (the server runs in it).
fn threads() -> usize {
    std::fs::read_to_string("/proc/self/status")
        .unwrap()
        .lines()
        .find_map(|l| l.strip_prefix("Threads:"))
        .map(|n| n.trim().parse().unwrap())
        .unwrap()
}

fn request(method: &str, url: &str, token: &str, ct: Option<&str>, body: &[u8]) -> (u16, String) {
    let auth = format!("Bearer {token}");
    let (status, _, text) = raw(method, url, ct, body, &[("authorization", &auth)]);
    (status, text)
}

fn id_of(text: &str) -> String {
    let doc: Value = serde_json::from_str(text).unwrap();
    doc["id"].as_str().unwrap().to_owned()
}

#[test]
fn six_hundred_long_jobs_never_delay_another_clients_estimate() {
    let dir = tempfile::tempdir().unwrap();
    // Real time: a 30 s recording plays one trial every 30 s, 100 trials a job.
    let mut config = sim_config(&dir.path().join("data"), 1.0, 1);
    config.playback_workers = 4;
    config.jobs_per_token = 2;
    config.limits.sessions_per_hour = 10_000;
    let server = start(config);
    let base = server.url();
    let rec = std::fs::read(sim_recording(dir.path(), "walk.rec", 30.0, 3)).unwrap();
    let threads_before = threads();

    // One client: 600 sessions of 100 trials, each with its recording (4 uploaders).
    std::thread::scope(|scope| {
        for _ in 0..4 {
            scope.spawn(|| {
                for _ in 0..LONG_JOBS / 4 {
                    let (code, text) = request(
                        "POST",
                        &format!("{base}/v1/sessions"),
                        APP_TOKEN,
                        Some("application/json"),
                        br#"{"playback":"sim","trials":100}"#,
                    );
                    assert_eq!(code, 201, "{text}");
                    let id = id_of(&text);
                    let (code, text) = request(
                        "PUT",
                        &format!("{base}/v1/sessions/{id}/recording"),
                        APP_TOKEN,
                        Some("application/octet-stream"),
                        &rec,
                    );
                    assert!(code < 300, "{code} {text}");
                }
            });
        }
    });
    // They wait in the queue: two play (the per-token limit), the rest hold no thread.
    let (code, text) = request(
        "GET",
        &format!("{base}/v1/sessions?limit=500"),
        APP_TOKEN,
        None,
        b"",
    );
    assert_eq!(code, 200, "{text}");
    let doc: Value = serde_json::from_str(&text).unwrap();
    let sessions = doc["sessions"].as_array().unwrap();
    let playing = sessions.iter().filter(|s| s["state"] == "playing").count();
    let queued = sessions
        .iter()
        .filter(|s| s["queue_position"].is_u64())
        .count();
    assert!(playing <= 2, "{playing} playing");
    assert!(queued >= 500 - 2, "{queued} of 500 listed are queued");
    let threads_loaded = threads();
    assert!(
        threads_loaded < threads_before + 64,
        "{threads_before} threads before, {threads_loaded} with {LONG_JOBS} jobs"
    );

    // Another client: devices and an upload answer at once, and its estimate is quick.
    let started = Instant::now();
    let (code, text) = request("GET", &format!("{base}/v1/devices"), ADMIN_TOKEN, None, b"");
    assert_eq!(code, 200, "{text}");
    let devices_s = started.elapsed().as_secs_f64();
    let trials = sitar_sim::simulate_trials(&sitar_sim::Recording::demo(3.0, 30.0, 7).unwrap(), 2);
    let started = Instant::now();
    let (code, text) = request(
        "POST",
        &format!("{base}/v1/sessions"),
        APP2_TOKEN,
        Some("application/json"),
        br#"{"playback":"upload","trials":2}"#,
    );
    assert_eq!(code, 201, "{text}");
    let id = id_of(&text);
    let (code, text) = request(
        "PUT",
        &format!("{base}/v1/sessions/{id}/recording"),
        APP2_TOKEN,
        Some("application/octet-stream"),
        &rec,
    );
    assert!(code < 300, "{code} {text}");
    let upload_s = started.elapsed().as_secs_f64();
    let started = Instant::now();
    for trial in &trials {
        let (code, text) = request(
            "POST",
            &format!("{base}/v1/sessions/{id}/trials"),
            APP2_TOKEN,
            Some("text/plain"),
            tum_text(trial).as_bytes(),
        );
        assert!(code < 300, "{code} {text}");
    }
    let (code, text) = request(
        "POST",
        &format!("{base}/v1/sessions/{id}/estimate"),
        APP2_TOKEN,
        None,
        b"",
    );
    assert_eq!(code, 202, "{text}");
    loop {
        let (code, text) = request(
            "GET",
            &format!("{base}/v1/sessions/{id}"),
            APP2_TOKEN,
            None,
            b"",
        );
        assert_eq!(code, 200, "{text}");
        let doc: Value = serde_json::from_str(&text).unwrap();
        if doc["state"] == "done" {
            break;
        }
        assert_ne!(doc["state"], "failed", "{doc}");
        assert!(
            started.elapsed() < Duration::from_secs(2),
            "not done after 2 s: {doc}"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    let estimate_s = started.elapsed().as_secs_f64();
    assert!(
        devices_s < 1.0 && upload_s < 2.0,
        "devices {devices_s} s, upload {upload_s} s"
    );
    eprintln!(
        "{LONG_JOBS} queued jobs: devices {devices_s:.3} s, upload {upload_s:.3} s, 2 trials and \
         estimate {estimate_s:.3} s, threads {threads_before} → {threads_loaded}"
    );
}
