//! `GET /v1/venues/{id}/map.json` over loopback against a real server and its SQLite file:
//! two users' sessions in world frames 1 m apart, each aligned by its anchor observations,
//! give the cells computed here by hand from the sessions' own `results.json` (cell centres
//! `⌊p/c + ½⌋·c`, errors a 30 % trimmed mean as `scipy.stats.trim_mean`); the map follows
//! its sessions (joined, given its log, finished, deleted) on the next request, and strangers
//! get a 404. Also: `map.glb` (one node per cell, the Khronos validator), the venue report
//! (its 3-D view data, problem regions with causes and the reader's own thumbnails, the saved
//! page drawn in Chromium) and a session's scene from the phone's own log.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use sitar_server::{Role, ServerHandle};

mod support;
use support::http::{Answer, call};

const CELL_M: f64 = 0.25;
const FRAME_NS: i64 = 33_333_333;
const T0: i64 = 1_700_000_000_000_000_000;

fn t(frame: i64) -> i64 {
    T0 + frame * FRAME_NS
}

/// The walk's camera position at `frame` in the venue frame.
fn position(frame: i64) -> [f64; 3] {
    [0.01 * frame as f64, 1.5, 0.002 * frame as f64]
}

/// The surface point sub-trajectory `k` saw (venue frame), for even `k`.
fn surface(k: i64) -> [f64; 3] {
    [0.3, 1.5, 2.0 + 0.01 * k as f64]
}

/// One user's files, in a world frame shifted by `dx` along x from the venue frame.
struct Phone {
    dx: f64,
}

impl Phone {
    fn trial(&self, noise: f64) -> String {
        (0..=40)
            .map(|i| {
                let p = position(i);
                let wiggle = noise * ((i * i % 7) as f64 - 3.0);
                format!(
                    "{} {} {} {} 0 0 0 1\n",
                    t(i),
                    p[0] + self.dx + wiggle,
                    p[1],
                    p[2]
                )
            })
            .collect()
    }

    fn trajectory_txt(&self) -> String {
        (0..=40)
            .step_by(5)
            .map(|i| {
                let p = position(i);
                format!("{} {} {} {} 0 0 0 1\n", t(i), p[0] + self.dx, p[1], p[2])
            })
            .collect()
    }

    fn anchors_csv(&self) -> String {
        let mut csv = String::from("t_ns,anchor,px,py,pz,qx,qy,qz,qw,tracking\n");
        for k in 0..3 {
            csv.push_str(&format!("{},poster-1,{},0,0,0,0,0,1,full\n", t(k), self.dx));
        }
        csv
    }

    fn subtrajectories_csv(&self) -> String {
        let mut csv = String::from(
            "index,start_ns,mid_ns,end_ns,depth,pixel_x,pixel_y,depth_m,distance_m,cam_x,cam_y,cam_z,cam_nx,cam_ny,cam_nz,x,y,z,nx,ny,nz,error_m,class\n",
        );
        for k in 0..4 {
            let depth = if k % 2 == 0 {
                let s = surface(k);
                format!(
                    "valid,128,96,2,2,0,0,2,0,0,-1,{},{},{},0,0,-1",
                    s[0] + self.dx,
                    s[1],
                    s[2]
                )
            } else {
                format!("missing{}", ",".repeat(16))
            };
            csv.push_str(&format!(
                "{k},{},{},{},{depth},,\n",
                t(10 * k),
                t(10 * k + 5),
                t(10 * k + 10)
            ));
        }
        csv
    }
}

fn put(server: &ServerHandle, token: &str, path: &str, body: &str) -> Answer {
    let a = call(
        server,
        token,
        "PUT",
        path,
        Some("text/plain"),
        body.as_bytes(),
    );
    assert_eq!(a.status, 200, "{path}: {}", a.body);
    a
}

fn get(server: &ServerHandle, token: &str, path: &str) -> Answer {
    call(server, token, "GET", path, None, &[])
}

/// A finished session of `token` in `venue` with `phone`'s files; its results.json.
fn finished_session(
    server: &ServerHandle,
    token: &str,
    venue: &str,
    phone: &Phone,
) -> (String, Value) {
    finished_session_with(server, token, venue, phone, 0.003)
}

