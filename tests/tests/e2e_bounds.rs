//! Every request bounded, over loopback against the real server: connections beyond the cap
//! get a JSON 503, headers dribbled too slowly are cut off, a declared body over its route's
//! limit is a small JSON 413 before any of it is read, a stalled JSON body ends, and the
//! disk quotas answer 413 (session) and 507 (server) leaving nothing behind.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::time::{Duration, Instant};

use sitar_tests::*;

/// The JSON error of a raw answer: (code, whole body length).
fn json_error(answer: &str) -> (String, usize) {
    let (head, body) = answer.split_once("\r\n\r\n").unwrap();
    assert!(
        head.to_ascii_lowercase()
            .contains("content-type: application/json"),
        "{answer}"
    );
    let v: serde_json::Value =
        serde_json::from_str(body).unwrap_or_else(|e| panic!("{e}: {answer}"));
    (v["error"]["code"].as_str().unwrap().to_owned(), body.len())
}

fn addr(server: &sitar_server::ServerHandle) -> SocketAddr {
    server.addr()
}

#[test]
fn connections_beyond_the_cap_get_a_json_503_and_the_slots_come_back() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = sim_config(dir.path(), 10.0, 1);
    config.max_connections = 4;
    config.header_read_timeout = Duration::from_secs(30);
    let server = start(config);
    let held: Vec<TcpStream> = (0..4)
        .map(|_| TcpStream::connect(addr(&server)).unwrap())
        .collect();
    // The accept loop takes them in order; give it a moment to hold all four.
    std::thread::sleep(Duration::from_millis(200));
    let mut extra = TcpStream::connect(addr(&server)).unwrap();
    extra
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let (status, answer) = read_answer(&mut extra);
    assert_eq!(status, 503, "{answer}");
    let (code, len) = json_error(&answer);
    assert_eq!(code, "busy");
    assert!(answer.len() <= 1024 && len < 200, "{answer}");
    // Closed after the answer.
    let mut rest = [0u8; 16];
    assert_eq!(extra.read(&mut rest).unwrap_or(0), 0);

    drop(held);
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let (status, _, _) = raw("GET", &format!("{}/healthz", server.url()), None, b"", &[]);
        if status == 200 {
            break;
        }
        assert!(Instant::now() < deadline, "the slots never came back");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn requests_hyper_cannot_parse_get_the_json_error_shape_too() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(dir.path(), 10.0, 1));
    let many_headers: String = (0..200).map(|i| format!("x-h{i}: a\r\n")).collect();
    for (head, status, code) in [
        (
            // A Content-Length beyond u64: hyper refuses it before any handler runs.
            "POST /v1/sessions HTTP/1.1\r\nhost: x\r\ncontent-length: 99999999999999999999999\r\n\r\n"
                .to_string(),
            400,
            "bad_request",
        ),
        ("GARBAGE\r\n\r\n".to_string(), 400, "bad_request"),
        (
            format!("GET /healthz HTTP/1.1\r\nhost: x\r\n{many_headers}\r\n"),
            431,
            "headers_too_large",
        ),
    ] {
        let (got, answer) = exchange(addr(&server), &head, b"");
        assert_eq!(got, status, "{answer}");
        let (got_code, len) = json_error(&answer);
        assert_eq!(got_code, code, "{answer}");
        assert!(answer.len() <= 1024 && len < 300, "{answer}");
    }
    // The connection's other answers are untouched: a normal request still works.
    let (status, answer) = exchange(
        addr(&server),
        "GET /healthz HTTP/1.1\r\nhost: x\r\nconnection: close\r\n\r\n",
        b"",
    );
    assert_eq!(status, 200, "{answer}");
}

