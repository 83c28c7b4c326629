//! The `adb` playback against a fake `adb` on PATH that behaves like phones
//! running the shipped playback app (`tests/fake_adb.sh` checks the contract of
//! docs/playback-contract.md: the `am start` options and extras, an installed
//! activity, the app's own folder).
//!
//! One test function: it sets PATH and FAKE_ADB_ROOT for the whole process.

mod playback_support;

use std::path::Path;
use std::time::Duration;

use sitar_client::{NewSession, SessionState};
use sitar_server::{PlaybackKind, ServerConfig};
use sitar_tests::*;

/// Fake phones with the Kotlin playback app (as its manifest declares it) installed.
fn fake_phones(root: &Path, serials: &[&str], pool: &[sitar_estimator::Trajectory]) {
    let component = playback_support::kotlin_playback_app().component();
    fake_phones_with(root, serials, pool, &component);
}

fn fake_phones_with(
    root: &Path,
    serials: &[&str],
    pool: &[sitar_estimator::Trajectory],
    installed: &str,
) {
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
        let phone = root.join("phones").join(s);
        std::fs::create_dir_all(&phone).unwrap();
        std::fs::write(phone.join(".installed"), format!("{installed}\n")).unwrap();
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
    // SAFETY: the only test in this binary, before any thread that reads the environment.
    let phones = unsafe { sitar_tests::fake_adb_on_path(dir.path(), "0.3") };
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
    // The backend's defaults are the shipped app's package and its own external folder.
    let files = "/sdcard/Android/data/io.github.sitar.playback/files";
    assert!(
        log.lines()
            .any(|l| l.starts_with("PHONE1 push ")
                && l.ends_with(&format!(" {files}/recording.mp4"))),
        "{log}"
    );
    assert!(
        log.contains(&format!(
            "PHONE1 shell am start -S -W -n io.github.sitar.playback/.PlaybackActivity \
             --ei trials 4 --ei first 0 --es recording {files}/recording.mp4 --es output {files}/out"
        )),
        "{log}"
    );
    assert!(
        log.contains(&format!(
            "PHONE1 shell rm -f {files}/out/trajectory_*.txt {files}/out/status.txt"
        )),
        "{log}"
    );
    assert!(
        log.contains(&format!("pull {files}/out/trajectory_3.txt")),
        "{log}"
    );
    assert_eq!(
        std::fs::read_to_string(phones.join(format!("phones/PHONE1{files}/out/status.txt")))
            .unwrap(),
        "done 4/4\n"
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
    // PHONE1's later shares (its own second one, the lost phone's trials) start at a
    // later trial: their files are numbered from there.
    let later: Vec<&str> = log
        .lines()
        .filter(|l| l.starts_with("PHONE1 shell am start") && !l.contains("--ei first 0 "))
        .collect();
    assert!(!later.is_empty(), "a share with first > 0: {log}");
    for start in later {
        let first: u32 = start
            .split("--ei first ")
            .nth(1)
            .and_then(|r| r.split_whitespace().next())
            .and_then(|n| n.parse().ok())
            .unwrap();
        let serial = start.split_whitespace().next().unwrap();
        assert!(
            log.contains(&format!("{serial} pull /sdcard/Android/data/io.github.sitar.playback/files/out/trajectory_{first}.txt")),
            "{serial} pulls trajectory_{first}: {log}"
        );
    }
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
        log.contains("PHONE3 shell am force-stop io.github.sitar.playback"),
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
    drop(server);

    // The app reports a failure in its status file: the phone's share fails with that message.
    fake_phones(&phones, &["PHONE4"], &pool);
    std::fs::write(
        phones.join("phones/PHONE4/.fail"),
        "ARCore cannot play the recording: PlaybackFailedException",
    )
    .unwrap();
    let server = start(adb_config(&dir.path().join("data")));
    let client = sitar_tests::client(&server);
    let id = client.create_session(&new(3)).unwrap();
    client.upload_recording(&id, &mp4, &mut |_, _| {}).unwrap();
    let status = wait_done(&client, &id);
    assert_eq!(status.state, SessionState::Failed, "{status:?}");
    let error = status.error.unwrap();
    assert!(
        error.contains("PHONE4: the playback app failed: ARCore cannot play the recording: PlaybackFailedException"),
        "{error}"
    );
    let log = std::fs::read_to_string(phones.join("log")).unwrap();
    assert!(
        log.contains(
            "PHONE4 shell cat /sdcard/Android/data/io.github.sitar.playback/files/out/status.txt"
        ),
        "{log}"
    );
    drop(server);

    // Another app is installed: am's own error, not a wait for the deadline.
    fake_phones_with(&phones, &["PHONE5"], &pool, "com.example.other/.Main");
    let server = start(adb_config(&dir.path().join("data")));
    let client = sitar_tests::client(&server);
    let id = client.create_session(&new(2)).unwrap();
    let began = std::time::Instant::now();
    client.upload_recording(&id, &mp4, &mut |_, _| {}).unwrap();
    let status = wait_done(&client, &id);
    assert_eq!(status.state, SessionState::Failed, "{status:?}");
    let error = status.error.unwrap();
    assert!(
        error.contains("does not exist") && error.contains("is the playback app installed"),
        "{error}"
    );
    assert!(
        began.elapsed() < Duration::from_secs(10),
        "failed at once: {:?}",
        began.elapsed()
    );
    drop(server);

    // A Unity playback app: another package and activity, its own folder by default.
    let unity = "com.example.unityplayback/com.unity3d.player.UnityPlayerActivity";
    fake_phones_with(&phones, &["PHONE6"], &pool, unity);
    let mut config = adb_config(&dir.path().join("data"));
    config.adb.package = "com.example.unityplayback".into();
    config.adb.activity = "com.unity3d.player.UnityPlayerActivity".into();
    let server = start(config);
    let client = sitar_tests::client(&server);
    let id = client.create_session(&new(2)).unwrap();
    client.upload_recording(&id, &mp4, &mut |_, _| {}).unwrap();
    let status = wait_done(&client, &id);
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    let log = std::fs::read_to_string(phones.join("log")).unwrap();
    assert!(
        log.contains(&format!(
            "PHONE6 shell am start -S -W -n {unity} --ei trials 2 --ei first 0 \
             --es recording /sdcard/Android/data/com.example.unityplayback/files/recording.mp4"
        )),
        "{log}"
    );
    drop(server);

    // A recording that is not an MP4 is refused at upload (422), for adb sessions only.
    fake_phones(&phones, &["PHONE1"], &pool);
    let server = start(adb_config(&dir.path().join("data")));
    let client = sitar_tests::client(&server);
    let id = client.create_session(&new(2)).unwrap();
    let url = format!("{}/v1/sessions/{id}/recording", server.url());
    let garbage: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 24) as u8)
        .collect();
    let (code, ct, body) = raw("PUT", &url, Some("application/octet-stream"), &garbage, &[]);
    assert_eq!(error_code(code, &ct, &body, 422), "invalid_content");
    assert!(body.contains("not an MP4"), "{body}");
    let status = client.status(&id).unwrap();
    assert_eq!(
        status.state,
        SessionState::Created,
        "nothing was played: {status:?}"
    );
    // The same session then takes the real recording.
    client.upload_recording(&id, &mp4, &mut |_, _| {}).unwrap();
    assert_eq!(wait_done(&client, &id).state, SessionState::Done);
    // The legacy route, when the server plays over adb.
    let (ct, form) = multipart("recording", "session.mp4", b"not an mp4 at all, just text");
    let (code, rct, body) = raw(
        "POST",
        &format!("{}/recording", server.url()),
        Some(&ct),
        &form,
        &[],
    );
    assert_eq!(error_code(code, &rct, &body, 422), "invalid_content");
    drop(server);

    // Deleting a playing adb session stops the app on the phone, then deletes it.
    fake_phones(&phones, &["PHONE7"], &pool);
    std::fs::write(phones.join("phones/PHONE7/.hang"), "").unwrap();
    let server = start(adb_config(&dir.path().join("data")));
    let client = sitar_tests::client(&server);
    let id = client.create_session(&new(4)).unwrap();
    client.upload_recording(&id, &mp4, &mut |_, _| {}).unwrap();
    let log_has = |needle: &str| {
        std::fs::read_to_string(phones.join("log"))
            .unwrap_or_default()
            .contains(needle)
    };
    let began = std::time::Instant::now();
    while !log_has("PHONE7 shell am start") {
        assert!(
            began.elapsed() < Duration::from_secs(20),
            "the app never started"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    client.delete_session(&id).unwrap();
    assert_eq!(client.status(&id).unwrap_err().status(), Some(404));
    assert!(
        log_has("PHONE7 shell am force-stop io.github.sitar.playback"),
        "the app was stopped"
    );
    drop(server);
}
