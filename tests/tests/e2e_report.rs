//! The report of a demo-like session in headless Chromium (Debian `chromium`), loaded from
//! the running server with every host but loopback refused (`scripts/report-screenshot`):
//! the 3-D canvas shows the walk (pixel statistics of the screenshot, not a stored image),
//! the regions table lists the markers the phone places, the console shows no error and
//! no request leaves loopback. A session whose phone sent its camera evidence shows each
//! region's thumbnail and likely causes; its share link shows the same 3-D view with no
//! other token, and reaches nothing of another session.

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

/// Runs `scripts/report-screenshot` on `url` into `out` (1280 × 1000); it must end within
/// two minutes, also on a page that reloads itself.
fn shoot(url: &str, out: &Path) {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scripts/report-screenshot");
    let mut child = Command::new(&script)
        .arg(url)
        .arg(out)
        .arg("1280x1000")
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > std::time::Duration::from_secs(120) {
            child.kill().unwrap();
            panic!("scripts/report-screenshot {url} did not end in 2 minutes");
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    };
    assert!(status.success());
}

/// Whether Chromium is missing (then the test says it skipped `what`).
fn chromium_missing(what: &str) -> bool {
    let missing = !Path::new("/usr/bin/chromium").exists();
    if missing {
        println!("SKIPPED {what}: /usr/bin/chromium is not installed (.ci/run installs it)");
    }
    missing
}

/// The 3-D canvas in the screenshot `png` shows the walk: enough drawn pixels, in the
/// classes' colours (low blue, medium yellow). The drawn share of the canvas.
fn assert_walk_drawn(png: &Path) -> f64 {
    let (drawn, blue, yellow, total) = canvas_pixels(png);
    let share = drawn as f64 / total as f64;
    assert!((0.02..0.9).contains(&share), "drawn share {share}");
    assert!(
        blue > 200 && yellow > 200,
        "class colours: blue {blue}, yellow {yellow}"
    );
    println!(
        "canvas: {:.1} % drawn, {blue} blue, {yellow} yellow px",
        share * 100.0
    );
    share
}

/// The demo's walk (it has problem regions) in `dir`: the recording's file, and the phone
/// session that recorded it with images and depth, saved with its evidence into the
/// returned folder.
fn demo_walk_with_evidence(dir: &Path) -> (PathBuf, sitar_core::Session, PathBuf) {
    let recording = sitar_sim::Recording::demo(15.0, 30.0, 42).unwrap();
    let rec_path = dir.join("walk.rec");
    std::fs::write(&rec_path, recording.to_bytes()).unwrap();
    let phone = phone_walk_with_evidence(&recording);
    let folder = dir.join("phone");
    phone.save(&folder).unwrap();
    (rec_path, phone, folder)
}

/// A sim session of 8 trials (`trim_mean_30`) of `recording`, with the phone's evidence from
/// `evidence` when given, played to the end: its id.
fn played_session(
    client: &sitar_client::Client,
    recording: &Path,
    evidence: Option<&Path>,
) -> String {
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
        .upload_recording(&id, recording, &mut |_, _| {})
        .unwrap();
    if let Some(folder) = evidence {
        client.upload_evidence(&id, folder).unwrap();
    }
    assert_eq!(wait_done(client, &id).state, SessionState::Done);
    id
}

/// (drawn, blue, yellow) pixels of the 3-D canvas (background #f4f5f7) in a screenshot, and
/// the canvas's size.
fn canvas_pixels(png: &Path) -> (usize, usize, usize, usize) {
    let (w, _h, px) = read_png(png);
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
    let (mut drawn, mut blue, mut yellow) = (0, 0, 0);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let [r, g, b] = px[y * w + x].map(i32::from);
            drawn += usize::from([r, g, b] != [244, 245, 247]);
            blue += usize::from(b > r + 60 && b > 150);
            yellow += usize::from(r > 170 && g > 130 && b < 90);
        }
    }
    (drawn, blue, yellow, (x1 - x0 + 1) * (y1 - y0 + 1))
}