#[test]
fn headers_dribbled_slowly_are_cut_off() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = sim_config(dir.path(), 10.0, 1);
    config.header_read_timeout = Duration::from_millis(800);
    let server = start(config);
    // A connection that sends nothing at all is closed too.
    let mut silent = TcpStream::connect(addr(&server)).unwrap();
    silent
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let opened = Instant::now();
    let mut buf = [0u8; 64];
    let _ = silent.read(&mut buf);
    assert!(
        opened.elapsed() < Duration::from_secs(5),
        "{:?}",
        opened.elapsed()
    );
    let mut slow = TcpStream::connect(addr(&server)).unwrap();
    slow.write_all(b"GET /healthz HTTP/1.1\r\nhost: x\r\n")
        .unwrap();
    let started = Instant::now();
    let mut cut_after = None;
    // One header byte every 100 ms, for at most 10 s: the server must close first.
    for i in 0..100 {
        std::thread::sleep(Duration::from_millis(100));
        if slow
            .write_all(format!("x-dribble-{i}: y\r\n").as_bytes())
            .is_err()
        {
            cut_after = Some(started.elapsed());
            break;
        }
        slow.set_nonblocking(true).unwrap();
        let mut buf = [0u8; 256];
        let closed = match slow.read(&mut buf) {
            Ok(_) => true,
            Err(e) => e.kind() != std::io::ErrorKind::WouldBlock,
        };
        slow.set_nonblocking(false).unwrap();
        if closed {
            cut_after = Some(started.elapsed());
            break;
        }
    }
    let cut_after = cut_after.expect("the dribbling client was never cut off");
    assert!(cut_after < Duration::from_secs(5), "{cut_after:?}");
    // A quick client is served as always.
    let (status, _, _) = raw("GET", &format!("{}/healthz", server.url()), None, b"", &[]);
    assert_eq!(status, 200);
}

#[test]
fn every_route_refuses_an_oversized_declared_body_before_reading_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = sim_config(dir.path(), 10.0, 1);
    config.max_recording_bytes = 1 << 20;
    config.max_trajectory_bytes = 1 << 20;
    let server = start(config);
    let id = upload_session(&client(&server), 2);
    let huge = 1u64 << 40;
    for (method, path, limit) in [
        ("POST", "/v1/sessions".to_owned(), 64 << 10),
        ("GET", "/healthz".to_owned(), 64 << 10),
        ("GET", format!("/v1/sessions/{id}"), 64 << 10),
        ("POST", format!("/v1/sessions/{id}/estimate"), 64 << 10),
        ("DELETE", format!("/v1/sessions/{id}"), 64 << 10),
        ("POST", format!("/v1/sessions/{id}/share"), 64 << 10),
        ("PUT", format!("/v1/sessions/{id}/recording"), 1 << 20),
        ("POST", format!("/v1/sessions/{id}/trials"), 1 << 20),
        ("PUT", format!("/v1/sessions/{id}/evidence.csv"), 8 << 20),
        ("POST", "/recording".to_owned(), (1 << 20) + (64 << 10)),
        ("GET", "/no/such/route".to_owned(), 64 << 10),
    ] {
        for declared in [limit + 1, huge] {
            let head = format!(
                "{method} {path} HTTP/1.1\r\nhost: x\r\nauthorization: Bearer {ADMIN_TOKEN}\r\n\
                 content-type: application/octet-stream\r\ncontent-length: {declared}\r\n\r\n"
            );
            // No body at all: the answer must not wait for one.
            let (status, answer) = exchange(addr(&server), &head, b"");
            assert_eq!(status, 413, "{method} {path} {declared}: {answer}");
            let (code, _) = json_error(&answer);
            assert_eq!(code, "too_large", "{answer}");
            assert!(answer.len() <= 1024, "{} bytes: {answer}", answer.len());
        }
    }
    // The session is untouched.
    let (status, _, body) = raw(
        "GET",
        &format!("{}/v1/sessions/{id}", server.url()),
        None,
        b"",
        &[],
    );
    assert_eq!(status, 200, "{body}");
}