/// As [`finished_session`], the second trial wiggling by `noise` (m) per frame.
fn finished_session_with(
    server: &ServerHandle,
    token: &str,
    venue: &str,
    phone: &Phone,
    noise: f64,
) -> (String, Value) {
    let body = json!({"playback": "upload", "trials": 2, "venue": venue}).to_string();
    let a = call(
        server,
        token,
        "POST",
        "/v1/sessions",
        Some("application/json"),
        body.as_bytes(),
    );
    assert_eq!(a.status, 201, "{}", a.body);
    let id = a.json()["id"].as_str().unwrap().to_owned();
    send_phone_log(server, token, &id, phone);
    let results = finish(server, token, &id, phone, noise);
    (id, results)
}

/// Uploads `phone`'s own log (anchors, trajectory, whole sub-trajectory table) to session `id`.
fn send_phone_log(server: &ServerHandle, token: &str, id: &str, phone: &Phone) {
    let base = format!("/v1/sessions/{id}");
    put(
        server,
        token,
        &format!("{base}/anchors.csv"),
        &phone.anchors_csv(),
    );
    put(
        server,
        token,
        &format!("{base}/trajectory.txt"),
        &phone.trajectory_txt(),
    );
    put(
        server,
        token,
        &format!("{base}/subtrajectories.csv"),
        &phone.subtrajectories_csv(),
    );
}