/// Console lines of the page, besides SwiftShader's performance notes.
fn console_lines(out: &Path) -> Vec<String> {
    std::fs::read_to_string(out.join("console.log"))
        .unwrap()
        .lines()
        .filter(|l| l.contains(":CONSOLE"))
        .filter(|l| !l.contains("GL Driver Message"))
        .map(str::to_owned)
        .collect()
}

/// Chromium's net log of the page load.
fn netlog(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("netlog.json")).unwrap();
    // Chromium may leave the log's closing brackets out when it exits.
    serde_json::from_str(&text)
        .or_else(|_| serde_json::from_str(&format!("{}]}}", text.trim_end().trim_end_matches(','))))
        .unwrap()
}

/// Every URL the page asked for.
fn requested_urls(netlog: &serde_json::Value) -> Vec<String> {
    let mut urls = Vec::new();
    netlog_strings(netlog, "url", &mut urls);
    urls
}

/// The contents of the element that starts with `open` (up to `close`).
fn section<'a>(dom: &'a str, open: &str, close: &str) -> &'a str {
    let from = &dom[dom
        .find(open)
        .unwrap_or_else(|| panic!("no {open} in {}", &dom[..dom.len().min(3000)]))..];
    &from[..from.find(close).unwrap()]
}

#[test]
fn the_report_renders_the_walk_in_chromium_offline() {
    if chromium_missing("the report in Chromium") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // The demo's walk: 15 s, seed 42, 8 trials on 2 simulated phones.
    let recording = sim_recording(dir.path(), "walk.rec", 15.0, 42);
    let server = start(sim_config(&dir.path().join("data"), 40.0, 2));
    let client = client(&server);
    let id = played_session(&client, &recording, None);
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
    let url = format!(
        "{}/v1/sessions/{id}/report?token={ADMIN_TOKEN}",
        server.url()
    );
    shoot(&url, &out);

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
    let console = console_lines(&out);
    assert!(console.is_empty(), "console: {console:#?}");

    // No request left loopback: every connection went to 127.0.0.1, and every URL the
    // page asked for is this server's.
    let netlog = netlog(&out);
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
    let urls = requested_urls(&netlog);
    assert!(
        urls.iter().any(|u| u.ends_with("/assets/report.bundle.js")),
        "{urls:?}"
    );
    assert!(urls.iter().any(|u| u.ends_with("/scene.json")));

    // The canvas (background #f4f5f7) shows the walk: enough drawn pixels, in the classes'
    // colours.
    assert_walk_drawn(&out.join("screenshot.png"));
}