#[test]
fn a_stalled_json_body_ends_after_the_body_timeout() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = sim_config(dir.path(), 10.0, 1);
    config.body_idle_timeout = Duration::from_millis(500);
    let server = start(config);
    let head = format!(
        "POST /v1/sessions HTTP/1.1\r\nhost: x\r\nauthorization: Bearer {ADMIN_TOKEN}\r\n\
         content-type: application/json\r\ncontent-length: 100\r\n\r\n"
    );
    let started = Instant::now();
    let (status, answer) = exchange(addr(&server), &head, b"{\"trials\":");
    assert_eq!(status, 400, "{answer}");
    assert!(answer.contains("no data for 0.5 s"), "{answer}");
    assert!(started.elapsed() < Duration::from_secs(5));
}

fn session_files(data: &Path, id: &str) -> Vec<String> {
    let dir = data.join("sessions").join(id);
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .map(|entries| {
            entries
                .flatten()
                .filter(|e| e.path().is_file())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

fn put_recording(url: &str, body: &[u8], declare: bool) -> (u16, String) {
    let addr: SocketAddr = url
        .strip_prefix("http://")
        .unwrap()
        .split('/')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let path = &url[url.find("/v1/").unwrap()..];
    if declare {
        let head = format!(
            "PUT {path} HTTP/1.1\r\nhost: x\r\nauthorization: Bearer {ADMIN_TOKEN}\r\n\
             content-type: application/octet-stream\r\ncontent-length: {}\r\n\r\n",
            body.len()
        );
        exchange(addr, &head, body)
    } else {
        // Chunked: the quota is only found while streaming.
        let head = format!(
            "PUT {path} HTTP/1.1\r\nhost: x\r\nauthorization: Bearer {ADMIN_TOKEN}\r\n\
             content-type: application/octet-stream\r\ntransfer-encoding: chunked\r\n\r\n"
        );
        let mut chunked = Vec::new();
        for chunk in body.chunks(16 << 10) {
            chunked.extend_from_slice(format!("{:x}\r\n", chunk.len()).as_bytes());
            chunked.extend_from_slice(chunk);
            chunked.extend_from_slice(b"\r\n");
        }
        chunked.extend_from_slice(b"0\r\n\r\n");
        exchange(addr, &head, &chunked)
    }
}

#[test]
fn the_session_quota_is_413_and_the_server_quota_507_leaving_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let mut config = sim_config(&data, 10.0, 1);
    config.session_disk_quota = 1 << 20;
    config.disk_quota = 6 << 20;
    let server = start(config);
    let admin = client(&server);
    let url = |id: &str| format!("{}/v1/sessions/{id}/recording", server.url());

    let a = upload_session(&admin, 2);
    let before = session_files(&data, &a);
    for declare in [true, false] {
        let (status, answer) = put_recording(&url(&a), &vec![7u8; (1 << 20) + 1], declare);
        assert_eq!(status, 413, "declared {declare}: {answer}");
        assert!(answer.contains("disk quota"), "{answer}");
        assert_eq!(session_files(&data, &a), before, "declared {declare}");
    }
    let (status, answer) = put_recording(&url(&a), &vec![7u8; 900 << 10], true);
    assert_eq!(status, 202, "{answer}");

    // Five more sessions fill the server's 6 MiB; the next upload is a 507.
    let mut others = Vec::new();
    let refused = loop {
        assert!(others.len() < 8, "the server quota never answered");
        let id = upload_session(&admin, 2);
        let (status, answer) = put_recording(&url(&id), &vec![9u8; 1000 << 10], false);
        match status {
            202 => others.push(id),
            507 => {
                let (code, _) = json_error(&answer);
                assert_eq!(code, "insufficient_storage");
                break id;
            }
            _ => panic!("{answer}"),
        }
    };
    assert!(others.len() >= 4, "only {} fitted", others.len());
    assert!(session_files(&data, &refused).is_empty(), "{refused}");
    assert!(
        std::fs::read_dir(data.join("tmp"))
            .unwrap()
            .next()
            .is_none(),
        "an upload left a temporary file"
    );

    // Deleting sessions makes room again (once the usage is measured afresh).
    for id in &others {
        admin.delete_session(id).unwrap();
    }
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let (status, answer) = put_recording(&url(&refused), &vec![9u8; 1000 << 10], true);
        if status == 202 {
            break;
        }
        assert_eq!(status, 507, "{answer}");
        assert!(
            Instant::now() < deadline,
            "no room after deleting: {answer}"
        );
        std::thread::sleep(Duration::from_millis(250));
    }
}

#[test]
fn results_json_pages_its_windows_and_answers_a_normal_session_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = sim_config(dir.path(), 10.0, 1);
    config.progressive_uploads = false;
    let server = start(config);
    let admin = client(&server);
    let id = upload_session(&admin, 2);
    for wobble in [0.0, 0.01] {
        admin.upload_trial(&id, &tum_walk(300, wobble)).unwrap();
    }
    admin.start_estimate(&id).unwrap();
    wait_done(&admin, &id);
    let url = format!("{}/v1/sessions/{id}/results.json", server.url());
    let (status, _, whole) = raw("GET", &url, None, b"", &[]);
    assert_eq!(status, 200, "{whole}");
    let whole: serde_json::Value = serde_json::from_str(&whole).unwrap();
    assert!(whole.get("page").is_none(), "{whole}");
    let windows = whole["windows"].as_array().unwrap().clone();
    assert!(windows.len() > 7, "{} windows", windows.len());

    let mut paged = Vec::new();
    let mut next = Some(0u64);
    while let Some(offset) = next {
        let (status, _, text) = raw(
            "GET",
            &format!("{url}?offset={offset}&limit=3"),
            None,
            b"",
            &[],
        );
        assert_eq!(status, 200, "{text}");
        let page: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(page["page"]["total"], windows.len());
        assert_eq!(page["setting"], whole["setting"]);
        paged.extend(page["windows"].as_array().unwrap().iter().cloned());
        next = page["page"]["next"].as_u64();
    }
    assert_eq!(paged, windows);
    let (status, ct, text) = raw("GET", &format!("{url}?limit=0"), None, b"", &[]);
    assert_eq!(error_code(status, &ct, &text, 400), "bad_request");
}

