//! The report of a demo-like session in headless Chromium (Debian `chromium`), loaded from
//! the running server with every host but loopback refused (`scripts/report-screenshot`):
//! the 3-D canvas shows the walk (pixel statistics of the screenshot, not a stored image),
//! the regions table lists the markers the phone places, the console shows no error and
//! no request leaves loopback.

use std::path::{Path, PathBuf};
use std::process::Command;

use sitar_client::{NewSession, SessionState};
use sitar_core::{DisplayRotation, SessionConfig};
use sitar_tests::*;

/// (width, height, RGB rows) of a PNG.
fn read_png(path: &Path) -> (usize, usize, Vec<[u8; 3]>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    let pixels = buf[..info.buffer_size()]
        .chunks(channels)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    (info.width as usize, info.height as usize, pixels)
}

/// Every `"url"` and address string in a Chromium net log.
fn netlog_strings(value: &serde_json::Value, key: &str, out: &mut Vec<String>) {
    match value {
        serde_json::Value::Object(map) => {
            for (k, v) in map {
                match v {
                    serde_json::Value::String(s) if k == key => out.push(s.clone()),
                    _ => netlog_strings(v, key, out),
                }
            }
        }
        serde_json::Value::Array(items) => items.iter().for_each(|v| netlog_strings(v, key, out)),
        _ => {}
    }
}

#[test]
fn the_report_renders_the_walk_in_chromium_offline() {
    if !Path::new("/usr/bin/chromium").exists() {
        println!(
            "SKIPPED the report in Chromium: /usr/bin/chromium is not installed (.ci/run installs it)"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // The demo's walk: 15 s, seed 42, 8 trials on 2 simulated phones.
    let recording = sim_recording(dir.path(), "walk.rec", 15.0, 42);
    let server = start(sim_config(&dir.path().join("data"), 40.0, 2));
    let client = client(&server);
    let id = client
        .create_session(&NewSession {
            trials: 8,
            setting: "trim_mean_30".into(),
            playback: "sim".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    client
        .upload_recording(&id, &recording, &mut |_, _| {})
        .unwrap();
    assert_eq!(wait_done(&client, &id).state, SessionState::Done);
    // The markers the phone places with these results.
    let rec = sitar_sim::Recording::from_bytes(&std::fs::read(&recording).unwrap()).unwrap();
    let mut phone = rec
        .phone_session(
            SessionConfig::from_json(r#"{"convention":"arcore"}"#).unwrap(),
            DisplayRotation::Deg90,
        )
        .unwrap();
    phone
        .load_results(&client.results_json(&id).unwrap())
        .unwrap();
    let markers = phone.markers().unwrap();
    assert!(!markers.is_empty());

    let out = dir.path().join("shot");
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scripts/report-screenshot");
    let url = format!(
        "{}/v1/sessions/{id}/report?token={ADMIN_TOKEN}",
        server.url()
    );
    let status = Command::new(&script)
        .arg(&url)
        .arg(&out)
        .arg("1280x1000")
        .status()
        .unwrap();
    assert!(status.success());

    // The scripts ran: the view says it is ready, and the regions table lists every marker.
    let dom = std::fs::read_to_string(out.join("dom.html")).unwrap();
    assert!(
        dom.contains("data-view=\"ready\""),
        "{}",
        &dom[..dom.len().min(2000)]
    );
    let regions = &dom[dom.find("<table id=\"regions\"").unwrap()..];
    let regions = &regions[..regions.find("</table>").unwrap()];
    for (i, m) in markers.iter().enumerate() {
        assert!(
            regions.contains(&format!("M{}", i + 1)),
            "marker {} (sub-trajectory {}) missing: {regions}",
            i + 1,
            m.subtrajectory
        );
    }

    // No console error: the only console lines allowed are SwiftShader's performance notes.
    let log = std::fs::read_to_string(out.join("console.log")).unwrap();
    let console: Vec<&str> = log
        .lines()
        .filter(|l| l.contains(":CONSOLE"))
        .filter(|l| !l.contains("GL Driver Message"))
        .collect();
    assert!(console.is_empty(), "console: {console:#?}");

    // No request left loopback: every connection went to 127.0.0.1, and every URL the
    // page asked for is this server's.
    let netlog: serde_json::Value = {
        let text = std::fs::read_to_string(out.join("netlog.json")).unwrap();
        // Chromium may leave the log's closing brackets out when it exits.
        serde_json::from_str(&text)
            .or_else(|_| {
                serde_json::from_str(&format!("{}]}}", text.trim_end().trim_end_matches(',')))
            })
            .unwrap()
    };
    // TCP connections (HTTP) and UDP datagrams actually sent. (Chromium `connect`s a UDP
    // socket to a public address to learn its route, sending nothing: not a request.)
    let name_of = |table: &str, id: &serde_json::Value| {
        netlog["constants"][table]
            .as_object()
            .unwrap()
            .iter()
            .find(|(_, v)| *v == id)
            .map(|(k, _)| k.clone())
            .unwrap_or_default()
    };
    let mut connections = 0;
    for event in netlog["events"].as_array().unwrap() {
        let kind = name_of("logEventTypes", &event["type"]);
        let source = name_of("logSourceType", &event["source"]["type"]);
        let counts = (kind.starts_with("TCP_CONNECT") || kind == "SOCKET_CONNECT")
            && !source.starts_with("UDP")
            || kind == "UDP_BYTES_SENT";
        if !counts {
            continue;
        }
        let mut addresses = Vec::new();
        for key in ["address", "remote_address"] {
            netlog_strings(&event["params"], key, &mut addresses);
        }
        for a in addresses {
            connections += 1;
            assert!(
                a.starts_with("127.0.0.1:") || a.starts_with("[::1]:"),
                "{kind} ({source}) to {a}"
            );
        }
    }
    assert!(connections > 0, "no connection in the net log");
    let mut urls = Vec::new();
    netlog_strings(&netlog, "url", &mut urls);
    assert!(
        urls.iter()
            .any(|u| u.ends_with("/assets/three/three.core.js")),
        "{urls:?}"
    );
    assert!(urls.iter().any(|u| u.ends_with("/scene.json")));

    // The canvas (background #f4f5f7) shows the walk: enough drawn pixels, in the classes'
    // colours.
    let (w, _h, px) = read_png(&out.join("screenshot.png"));
    let bg = [244u8, 245, 247];
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for (i, p) in px.iter().enumerate() {
        if *p == bg {
            let (x, y) = (i % w, i / w);
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
    }
    assert!(
        x1 > x0 + 400 && y1 > y0 + 200,
        "no canvas found: ({x0},{y0})–({x1},{y1})"
    );
    let (mut drawn, mut blue, mut yellow, mut total) = (0usize, 0usize, 0usize, 0usize);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let [r, g, b] = px[y * w + x].map(i32::from);
            total += 1;
            if [r, g, b] != [244, 245, 247] {
                drawn += 1;
            }
            if b > r + 60 && b > 150 {
                blue += 1;
            }
            if r > 170 && g > 130 && b < 90 {
                yellow += 1;
            }
        }
    }
    let share = drawn as f64 / total as f64;
    assert!((0.02..0.9).contains(&share), "drawn share {share}");
    assert!(
        blue > 200 && yellow > 200,
        "class colours: blue {blue}, yellow {yellow}"
    );
    println!(
        "canvas ({x0},{y0})–({x1},{y1}): {:.1} % drawn, {blue} blue, {yellow} yellow px",
        share * 100.0
    );
}