#[test]
fn regions_show_the_camera_evidence_and_a_share_link_shows_the_same_view() {
    if chromium_missing("evidence and share in Chromium") {
        return;
    }
    use sitar_client::{JobOptions, JobState, UploadJob};
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 40.0, 2));
    let base = server.url();
    // The demo's walk, recorded with images and depth by the phone logic; the upload job
    // sends the recording and the session folder's evidence.
    let (rec_path, mut phone, folder) = demo_walk_with_evidence(dir.path());
    let app = client_with(&server, APP_TOKEN);
    let mut options = JobOptions::new(NewSession {
        trials: 6,
        setting: "trim_mean_30".into(),
        playback: "sim".into(),
        window_frames: None,
        pose_relation: None,
    });
    options.poll_interval = Duration::from_millis(20);
    options.evidence_dir = Some(folder.clone());
    let job = UploadJob::start(app.clone(), &rec_path, options, |_: &str| {
        Ok::<(), std::convert::Infallible>(())
    })
    .unwrap();
    let started = Instant::now();
    while !job.progress().state.is_finished() && started.elapsed() < Duration::from_secs(180) {
        std::thread::sleep(Duration::from_millis(50));
    }
    let progress = job.progress();
    assert_eq!(progress.state, JobState::Done, "{:?}", progress.error);
    assert!(progress.evidence_sent);
    let id = job.server_id().unwrap();
    phone.load_results(&app.results_json(&id).unwrap()).unwrap();

    // The owner's page: every region row has the thumbnail of one of its sub-trajectories,
    // loaded by the browser, and the causes the phone found for it.
    let out = dir.path().join("owner");
    shoot(
        &format!("{base}/v1/sessions/{id}/report?token={ADMIN_TOKEN}"),
        &out,
    );
    let dom = std::fs::read_to_string(out.join("dom.html")).unwrap();
    assert!(
        dom.contains("data-view=\"ready\""),
        "{}",
        &dom[..dom.len().min(2000)]
    );
    assert!(section(&dom, "<p class=\"note\" id=\"evidence-note\">", "</p>").contains("Camera:"));
    let regions = section(&dom, "<table id=\"regions\"", "</table>");
    let rows: Vec<&str> = regions.split("<tr class=").skip(1).collect();
    assert!(
        !rows.is_empty(),
        "the demo walk has problem regions: {regions}"
    );
    let urls = requested_urls(&netlog(&out));
    let mut causes_shown = 0;
    for row in &rows {
        let prefix = format!("<img src=\"/v1/sessions/{id}/subtrajectories/");
        let at = row
            .find(&prefix)
            .unwrap_or_else(|| panic!("no thumbnail: {row}"));
        let k: u32 = row[at + prefix.len()..]
            .split('/')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        // The pictured sub-trajectory is one of the region's medium/high ones …
        assert!(
            matches!(
                phone.subtrajectory_class(k),
                sitar_core::ErrorClass::Medium | sitar_core::ErrorClass::High
            ),
            "sub-trajectory {k} pictured: {row}"
        );
        // … the browser fetched its image, and it is the phone's thumbnail.
        let path = format!("/v1/sessions/{id}/subtrajectories/{k}/image.jpg");
        assert!(
            urls.iter().any(|u| u.ends_with(&path)),
            "{path} not requested"
        );
        let (status, _, jpeg) = get_bytes(&format!("{base}{path}"), Some(ADMIN_TOKEN));
        assert_eq!(status, 200);
        assert_eq!(jpeg, phone.thumbnail(k).unwrap());
        // Its causes are listed, each with a reason.
        let cell = section(row, "<td class=\"cause\">", "</td>");
        for name in phone.evidence_of(k).unwrap().causes.names() {
            assert!(
                cell.contains(&format!("<b class=\"cause-name\">{name}</b>")),
                "cause {name} of sub-trajectory {k} missing: {cell}"
            );
            causes_shown += 1;
        }
    }
    assert!(
        causes_shown > 0,
        "the demo's regions face the blank wall or the glass"
    );
    let console = console_lines(&out);
    assert!(console.is_empty(), "console: {console:#?}");

    // A share link, opened in a browser with no token and no cookie: the same 3-D view,
    // its data and images through the link's own token.
    let (status, _, body) = raw(
        "POST",
        &format!("{base}/v1/sessions/{id}/share"),
        None,
        b"",
        &[("authorization", &format!("Bearer {APP_TOKEN}"))],
    );
    assert_eq!(status, 201, "{body}");
    let link = serde_json::from_str::<serde_json::Value>(&body).unwrap()["url"]
        .as_str()
        .unwrap()
        .to_owned();
    let token = link.rsplit('/').next().unwrap().to_owned();
    let out = dir.path().join("shared");
    shoot(&link, &out);
    let dom = std::fs::read_to_string(out.join("dom.html")).unwrap();
    assert!(
        dom.contains("data-view=\"ready\""),
        "{}",
        &dom[..dom.len().min(2000)]
    );
    let status_line = section(&dom, "<p id=\"view-status\"", "</p>");
    assert!(status_line.contains("sub-trajectories"), "{status_line}");
    assert!(dom.contains(&format!("<img src=\"/share/{token}/subtrajectories/")));
    assert!(
        !dom.contains(&format!("/v1/sessions/{id}/")),
        "owner URLs on a share page"
    );
    let urls = requested_urls(&netlog(&out));
    assert!(
        urls.iter()
            .any(|u| u.ends_with(&format!("/share/{token}/scene.json"))),
        "{urls:?}"
    );
    assert!(urls.iter().all(|u| !u.contains("/v1/")), "{urls:?}");
    let console = console_lines(&out);
    assert!(console.is_empty(), "console: {console:#?}");
    let (status, _, shared_scene) = get_bytes(&format!("{base}/share/{token}/scene.json"), None);
    assert_eq!(status, 200);
    let (_, _, owner_scene) = get_bytes(
        &format!("{base}/v1/sessions/{id}/scene.json"),
        Some(ADMIN_TOKEN),
    );
    assert_eq!(shared_scene, owner_scene);
    for name in [
        "results.csv",
        "results.json",
        "trajectory.tum",
        "scene.glb",
        "trials.zip",
    ] {
        assert_eq!(
            get_bytes(&format!("{base}/share/{token}/{name}"), None).0,
            200,
            "{name}"
        );
    }

    // Nothing else through it: another session's data, other names, paths out of the link,
    // a wrong token; and nothing once revoked.
    let other = upload_session(&app, 2);
    for path in [
        format!("/share/{token}/{other}/scene.json"),
        format!("/share/{token}/..%2F..%2Fv1%2Fsessions%2F{other}%2Fscene.json"),
        format!("/share/{token}/sessions"),
        format!("/share/{token}/subtrajectories/0/../../../v1/sessions/{other}/scene.json"),
        format!("/share/{token}/subtrajectories/999999/image.jpg"),
        format!("/share/{token}/subtrajectories/-1/image.jpg"),
        format!("/share/{token}x/scene.json"),
        format!("/v1/sessions/{other}/scene.json"),
        format!("/v1/sessions/{id}/scene.json"),
    ] {
        let (status, _, _) = get_bytes(&format!("{base}{path}"), None);
        assert!(matches!(status, 401 | 404), "{path}: {status}");
    }
    let (status, _, _) = raw(
        "DELETE",
        &format!("{base}/v1/sessions/{id}/share"),
        None,
        b"",
        &[("authorization", &format!("Bearer {APP_TOKEN}"))],
    );
    assert_eq!(status, 200);
    assert_eq!(
        get_bytes(&format!("{base}/share/{token}/scene.json"), None).0,
        404
    );
    server.stop();
}

