//! The `adb` playback against a fake `adb` on PATH that behaves like phones.
//!
//! One test function: it sets PATH and FAKE_ADB_ROOT for the whole process.

use std::path::Path;
use std::time::Duration;

use sitar_client::{NewSession, SessionState};
use sitar_server::{PlaybackKind, ServerConfig};
use sitar_tests::*;

fn fake_phones(root: &Path, serials: &[&str], pool: &[sitar_estimator::Trajectory]) {
    let _ = std::fs::remove_dir_all(root);
    std::fs::create_dir_all(root.join("pool")).unwrap();
    for (k, t) in pool.iter().enumerate() {
        std::fs::write(
            root.join("pool").join(format!("trial_{k}.txt")),
            tum_text(t),
        )
        .unwrap();
    }
    std::fs::write(root.join("counter"), "0\n").unwrap();
    for s in serials {
        std::fs::create_dir_all(root.join("phones").join(s)).unwrap();
    }
}

fn adb_config(data: &Path) -> ServerConfig {
    let mut config = ServerConfig::new(data);
    config.playback = PlaybackKind::Adb;
    config.adb.poll_interval = Duration::from_millis(30);
    config.adb.trial_timeout_slack = Duration::from_secs(10);
    config
}

#[test]
fn adb_playback_with_fake_phones() {
    let dir = tempfile::tempdir().unwrap();
    let bin = dir.path().join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fake_adb.sh"),
        bin.join("adb"),
    )
    .unwrap();
    let phones = dir.path().join("phones-root");
    // SAFETY: the only test in this binary, set before any thread that reads the environment.
    unsafe {
        std::env::set_var(
            "PATH",
            format!(
                "{}:{}",
                bin.display(),
                std::env::var("PATH").unwrap_or_default()
            ),
        );
        std::env::set_var("FAKE_ADB_ROOT", &phones);
        std::env::set_var("FAKE_TRIAL_SECONDS", "0.3");
    }
    let rec = sitar_sim::Recording::demo(3.0, 30.0, 21).unwrap();
    let pool = sitar_sim::simulate_trials(&rec, 12);
    let mp4 = dir.path().join("recording.mp4");
    std::fs::write(&mp4, minimal_mp4(300)).unwrap();
    let new = |trials| NewSession {
        trials,
        setting: "trim_mean_30".into(),
        playback: "adb".into(),
        window_frames: None,
        pose_relation: None,
    };

    // One phone: trials arrive in order, so the numbers equal the estimator's.
    fake_phones(&phones, &["PHONE1"], &pool);
    let server = start(adb_config(&dir.path().join("data")));
    let client = sitar_tests::client(&server);
    let devices: serde_json::Value = serde_json::from_str(&client.devices_json().unwrap()).unwrap();
    assert_eq!(devices["devices"][0]["serial"], "PHONE1");
    assert_eq!(devices["devices"][0]["state"], "device");
    let id = client.create_session(&new(4)).unwrap();
    client.upload_recording(&id, &mp4, &mut |_, _| {}).unwrap();
    let mut first_eta = None;
    let status = client
        .wait(
            &id,
            Duration::from_millis(30),
            Duration::from_secs(60),
            &mut |s| {
                if s.state == SessionState::Playing && first_eta.is_none() {
                    first_eta = s.eta_s;
                }
            },
        )
        .unwrap();
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert_eq!(status.trials_done, 4);
    // d·⌈T/D⌉ with d = 0.3 s from the mp4 header, T = 4, D = 1 (plus 0.5 s for the estimate).
    let eta = first_eta.expect("an ETA while playing");
    assert!(eta <= 1.2 + 0.5 + 1e-9 && eta > 0.5, "eta {eta}");
    assert_same_results(
        &client.results_csv(&id).unwrap(),
        &direct_csv(&pool[..4], "trim_mean_30"),
    );
    let log = std::fs::read_to_string(phones.join("log")).unwrap();
    assert!(log.contains("PHONE1 push "), "{log}");
    assert!(
        log.contains("am start -n org.sitar.playback/.PlaybackActivity --ei trials 4"),
        "{log}"
    );
    assert!(
        log.contains("pull /sdcard/sitar/out/trajectory_3.txt"),
        "{log}"
    );
    drop(server);

    // Two phones, one lost after its first trial: its trials go to the other.
    fake_phones(&phones, &["PHONE1", "PHONE2"], &pool);
    std::fs::write(phones.join("phones/PHONE2/.lose_after"), "1").unwrap();
    let server = start(adb_config(&dir.path().join("data")));
    let client = sitar_tests::client(&server);
    let id = client.create_session(&new(6)).unwrap();
    client.upload_recording(&id, &mp4, &mut |_, _| {}).unwrap();
    let status = client
        .wait(
            &id,
            Duration::from_millis(30),
            Duration::from_secs(60),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert_eq!(status.trials_done, 6);
    let log = std::fs::read_to_string(phones.join("log")).unwrap();
    let starts_on_1 = log
        .lines()
        .filter(|l| l.starts_with("PHONE1 shell am start"))
        .count();
    assert!(
        starts_on_1 >= 2,
        "PHONE1 took over the lost phone's trials: {log}"
    );
    assert!(phones.join("phones/PHONE2/.lost").exists());
    let csv = client.results_csv(&id).unwrap();
    assert!(parse_csv(&csv).len() > 50);
    drop(server);

    // A phone whose app hangs misses its deadline (2·d + slack); its trials go to the other.
    fake_phones(&phones, &["PHONE1", "PHONE3"], &pool);
    std::fs::write(phones.join("phones/PHONE3/.hang"), "").unwrap();
    let mut config = adb_config(&dir.path().join("data"));
    config.adb.trial_timeout_slack = Duration::from_millis(500);
    let server = start(config);
    let client = sitar_tests::client(&server);
    let id = client.create_session(&new(4)).unwrap();
    client.upload_recording(&id, &mp4, &mut |_, _| {}).unwrap();
    let status = client
        .wait(
            &id,
            Duration::from_millis(30),
            Duration::from_secs(60),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert_eq!(status.trials_done, 4);
    let log = std::fs::read_to_string(phones.join("log")).unwrap();
    assert!(
        log.contains("PHONE3 shell am force-stop org.sitar.playback"),
        "{log}"
    );
    let pulls_from_3 = log.lines().filter(|l| l.starts_with("PHONE3 pull")).count();
    assert_eq!(pulls_from_3, 0);
    drop(server);

    // No phone at all: the session fails and says why.
    fake_phones(&phones, &[], &pool);
    let server = start(adb_config(&dir.path().join("data")));
    let client = sitar_tests::client(&server);
    let id = client.create_session(&new(2)).unwrap();
    client.upload_recording(&id, &mp4, &mut |_, _| {}).unwrap();
    let status = client
        .wait(
            &id,
            Duration::from_millis(30),
            Duration::from_secs(30),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(status.state, SessionState::Failed);
    assert!(status.error.unwrap().contains("no playback phone"));
}
