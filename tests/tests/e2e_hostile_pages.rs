//! Hostile strings in every field that reaches a page, loaded by headless Chromium
//! (Debian `chromium`) from the real server over loopback: they come out as text, never
//! as markup, and no script of theirs runs.
//!
//! What reaches the pages from outside the server: device serials (from `adb devices`;
//! shown in the devices table, in "played by" as `adb:SERIAL`, in error texts), the
//! playback app's failure message (read from the phone's status file; the session's
//! note on the overview) and session options (setting and pose relation are closed
//! lists: hostile ones are refused with a JSON error and never stored). The report page
//! shows only the session id and server-made values; it is loaded for the session the
//! hostile phone played, and for one where the phone returned a hostile trial file (the
//! trial is dropped: its text reaches no page). The phones are `tests/fake_adb.sh` (a
//! fake `adb` on PATH).
//!
//! One test function: it sets PATH and FAKE_ADB_ROOT for the whole process.

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use sitar_client::{NewSession, SessionState};
use sitar_server::{PlaybackKind, ServerConfig};
use sitar_tests::*;

/// What every hostile string carries: a script element, an attribute break-out with an
/// event handler, both quotes, an entity, control characters. Each payload, had it run,
/// would set the page title to `PWNED…`.
const PAYLOAD: &str = "<script>document.title='PWNED-script'</script>\
     \"><img src=x onerror=\"document.title='PWNED-img'\">'\"&amp;\u{1}\u{7}\u{1b}[31m";

/// A serial `adb devices` can print: no white space (the server splits on it), no `/`
/// (the fake phones are directories), a control character.
const SERIAL: &str = "<b>PWNED-serial\"'&amp;<i>\u{1}";