/// The number in `<b …>N sub-trajectories</b>`-like text: the first integer after `key`.
fn number_after(text: &str, key: &str) -> u64 {
    let at = text
        .find(key)
        .unwrap_or_else(|| panic!("no {key:?} in {text}"))
        + key.len();
    let digits: String = text[at..]
        .chars()
        .skip_while(|c| !c.is_ascii_digit())
        .take_while(|c| c.is_ascii_digit())
        .collect();
    digits.parse().unwrap()
}

/// `GET …/report?download=1` (what `sitar demo` writes): one file that shows the full page
/// opened from disk in Chromium: the 3-D view ready with every framed point in view,
/// thumbnails inline, the regions and markers tables, no console error, and no request at
/// all (no server).
#[test]
fn the_saved_report_opens_from_disk_with_its_3d_view_and_thumbnails() {
    if chromium_missing("the saved report in Chromium") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 40.0, 2));
    let (rec_path, _, folder) = demo_walk_with_evidence(dir.path());
    let client = client(&server);
    let id = played_session(&client, &rec_path, Some(&folder));

    let url = format!("{}/v1/sessions/{id}/report?download=1", server.url());
    let response = agent()
        .get(&url)
        .header("authorization", format!("Bearer {ADMIN_TOKEN}"))
        .call()
        .unwrap();
    let headers = response.headers().clone();
    assert_eq!(
        headers["content-disposition"],
        format!("attachment; filename=\"report-{id}.html\"").as_str()
    );
    let csp = headers["content-security-policy"]
        .to_str()
        .unwrap()
        .to_owned();
    assert!(csp.contains("script-src 'sha256-"), "{csp}");
    let (_, _, html) = get_bytes(&url, Some(ADMIN_TOKEN));
    let html = String::from_utf8(html).unwrap();
    // The file keeps its policy (the header's, less what only a header can say).
    let meta = section(
        &html,
        "<meta http-equiv=\"Content-Security-Policy\" content=\"",
        "\">",
    );
    let meta = meta[meta.rfind('"').unwrap() + 1..]
        .replace("&#x27;", "'")
        .replace("&#x2f;", "/");
    assert_eq!(meta, csp.trim_end_matches("; frame-ancestors 'none'"));
    assert!(
        !html.contains("http-equiv=\"refresh\""),
        "a finished report reloads"
    );
    // No server from here on.
    server.stop();
    let file = dir.path().join(format!("report-{id}.html"));
    std::fs::write(&file, &html).unwrap();
    let out = dir.path().join("saved");
    shoot(&format!("file://{}", file.display()), &out);

    let dom = std::fs::read_to_string(out.join("dom.html")).unwrap();
    assert!(
        dom.contains("data-view=\"ready\""),
        "{}",
        &dom[..dom.len().min(2000)]
    );
    // The default view frames the walk, the markers and the surface points.
    let framed = &dom[dom.find("data-framed=\"").expect("no data-framed") + 13..];
    let framed = &framed[..framed.find('"').unwrap()];
    let (shown, all) = framed.split_once('/').unwrap();
    assert_eq!(shown, all, "framed points in view: {framed}");
    // One count of sub-trajectories: the summary's, the 3-D view's and the tables' agree.
    let summary = section(&dom, "<p id=\"summary\">", "</p>");
    let status_line = section(&dom, "<p id=\"view-status\"", "</p>");
    let subs = number_after(summary, "<b>");
    assert_eq!(
        subs,
        number_after(status_line, ">"),
        "{summary} / {status_line}"
    );
    assert!(
        summary.contains(" pairs)") && !summary.contains("(s)"),
        "{summary}"
    );
    // Thumbnails inline, with the regions' causes; the markers with their tiers.
    let regions = section(&dom, "<table id=\"regions\"", "</table>");
    assert!(
        regions.contains("<img src=\"data:image/jpeg;base64,/9j/"),
        "{regions}"
    );
    let markers = section(&dom, "<table id=\"markers\"", "</table>");
    assert!(markers.contains("<td class=\"tier\">≥ "), "{markers}");
    assert!(dom.contains("id=\"marker-rule\""));
    assert!(
        !dom.contains("href=\"/") && !dom.contains("src=\"/"),
        "server paths"
    );
    let console = console_lines(&out);
    assert!(console.is_empty(), "console: {console:#?}");
    // Nothing fetched: no request of the page's in the net log (Chromium's own background
    // requests, refused by the script, aside), and the server is gone anyway.
    let urls = requested_urls(&netlog(&out));
    assert!(
        urls.iter()
            .all(|u| !u.contains("127.0.0.1") && !u.contains("localhost") && !u.contains("/v1/")),
        "{urls:?}"
    );
    let share = assert_walk_drawn(&out.join("screenshot.png"));
    println!(
        "saved report: {} kB, {:.1} % of the canvas drawn, framed {framed}",
        html.len() / 1000,
        share * 100.0
    );
}