/// Sends session `id` two trials (the second wiggling by `noise`), estimates and waits until
/// it is done; its results.json.
fn finish(server: &ServerHandle, token: &str, id: &str, phone: &Phone, noise: f64) -> Value {
    let base = format!("/v1/sessions/{id}");
    for noise in [0.0, noise] {
        let trial = phone.trial(noise);
        let a = call(
            server,
            token,
            "POST",
            &format!("{base}/trials"),
            Some("text/plain"),
            trial.as_bytes(),
        );
        assert_eq!(a.status, 201, "{}", a.body);
    }
    assert_eq!(
        call(
            server,
            token,
            "POST",
            &format!("{base}/estimate"),
            None,
            &[]
        )
        .status,
        202
    );
    let deadline = Instant::now() + Duration::from_secs(60);
    while get(server, token, &base).json()["state"] != "done" {
        assert!(
            Instant::now() < deadline,
            "{}",
            get(server, token, &base).body
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    get(server, token, &format!("{base}/results.json")).json()
}

/// The error of the window starting at `start` (the sub-trajectory's start; exact here).
fn error_at(results: &Value, start: i64) -> f64 {
    results["windows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["start"].as_f64() == Some(start as f64))
        .unwrap_or_else(|| panic!("no window at {start}: {}", results["windows"][0]))["error_m"]
        .as_f64()
        .unwrap()
}

/// `scipy.stats.trim_mean(values, 0.3)`: cut ⌊0.3·n⌋ from each end of the sorted values.
fn trim_mean_30(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let cut = (0.3 * v.len() as f64).floor() as usize;
    let kept = &v[cut..v.len() - cut];
    kept.iter().sum::<f64>() / kept.len() as f64
}

fn centre(p: [f64; 3]) -> [f64; 3] {
    // Cells centred on multiples of `cell_m` (sitar_core::venue::cell_index).
    p.map(|v| (v / CELL_M + 0.5).floor() * CELL_M)
}

/// Expected cells: (kind, centre as µm integers) → errors of the sub-trajectories in it.
fn expected(results: &[&Value]) -> BTreeMap<(String, [i64; 3]), Vec<f64>> {
    let key =
        |kind: &str, p: [f64; 3]| (kind.to_owned(), centre(p).map(|v| (v * 1e6).round() as i64));
    let mut cells: BTreeMap<_, Vec<f64>> = BTreeMap::new();
    for r in results {
        for k in 0..4 {
            let e = error_at(r, t(10 * k));
            cells
                .entry(key("path", position(10 * k + 5)))
                .or_default()
                .push(e);
            if k % 2 == 0 {
                cells.entry(key("surface", surface(k))).or_default().push(e);
            }
        }
    }
    cells
}

fn assert_cells(map: &Value, expected: &BTreeMap<(String, [i64; 3]), Vec<f64>>, sessions: u64) {
    let cells = map["cells"].as_array().unwrap();
    assert_eq!(cells.len(), expected.len(), "{map}");
    for cell in cells {
        let c: Vec<f64> = cell["center"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let key = (
            cell["kind"].as_str().unwrap().to_owned(),
            [c[0], c[1], c[2]].map(|v| (v * 1e6).round() as i64),
        );
        let errors = expected
            .get(&key)
            .unwrap_or_else(|| panic!("unexpected cell {cell}"));
        assert_eq!(
            cell["subtrajectories"].as_u64().unwrap() as usize,
            errors.len(),
            "{cell}"
        );
        assert_eq!(cell["sessions"], sessions, "{cell}");
        let want = trim_mean_30(errors);
        let got = cell["error_m"].as_f64().unwrap();
        assert!(
            (got - want).abs() <= 1e-12 * want.abs().max(1e-3),
            "{cell}: {want}"
        );
        let directions: u64 = cell["directions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap())
            .sum();
        assert_eq!(
            directions as usize,
            errors.len(),
            "every camera has a heading: {cell}"
        );
    }
}

#[test]
fn the_venue_map_is_built_from_its_sessions_files_and_follows_them() {
    let dir = tempfile::tempdir().unwrap();
    let (server, admin) = support::spawn_with_admin(dir.path());
    let owner = sitar_server::create_token(dir.path(), Role::App, "owner").unwrap();
    let member = sitar_server::create_token(dir.path(), Role::App, "member").unwrap();
    let stranger = sitar_server::create_token(dir.path(), Role::App, "stranger").unwrap();
    let body = json!({"name": "Hall", "anchor": "poster-1", "cell_m": CELL_M}).to_string();
    let a = call(
        &server,
        &owner,
        "POST",
        "/v1/venues",
        Some("application/json"),
        body.as_bytes(),
    );
    let venue = a.json()["id"].as_str().unwrap().to_owned();
    assert_eq!(
        call(
            &server,
            &owner,
            "PUT",
            &format!("/v1/venues/{venue}/members/member"),
            None,
            &[]
        )
        .status,
        200
    );
    let map_path = format!("/v1/venues/{venue}/map.json");

    let empty = get(&server, &owner, &map_path).json();
    assert_eq!(
        (&empty["id"], &empty["unit"], &empty["cells"]),
        (&json!(venue), &json!("m"), &json!([]))
    );

    let (first, first_results) = finished_session(&server, &owner, &venue, &Phone { dx: 0.0 });
    let map = get(&server, &owner, &map_path).json();
    assert_eq!(
        (&map["anchor"], &map["cell_m"], &map["convention"]),
        (&json!("poster-1"), &json!(CELL_M), &json!("unity"))
    );
    assert_cells(&map, &expected(&[&first_results]), 1);
    assert_eq!(map["sessions"][0]["id"], json!(first));
    assert_eq!(map["sessions"][0]["aligned"], true);
    assert_eq!(map["sessions"][0]["subtrajectories"], 4);

    // A second user, whose world frame is 1 m off: the same cells, seen by two sessions.
    let (second, second_results) = finished_session(&server, &member, &venue, &Phone { dx: 1.0 });
    let map = get(&server, &member, &map_path).json();
    assert_cells(&map, &expected(&[&first_results, &second_results]), 2);
    let worst = map["cells"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["error_m"].as_f64().unwrap())
        .fold(0.0, f64::max);
    assert!(
        worst > 1e-4,
        "the trials differ, so some cell has an error: {map}"
    );
    let both = get(&server, &admin, &format!("{map_path}?min_sessions=2")).json();
    assert_eq!(
        both["cells"].as_array().unwrap().len(),
        map["cells"].as_array().unwrap().len()
    );

    // The report: both sessions with their spread, coverage in words; strangers get 404.
    let page = get(&server, &member, &format!("/v1/venues/{venue}/report"));
    assert_eq!(page.status, 200, "{}", page.body);
    for needed in [
        "<svg id=\"topview\"",
        &first,
        &second,
        "seen only from the",
        "0.0 cm",
        "Hall",
    ] {
        assert!(page.body.contains(needed), "{needed}: {}", page.body);
    }
    assert!(
        page.body.contains("(yours)"),
        "the member's own session is marked"
    );
    let file = get(
        &server,
        &owner,
        &format!("/v1/venues/{venue}/report?download=1"),
    );
    assert_eq!(file.status, 200);
    let head = file.head.to_ascii_lowercase();
    assert!(
        head.contains("content-disposition: attachment; filename=\"venue-"),
        "{head}"
    );
    assert!(
        head.contains("style-src 'sha256-") && !file.body.contains("/assets/"),
        "{head}"
    );
    assert!(
        file.body.contains("<script type=\"module\">") && head.contains("script-src 'sha256-"),
        "the saved page carries the 3-D view's script inline"
    );
    assert_eq!(
        get(&server, &stranger, &format!("/v1/venues/{venue}/report")).status,
        404
    );

    // The 3-D view's data: every cell of the map by kind, in glTF's frame (unity: z
    // mirrored), and both sessions' paths; the page loads the bundled script.
    assert!(
        page.body
            .contains("<script type=\"module\" src=\"/assets/report.bundle.js\">"),
        "{}",
        page.body
    );
    let view = view_data(&page.body);
    let cells = map["cells"].as_array().unwrap();
    for (kind, key) in [("surface", "surface"), ("path", "path")] {
        let of_kind: Vec<&Value> = cells.iter().filter(|c| c["kind"] == kind).collect();
        let centres = view[key]["centres"].as_array().unwrap();
        assert_eq!(centres.len(), 3 * of_kind.len(), "{kind}: {view}");
        for c in &of_kind {
            let p = [
                c["center"][0].as_f64().unwrap(),
                c["center"][1].as_f64().unwrap(),
                -c["center"][2].as_f64().unwrap(),
            ];
            assert!(
                centres
                    .chunks(3)
                    .any(|q| (0..3).all(|i| (q[i].as_f64().unwrap() - p[i]).abs() < 1e-3)),
                "{kind} cell {p:?} not drawn: {view}"
            );
        }
    }
    assert_eq!(view["paths"].as_array().unwrap().len(), 2, "{view}");

    // A session not yet finished and one without anchors bring no cells, and say so.
    let body = json!({"playback": "upload", "venue": venue}).to_string();
    let a = call(
        &server,
        &owner,
        "POST",
        "/v1/sessions",
        Some("application/json"),
        body.as_bytes(),
    );
    let idle = a.json()["id"].as_str().unwrap().to_owned();
    let map = get(&server, &owner, &map_path).json();
    let listed = map["sessions"].as_array().unwrap();
    assert_eq!(listed.len(), 3);
    let idle_entry = listed.iter().find(|s| s["id"] == json!(idle)).unwrap();
    assert_eq!(idle_entry["aligned"], false, "{idle_entry}");
    assert!(
        idle_entry["reason"].as_str().unwrap().contains("anchors"),
        "{idle_entry}"
    );
    assert_cells(&map, &expected(&[&first_results, &second_results]), 2);

    // Its phone's log arrives: still no cells until it is finished; then its cells count at
    // once (a third user whose world frame is 2 m off: the same cells, seen by three).
    let third = Phone { dx: 2.0 };
    send_phone_log(&server, &owner, &idle, &third);
    let map = get(&server, &owner, &map_path).json();
    assert_cells(&map, &expected(&[&first_results, &second_results]), 2);
    let third_results = finish(&server, &owner, &idle, &third, 0.005);
    let map = get(&server, &owner, &map_path).json();
    assert_cells(
        &map,
        &expected(&[&first_results, &second_results, &third_results]),
        3,
    );
    assert_eq!(
        call(
            &server,
            &owner,
            "DELETE",
            &format!("/v1/sessions/{idle}"),
            None,
            &[]
        )
        .status,
        200
    );
    let map = get(&server, &owner, &map_path).json();
    assert_cells(&map, &expected(&[&first_results, &second_results]), 2);

    // The next request after a deletion follows it.
    assert_eq!(
        call(
            &server,
            &member,
            "DELETE",
            &format!("/v1/sessions/{second}"),
            None,
            &[]
        )
        .status,
        200
    );
    let map = get(&server, &owner, &map_path).json();
    assert_cells(&map, &expected(&[&first_results]), 1);
    assert_eq!(
        get(&server, &owner, &format!("{map_path}?min_sessions=2")).json()["cells"],
        json!([])
    );

    // Bad parameters are named; strangers are told the venue does not exist.
    for bad in ["min_sessions=0", "min_sessions=x", "limit=2"] {
        let a = get(&server, &owner, &format!("{map_path}?{bad}"));
        assert_eq!(a.status, 400, "{bad}: {}", a.body);
        assert!(
            a.message().contains(bad.split('=').next().unwrap()),
            "{}",
            a.body
        );
    }
    assert_eq!(get(&server, &stranger, &map_path).status, 404);
    server.stop();
}

/// The 3-D view's data the venue page carries (`<script type="application/json" id="venue-data">`).
fn view_data(page: &str) -> Value {
    let start = page
        .find("id=\"venue-data\">")
        .unwrap_or_else(|| panic!("no venue-data: {page}"))
        + "id=\"venue-data\">".len();
    let end = start + page[start..].find("</script>").unwrap();
    serde_json::from_str(&page[start..end]).unwrap()
}

/// The JSON chunk of a GLB (glTF 2.0 binary: 12-byte header, then the JSON chunk).
fn glb_json(glb: &[u8]) -> Value {
    assert_eq!(&glb[0..4], b"glTF", "not a GLB");
    assert_eq!(
        u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize,
        glb.len(),
        "the header's length is the file's"
    );
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    assert_eq!(&glb[16..20], b"JSON");
    serde_json::from_slice(&glb[20..20 + len]).unwrap()
}

/// A venue of `owner` with two finished sessions (owner's and member's), 1 m apart in
/// their world frames.
fn venue_with_two_sessions(
    server: &ServerHandle,
    owner: &str,
    member: &str,
) -> (String, String, String) {
    let body = json!({"name": "Hall", "anchor": "poster-1", "cell_m": CELL_M}).to_string();
    let a = call(
        server,
        owner,
        "POST",
        "/v1/venues",
        Some("application/json"),
        body.as_bytes(),
    );
    let venue = a.json()["id"].as_str().unwrap().to_owned();
    let path = format!("/v1/venues/{venue}/members/member");
    assert_eq!(call(server, owner, "PUT", &path, None, &[]).status, 200);
    let (first, _) = finished_session(server, owner, &venue, &Phone { dx: 0.0 });
    let (second, _) = finished_session(server, member, &venue, &Phone { dx: 1.0 });
    (venue, first, second)
}

#[test]
fn the_venue_map_glb_has_one_node_per_cell_and_passes_the_khronos_validator() {
    let dir = tempfile::tempdir().unwrap();
    let (server, _admin) = support::spawn_with_admin(dir.path());
    let owner = sitar_server::create_token(dir.path(), Role::App, "owner").unwrap();
    let member = sitar_server::create_token(dir.path(), Role::App, "member").unwrap();
    let stranger = sitar_server::create_token(dir.path(), Role::App, "stranger").unwrap();
    let (venue, _, _) = venue_with_two_sessions(&server, &owner, &member);
    let mut files = Vec::new();
    for query in ["", "?min_sessions=2"] {
        let map = get(
            &server,
            &member,
            &format!("/v1/venues/{venue}/map.json{query}"),
        )
        .json();
        let a = get(
            &server,
            &member,
            &format!("/v1/venues/{venue}/map.glb{query}"),
        );
        assert_eq!(a.status, 200, "{}", a.body);
        let head = a.head.to_ascii_lowercase();
        assert!(head.contains("content-type: model/gltf-binary"), "{head}");
        assert!(
            head.contains(&format!("filename=\"venue-{venue}.glb\"")),
            "{head}"
        );
        let doc = glb_json(&a.bytes);
        let names: Vec<&str> = doc["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|n| n["name"].as_str())
            .collect();
        let cells = map["cells"].as_array().unwrap();
        assert!(!cells.is_empty(), "{map}");
        for (kind, prefix) in [("surface", "surface_cell_"), ("path", "path_cell_")] {
            let want = cells.iter().filter(|c| c["kind"] == kind).count();
            let got = names.iter().filter(|n| n.starts_with(prefix)).count();
            assert_eq!(got, want, "{kind} nodes: {names:?}");
        }
        let path = dir.path().join(format!("venue{}.glb", files.len()));
        std::fs::write(&path, &a.bytes).unwrap();
        files.push(path);
    }
    for (who, status) in [(&stranger, 404), (&owner, 200)] {
        assert_eq!(
            get(&server, who, &format!("/v1/venues/{venue}/map.glb")).status,
            status
        );
    }
    let bad = get(
        &server,
        &owner,
        &format!("/v1/venues/{venue}/map.glb?min_sessions=0"),
    );
    assert_eq!(bad.status, 400);
    assert!(bad.message().contains("min_sessions"), "{}", bad.body);
    server.stop();

    let tools = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tools/npm");
    if !tools.join("node_modules/gltf-validator").exists() {
        println!(
            "SKIPPED the_venue_map_glb_has_one_node_per_cell_and_passes_the_khronos_validator \
             (validator part): run `npm ci --prefix tools/npm`"
        );
        return;
    }
    let out = std::process::Command::new("node")
        .arg(tools.join("validate-gltf.mjs"))
        .args(&files)
        .output()
        .expect("node runs");
    let text = String::from_utf8_lossy(&out.stdout);
    let reports: Value = serde_json::from_str(&text).unwrap_or_else(|e| {
        panic!(
            "validator output ({e}): {text} {}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    for report in reports.as_array().unwrap() {
        let issues = &report["issues"];
        assert_eq!(issues["numErrors"], 0, "{issues}");
        assert_eq!(issues["numWarnings"], 0, "{issues}");
    }
    assert!(out.status.success());
}

#[test]
fn a_sessions_scene_is_the_phones_own_log_when_it_sent_one() {
    let dir = tempfile::tempdir().unwrap();
    let (server, _admin) = support::spawn_with_admin(dir.path());
    let owner = sitar_server::create_token(dir.path(), Role::App, "owner").unwrap();
    let member = sitar_server::create_token(dir.path(), Role::App, "member").unwrap();
    let (_, first, _) = venue_with_two_sessions(&server, &owner, &member);
    let base = format!("/v1/sessions/{first}");
    let tum = get(&server, &owner, &format!("{base}/trajectory.tum"));
    assert_eq!(tum.body, Phone { dx: 0.0 }.trajectory_txt());

    // The phone logged frames 0, 5, …, 40; the trials logged every frame: the scene's path
    // is the phone's, in glTF's frame (a unity session: z mirrored).
    let scene = get(&server, &owner, &format!("{base}/scene.json")).json();
    assert!(
        scene["source"]
            .as_str()
            .is_some_and(|s| s.contains("phone's own log")),
        "{scene}"
    );
    let joints: Vec<f64> = scene["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let logged: Vec<[f64; 3]> = (0..=40).step_by(5).map(position).collect();
    for p in &logged {
        let want = [p[0], p[1], -p[2]];
        assert!(
            joints
                .chunks(3)
                .any(|q| (0..3).all(|i| (q[i] - want[i]).abs() < 1e-3)),
            "logged pose {want:?} not in the scene's path {joints:?}"
        );
    }
    assert!(
        joints.chunks(3).all(|q| logged
            .iter()
            .any(|p| (q[0] - p[0]).abs() < 1e-3 && (q[2] + p[2]).abs() < 1e-3)),
        "only the phone's logged poses: {joints:?}"
    );
    // The depth the phone measured (2 m at sub-trajectories 0 and 2): a surface point 2 m
    // straight ahead of the midpoint (unity cameras look along +z).
    let surface: Vec<f64> = scene["surface"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(surface.len(), 6, "{surface:?}");
    for (point, k) in surface.chunks(3).zip([0, 2]) {
        let mid = position(10 * k + 5);
        let want = [mid[0], mid[1], -(mid[2] + 2.0)];
        assert!(
            (0..3).all(|i| (point[i] - want[i]).abs() < 1e-3),
            "sub-trajectory {k}: {point:?} against {want:?}"
        );
    }
    // Sub-trajectories keep the phone's start timestamps, so the results are found.
    let classes = scene["subs"]["class"].as_array().unwrap();
    assert_eq!(classes.len(), 4, "{}", scene["subs"]);
    assert!(classes.iter().all(|c| c != "unknown"), "{}", scene["subs"]);

    // A new log replaces the scene at once.
    let moved: String = Phone { dx: 0.5 }.trajectory_txt();
    put(&server, &owner, &format!("{base}/trajectory.txt"), &moved);
    let scene = get(&server, &owner, &format!("{base}/scene.json")).json();
    let x0 = scene["joints"][0].as_f64().unwrap();
    assert!((x0 - 0.5).abs() < 1e-3, "{x0}: {}", scene["joints"]);
    let glb = get(&server, &owner, &format!("{base}/scene.glb"));
    assert_eq!(glb.status, 200, "{}", glb.body);
    server.stop();
}

/// `data-NAME="…"` of the page's `<body>` after its scripts ran (Chromium's `--dump-dom`).
fn body_data(dom: &str, name: &str) -> Option<String> {
    let key = format!("data-{name}=\"");
    let start = dom.find(&key)? + key.len();
    Some(dom[start..start + dom[start..].find('"')?].to_owned())
}

/// The saved venue page and a saved session report (its scene from the phone's log),
/// opened from disk in headless Chromium (SwiftShader WebGL): both 3-D views are drawn with
/// every point they frame in view.
#[test]
fn the_saved_venue_report_draws_its_3d_view_in_chromium() {
    if !std::path::Path::new("/usr/bin/chromium").exists() {
        println!(
            "SKIPPED the_saved_venue_report_draws_its_3d_view_in_chromium: /usr/bin/chromium \
             is not installed (.ci/run installs it)"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (server, _admin) = support::spawn_with_admin(&dir.path().join("data"));
    let owner = sitar_server::create_token(&dir.path().join("data"), Role::App, "owner").unwrap();
    let member = sitar_server::create_token(&dir.path().join("data"), Role::App, "member").unwrap();
    let (venue, first, _) = venue_with_two_sessions(&server, &owner, &member);
    let pages = [
        ("venue", format!("/v1/venues/{venue}/report?download=1")),
        ("session", format!("/v1/sessions/{first}/report?download=1")),
    ];
    let mut saved = Vec::new();
    for (name, path) in &pages {
        let a = get(&server, &owner, path);
        assert_eq!(a.status, 200, "{path}: {}", a.body);
        let file = dir.path().join(format!("{name}.html"));
        std::fs::write(&file, &a.body).unwrap();
        saved.push((name, file));
    }
    // No server from here on: the files carry everything.
    server.stop();
    let script = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scripts/report-screenshot");
    for (name, file) in saved {
        let out = dir.path().join(format!("{name}-shot"));
        let status = std::process::Command::new(&script)
            .arg(format!("file://{}", file.display()))
            .arg(&out)
            .arg("1280x1000")
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
            .unwrap();
        assert!(status.success(), "{name}: report-screenshot failed");
        let dom = std::fs::read_to_string(out.join("dom.html")).unwrap();
        let head = &dom[..dom.len().min(3000)];
        assert_eq!(
            body_data(&dom, "view").as_deref(),
            Some("ready"),
            "{name}: {head}"
        );
        let framed = body_data(&dom, "framed").unwrap_or_default();
        let (shown, all) = framed.split_once('/').unwrap_or(("", "?"));
        assert_eq!(shown, all, "{name}: points framed in view: {framed}");
        assert!(all.parse::<u32>().unwrap() > 2, "{name}: {framed}");
        println!("{name}: 3-D view ready, {framed} framed points in view");
    }
}

/// The phone's evidence for the 4 sub-trajectories: each with an image, `low_texture` named
/// for the ones that faced the wall (0 and 2).
fn evidence_csv() -> String {
    let mut csv = String::from(
        "index,image,mean_brightness,contrast_std,laplacian_var,corners_per_10k,saturated_share,thumbnail_width,thumbnail_height,depth_valid_share,linear_speed_m_s,angular_speed_deg_s,depth_valid,distance_m,causes\n",
    );
    for k in 0..4 {
        let (valid, cause) = if k % 2 == 0 {
            (1, "low_texture")
        } else {
            (0, "")
        };
        csv.push_str(&format!(
            "{k},1,40,5,10,1,0,120,160,1,0.3,10,{valid},2,{cause}\n"
        ));
    }
    csv
}

#[test]
fn problem_regions_name_the_evidences_causes_and_show_only_the_readers_thumbnails() {
    let dir = tempfile::tempdir().unwrap();
    let (server, admin) = support::spawn_with_admin(dir.path());
    let owner = sitar_server::create_token(dir.path(), Role::App, "owner").unwrap();
    let member = sitar_server::create_token(dir.path(), Role::App, "member").unwrap();
    let body = json!({"name": "Hall", "anchor": "poster-1", "cell_m": CELL_M}).to_string();
    let a = call(
        &server,
        &owner,
        "POST",
        "/v1/venues",
        Some("application/json"),
        body.as_bytes(),
    );
    let venue = a.json()["id"].as_str().unwrap().to_owned();
    let path = format!("/v1/venues/{venue}/members/member");
    assert_eq!(call(&server, &owner, "PUT", &path, None, &[]).status, 200);
    // Trials 8 cm apart, wiggling frame to frame: every window's error is high.
    let mut ids = Vec::new();
    for (token, dx) in [(&owner, 0.0), (&member, 1.0)] {
        let (id, _) = finished_session_with(&server, token, &venue, &Phone { dx }, 0.08);
        let base = format!("/v1/sessions/{id}");
        put(
            &server,
            token,
            &format!("{base}/evidence.csv"),
            &evidence_csv(),
        );
        let jpeg = [0xFF, 0xD8, 0xFF, 0xE0, 0, 0, 0xFF, 0xD9];
        let a = call(
            &server,
            token,
            "PUT",
            &format!("{base}/subtrajectories/0/image.jpg"),
            Some("image/jpeg"),
            &jpeg,
        );
        assert_eq!(a.status, 204, "{}", a.body);
        ids.push(id);
    }
    let map = get(&server, &owner, &format!("/v1/venues/{venue}/map.json")).json();
    let wall: Vec<&Value> = map["cells"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["kind"] == "surface" && c["class"] == "high" && c["sessions"] == 2)
        .collect();
    assert_eq!(wall.len(), 1, "the wall's cell, seen by both: {map}");

    let image = |id: &str| format!("/v1/sessions/{id}/subtrajectories/0/image.jpg");
    for (reader, mine, theirs) in [
        (&owner, Some(&ids[0]), Some(&ids[1])),
        (&member, Some(&ids[1]), Some(&ids[0])),
        (&admin, None, None),
    ] {
        let page = get(&server, reader, &format!("/v1/venues/{venue}/report"));
        assert_eq!(page.status, 200, "{}", page.body);
        let regions = &page.body[page
            .body
            .find("<table id=\"regions\">")
            .expect("no regions")..];
        let regions = &regions[..regions.find("</table>").unwrap()];
        assert_eq!(regions.matches("<tr>").count(), 2, "one region: {regions}");
        // Both sessions' sub-trajectories 0 and 2 faced the wall; each named low texture.
        assert!(regions.contains("low texture (4 of 4)"), "{regions}");
        assert!(regions.contains("seen only from the"), "{regions}");
        let shown = |id: &str| regions.contains(&image(id).replace('/', "&#x2f;"));
        match (mine, theirs) {
            (Some(mine), Some(theirs)) => {
                assert!(shown(mine), "the reader's own thumbnail: {regions}");
                assert!(!shown(theirs), "another token's thumbnail: {regions}");
            }
            _ => assert!(ids.iter().all(|id| shown(id)), "admins see all: {regions}"),
        }
    }
    server.stop();
}

/// The map from kept contributions at 50 sessions: asked twice, the same answer, every
/// contribution kept in the database; a 51st session joining changes the next answer (each
/// cell seen by one more session, as computed by hand), its log sent again changes it, and
/// leaving (deleted) gives the 50-session answer back.
#[test]
fn a_session_joining_a_fifty_session_venue_changes_the_next_map_and_leaving_removes_it() {
    let dir = tempfile::tempdir().unwrap();
    let (server, admin) = support::spawn_with_admin(dir.path());
    let body = json!({"name": "Hall", "anchor": "poster-1", "cell_m": CELL_M}).to_string();
    let a = call(
        &server,
        &admin,
        "POST",
        "/v1/venues",
        Some("application/json"),
        body.as_bytes(),
    );
    let venue = a.json()["id"].as_str().unwrap().to_owned();
    let map_path = format!("/v1/venues/{venue}/map.json");
    // 50 users, each in its own world frame, 4 at a time.
    let results: Vec<Value> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..4)
            .map(|k| {
                let (server, admin, venue) = (&server, &admin, &venue);
                scope.spawn(move || {
                    (k..50)
                        .step_by(4)
                        .map(|i| {
                            let phone = Phone {
                                dx: 0.1 * i as f64 - 2.0,
                            };
                            finished_session(server, admin, venue, &phone).1
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect()
    });
    let fifty = get(&server, &admin, &map_path);
    assert_eq!(fifty.status, 200);
    let refs: Vec<&Value> = results.iter().collect();
    assert_cells(&fifty.json(), &expected(&refs), 50);
    assert_eq!(get(&server, &admin, &map_path).body, fifty.body);
    let kept: i64 = rusqlite::Connection::open(dir.path().join("sitar.db"))
        .unwrap()
        .query_row(
            "SELECT COUNT(*) FROM venue_contributions WHERE body IS NOT NULL",
            [],
            |r| r.get(0),
        )
        .unwrap();
    assert_eq!(kept, 50, "every contribution is kept");

    // A 51st joins: every cell is seen by one more session.
    let phone = Phone { dx: 3.0 };
    let (joined, joined_results) = finished_session(&server, &admin, &venue, &phone);
    let map = get(&server, &admin, &map_path).json();
    assert_eq!(map["sessions"].as_array().unwrap().len(), 51);
    let mut refs = refs.clone();
    refs.push(&joined_results);
    assert_cells(&map, &expected(&refs), 51);

    // Its anchor seen 0.5 m elsewhere: its samples move, so the next answer changes.
    let moved = Phone { dx: 3.5 }.anchors_csv();
    put(
        &server,
        &admin,
        &format!("/v1/sessions/{joined}/anchors.csv"),
        &moved,
    );
    let after_move = get(&server, &admin, &map_path).json();
    assert_ne!(after_move["cells"], map["cells"]);
    assert_eq!(after_move["sessions"].as_array().unwrap().len(), 51);

    // Leaving: the 50-session answer again.
    let gone = call(
        &server,
        &admin,
        "DELETE",
        &format!("/v1/sessions/{joined}"),
        None,
        &[],
    );
    assert_eq!(gone.status, 200, "{}", gone.body);
    assert_eq!(get(&server, &admin, &map_path).body, fifty.body);
    server.stop();
}