#[test]
fn the_subtrajectory_list_pages_like_results_json() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(dir.path(), 10.0, 1));
    let id = upload_session(&client(&server), 2);
    let base = format!("{}/v1/sessions/{id}", server.url());
    let mut table = String::from("index,start_ns,end_ns\n");
    for k in 0..25u64 {
        table.push_str(&format!(
            "{k},{},{}\n",
            k * 1_000_000,
            k * 1_000_000 + 999_999
        ));
    }
    let (status, _, text) = raw(
        "PUT",
        &format!("{base}/subtrajectories.csv"),
        Some("text/csv"),
        table.as_bytes(),
        &[],
    );
    assert_eq!(status, 200, "{text}");
    let get = |query: &str| {
        let (status, _, text) = raw(
            "GET",
            &format!("{base}/subtrajectories{query}"),
            None,
            b"",
            &[],
        );
        assert_eq!(status, 200, "{text}");
        serde_json::from_str::<serde_json::Value>(&text).unwrap()
    };
    let whole = get("");
    assert!(whole.get("page").is_none());
    assert_eq!(whole["subtrajectories"].as_array().unwrap().len(), 25);
    let mut indices = Vec::new();
    let mut next = Some(0);
    while let Some(offset) = next {
        let page = get(&format!("?offset={offset}&limit=10"));
        assert_eq!(page["page"]["total"], 25);
        indices.extend(
            page["subtrajectories"]
                .as_array()
                .unwrap()
                .iter()
                .map(|s| s["index"].as_u64().unwrap()),
        );
        next = page["page"]["next"].as_u64();
    }
    assert_eq!(indices, (0..25).collect::<Vec<u64>>());
}