/// While trials arrive: before the first estimate the report is an HTML page saying what it
/// waits for and reloading itself; a partial estimate carries a banner and reloads; the
/// final one has neither. The screenshot script ends on the reloading pages (the overview
/// among them), with no console error.
#[test]
fn pages_while_trials_arrive_say_so_and_reload_until_done() {
    if chromium_missing("pages while trials arrive") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // One simulated phone at 3×: a 15 s trial takes 5 s, so a partial page stays partial
    // for the screenshot's three Chromium runs.
    let server = start(sim_config(&dir.path().join("data"), 3.0, 1));
    let base = server.url();
    let client = client(&server);
    let id = client
        .create_session(&NewSession {
            trials: 6,
            setting: "trim_mean_30".into(),
            playback: "sim".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    let page = |id: &str| {
        let (status, ct, body) = get_bytes(
            &format!("{base}/v1/sessions/{id}/report"),
            Some(ADMIN_TOKEN),
        );
        assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
        assert!(ct.starts_with("text/html"), "{ct}");
        String::from_utf8(body).unwrap()
    };
    // Waiting: HTML, not a JSON 409, saying what it waits for.
    let waiting = page(&id);
    assert!(waiting.contains("<b>0 of 6 trials played</b>"), "{waiting}");
    assert!(waiting.contains("<meta http-equiv=\"refresh\" content=\"5\">"));
    let out = dir.path().join("waiting");
    shoot(
        &format!("{base}/v1/sessions/{id}/report?token={ADMIN_TOKEN}"),
        &out,
    );
    assert!(
        std::fs::read_to_string(out.join("dom.html"))
            .unwrap()
            .contains("id=\"waiting\"")
    );
    assert!(console_lines(&out).is_empty(), "{:#?}", console_lines(&out));

    let recording = sim_recording(dir.path(), "walk.rec", 15.0, 42);
    client
        .upload_recording(&id, &recording, &mut |_, _| {})
        .unwrap();
    // A partial estimate: the banner with k of 6, and the reload.
    let started = std::time::Instant::now();
    let partial = loop {
        let status = client.status(&id).unwrap();
        assert_ne!(
            status.state,
            SessionState::Done,
            "done before a partial page was seen"
        );
        if status.results_trials >= 2 {
            break page(&id);
        }
        assert!(started.elapsed().as_secs() < 120);
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let banner = section(&partial, "<p id=\"partial\"", "</p>");
    let k = number_after(banner, "from <b>");
    assert!((2..6).contains(&k), "{banner}");
    assert!(banner.contains(&format!("{k} of 6 trials")), "{banner}");
    assert!(partial.contains("<meta http-equiv=\"refresh\""));
    assert_eq!(number_after(&partial, "id=\"trials\">"), k);
    let out = dir.path().join("partial");
    shoot(
        &format!("{base}/v1/sessions/{id}/report?token={ADMIN_TOKEN}"),
        &out,
    );
    let dom = std::fs::read_to_string(out.join("dom.html")).unwrap();
    assert!(dom.contains("id=\"partial\""));
    assert!(console_lines(&out).is_empty(), "{:#?}", console_lines(&out));

    // Done: neither banner nor reload.
    assert_eq!(wait_done(&client, &id).state, SessionState::Done);
    let done = page(&id);
    assert!(!done.contains("id=\"partial\"") && !done.contains("http-equiv=\"refresh\""));
    assert!(
        done.contains("6 trials</b> (15 pairs)"),
        "{}",
        section(&done, "<p id=\"summary\">", "</p>")
    );

    // The overview of one session reads right and the script ends on it too.
    let out = dir.path().join("overview");
    shoot(&format!("{base}/?token={ADMIN_TOKEN}"), &out);
    let dom = std::fs::read_to_string(out.join("dom.html")).unwrap();
    assert!(dom.contains("The one session;"), "{dom}");
    assert!(console_lines(&out).is_empty(), "{:#?}", console_lines(&out));
    server.stop();
}

/// The served bundle is `scripts/bundle-report`'s output for the committed `report.js` and
/// three.js as `tools/npm` pins it (esbuild from there too): a rebuild from
/// `tools/npm/node_modules` gives the committed bytes.
#[test]
fn the_served_bundle_is_built_from_report_js() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let modules = root.join("tools/npm/node_modules");
    for needed in [".bin/esbuild", "three/package.json"] {
        if !modules.join(needed).exists() {
            println!(
                "SKIPPED the bundle check: tools/npm/node_modules/{needed} is missing \
                 (run `npm ci --prefix tools/npm`, as .ci/run does)"
            );
            return;
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report.bundle.js");
    let status = Command::new(root.join("scripts/bundle-report"))
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let committed = std::fs::read(root.join("rust/server/assets/report.bundle.js")).unwrap();
    assert!(
        std::fs::read(&out).unwrap() == committed,
        "rust/server/assets/report.bundle.js is stale: run scripts/bundle-report"
    );
    // The pinned three.js is the one bundled (three announces its revision).
    let pinned: serde_json::Value =
        serde_json::from_slice(&std::fs::read(modules.join("three/package.json")).unwrap())
            .unwrap();
    let version = pinned["version"].as_str().unwrap();
    let committed = String::from_utf8(committed).unwrap();
    let revision = version.split('.').nth(1).unwrap();
    assert!(
        committed.contains(&format!("revision:\"{revision}\"")),
        "the bundle is not three {version}"
    );
}