/// Runs headless Chromium on `url` and returns the DOM after the page's scripts ran.
fn dump_dom(url: &str) -> String {
    let profile = tempfile::tempdir().unwrap();
    let out = Command::new("/usr/bin/chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--no-default-browser-check",
            "--disable-extensions",
            // Nothing leaves loopback.
            "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1",
            "--proxy-server=http://127.0.0.1:9",
            "--proxy-bypass-list=<-loopback>;127.0.0.1",
            "--virtual-time-budget=3000",
            "--dump-dom",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg(url)
        .output()
        .unwrap();
    assert!(out.status.success(), "chromium: {out:?}");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The page's `<title>` text.
fn title(dom: &str) -> &str {
    let start = dom.find("<title>").expect("a title") + "<title>".len();
    &dom[start..start + dom[start..].find("</title>").unwrap()]
}

/// No hostile markup became an element, no payload ran, and the script elements are only
/// the page's own. (A serialised DOM escapes `<`, `>` and `&` in text, not quotes: an
/// `<img` or `<b>PWNED` in it is an element.)
fn assert_inert(dom: &str, page: &str) {
    assert!(
        !title(dom).contains("PWNED"),
        "{page}: a payload ran: title {:?}",
        title(dom)
    );
    for markup in [
        "<script>document",
        "<img src=\"x\"",
        "<img src=x",
        "<b>PWNED",
    ] {
        assert!(
            !dom.contains(markup),
            "{page}: hostile markup {markup:?} became an element"
        );
    }
    let own = dom
        .matches("<script type=\"module\" src=\"/assets/")
        .count();
    assert_eq!(
        dom.matches("<script").count(),
        own,
        "{page}: a script element that is not the page's own"
    );
}

fn adb_config(data: &Path) -> ServerConfig {
    let mut config = ServerConfig::new(data);
    config.playback = PlaybackKind::Adb;
    config.adb.poll_interval = Duration::from_millis(30);
    config.adb.trial_timeout_slack = Duration::from_secs(10);
    config
}

#[test]
fn hostile_strings_reach_the_pages_as_text() {
    if !Path::new("/usr/bin/chromium").exists() {
        println!(
            "SKIPPED hostile strings in Chromium: /usr/bin/chromium is not installed (.ci/run installs it)"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // SAFETY: the only test in this binary, before any thread that reads the environment.
    let root = unsafe { sitar_tests::fake_adb_on_path(dir.path(), "0.1") };
    // The trial pool and one phone with the playback app, under the hostile serial.
    let rec = sitar_sim::Recording::demo(3.0, 30.0, 21).unwrap();
    let pool = sitar_sim::simulate_trials(&rec, 8);
    std::fs::create_dir_all(root.join("pool")).unwrap();
    for (k, t) in pool.iter().enumerate() {
        std::fs::write(root.join(format!("pool/trial_{k}.txt")), tum_text(t)).unwrap();
    }
    std::fs::write(root.join("counter"), "0\n").unwrap();
    let phone = root.join("phones").join(SERIAL);
    std::fs::create_dir_all(&phone).unwrap();
    std::fs::write(
        phone.join(".installed"),
        "io.github.sitar.playback/.PlaybackActivity\n",
    )
    .unwrap();
    let mp4 = dir.path().join("recording.mp4");
    std::fs::write(&mp4, minimal_mp4(200)).unwrap();

    let server = start(adb_config(&dir.path().join("data")));
    let client = client(&server);
    let devices: serde_json::Value = serde_json::from_str(&client.devices_json().unwrap()).unwrap();
    assert_eq!(devices["devices"][0]["serial"], SERIAL, "{devices}");
    let new = |setting: &str| NewSession {
        trials: 3,
        setting: setting.into(),
        playback: "adb".into(),
        window_frames: None,
        pose_relation: None,
    };

    // Session options: a hostile setting is refused, so it never reaches a page.
    let refused = client.create_session(&new(&format!("{PAYLOAD}{}", "A".repeat(100_000))));
    assert!(refused.is_err(), "a hostile setting is refused");
    let mut hostile_relation = new("trim_mean_30");
    hostile_relation.pose_relation = Some(PAYLOAD.into());
    let refused = client.create_session(&hostile_relation);
    assert!(refused.is_err(), "a hostile pose relation is refused");
    let (code, _, sessions) = raw(
        "GET",
        &format!("{}/v1/sessions", server.url()),
        None,
        b"",
        &[],
    );
    assert_eq!(code, 200);
    assert!(
        !sessions.contains("PWNED"),
        "nothing hostile stored: {sessions}"
    );

    // A session the hostile phone plays to the end: its serial is in "played by".
    let done = client.create_session(&new("trim_mean_30")).unwrap();
    client
        .upload_recording(&done, &mp4, &mut |_, _| {})
        .unwrap();
    let status = wait_done(&client, &done);
    assert_eq!(status.state, SessionState::Done, "{status:?}");

    // A session whose playback app fails with a hostile, ~100 KB message: the error text.
    let long_tail = "L".repeat(100_000);
    std::fs::write(phone.join(".fail"), format!("{PAYLOAD}{long_tail}")).unwrap();
    let failed = client.create_session(&new("trim_mean_30")).unwrap();
    client
        .upload_recording(&failed, &mp4, &mut |_, _| {})
        .unwrap();
    let status = wait_done(&client, &failed);
    assert_eq!(status.state, SessionState::Failed, "{status:?}");
    let error = status.error.unwrap();
    assert!(error.contains(PAYLOAD), "the message is kept: {error:.300}");
    assert!(error.contains(SERIAL), "the message names the phone");

    // A session whose phone returns a hostile trial file (the second of the pool's next
    // three): the trial is dropped, the session ends with the other two.
    std::fs::remove_file(phone.join(".fail")).unwrap();
    let hostile_trial = format!("0 0 0 0 0 0 0 1\n{PAYLOAD} 1 2 3\n");
    std::fs::write(root.join("pool/trial_4.txt"), &hostile_trial).unwrap();
    let bad_trial = client.create_session(&new("trim_mean_30")).unwrap();
    client
        .upload_recording(&bad_trial, &mp4, &mut |_, _| {})
        .unwrap();
    let status = wait_done(&client, &bad_trial);
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert_eq!(status.trials_done, 2, "{status:?}");

    // The overview, opened as an operator would: `/?token=` sets the cookie, then `/`.
    let overview = dump_dom(&format!("{}/?token={ADMIN_TOKEN}", server.url()));
    assert!(
        overview.contains("<table id=\"sessions\""),
        "the overview, not a login error: {:.2000}",
        overview
    );
    assert_eq!(title(&overview), "SiTAR backend");
    assert_inert(&overview, "overview");
    // The hostile strings are there, as text.
    let payload_text = "&lt;script&gt;document.title='PWNED-script'&lt;/script&gt;\
         \"&gt;&lt;img src=x onerror=\"document.title='PWNED-img'\"&gt;'\"&amp;amp;";
    assert!(
        overview.contains(payload_text),
        "the failure message shows as text"
    );
    assert!(
        overview.contains(&long_tail[..1000]),
        "the long message is on the page"
    );
    let serial_text = "&lt;b&gt;PWNED-serial\"'&amp;amp;&lt;i&gt;";
    assert!(
        overview.contains(&format!("<code>{serial_text}")),
        "the serial shows in the devices table"
    );
    assert!(
        overview.contains(&format!("<code>adb:{serial_text}")),
        "the serial shows in \"played by\""
    );

    // The report of the session the hostile phone played.
    let report = dump_dom(&format!(
        "{}/v1/sessions/{done}/report?token={ADMIN_TOKEN}",
        server.url()
    ));
    assert!(
        report.contains("<table id=\"regions\""),
        "the report, not an error: {:.2000}",
        report
    );
    assert_inert(&report, "report");
    // And of the session with the hostile trial file: nothing of it shows.
    let report = dump_dom(&format!(
        "{}/v1/sessions/{bad_trial}/report?token={ADMIN_TOKEN}",
        server.url()
    ));
    assert!(report.contains("<table id=\"regions\""), "{:.2000}", report);
    assert_inert(&report, "report of the hostile trial's session");
    assert!(
        !report.contains("PWNED"),
        "the hostile trial is not on the page"
    );
    drop(server);
}
