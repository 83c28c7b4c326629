//! Hostile and careless requests against the real server on loopback: every rejection is the
//! JSON error shape, a resumed upload's total is fixed by its first chunk, absurd poses and
//! bodies are refused naming what is wrong.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::Duration;

use sitar_server::ServerHandle;

mod support;

struct Reply {
    status: u16,
    head: String,
    body: String,
}

impl Reply {
    /// The `{"error":{"code","message"}}` body, or a panic naming what came instead.
    fn error(&self) -> (String, String) {
        assert!(
            self.head
                .to_ascii_lowercase()
                .contains("content-type: application/json"),
            "not JSON: {} {}",
            self.head,
            self.body
        );
        let v: serde_json::Value = serde_json::from_str(&self.body).unwrap_or_else(|e| {
            panic!("{e}: {}", self.body);
        });
        let code = v["error"]["code"].as_str().expect("error.code").to_owned();
        let message = v["error"]["message"].as_str().expect("error.message");
        (code, message.to_owned())
    }
}

/// One request on its own connection (`Connection: close`), the whole reply read back.
fn send(server: &ServerHandle, token: &str, head: &str, body: &[u8]) -> Reply {
    let mut stream = TcpStream::connect(server.addr()).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    let request = format!(
        "{head}\r\nHost: localhost\r\nAuthorization: Bearer {token}\r\nConnection: close\r\n\r\n"
    );
    stream.write_all(request.as_bytes()).unwrap();
    let _ = stream.write_all(body);
    let mut raw = Vec::new();
    let _ = stream.read_to_end(&mut raw);
    let text = String::from_utf8_lossy(&raw).into_owned();
    let (head, body) = text.split_once("\r\n\r\n").unwrap_or((&text, ""));
    let status = head
        .split(' ')
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no status line: {text:?}"));
    Reply {
        status,
        head: head.to_owned(),
        body: body.to_owned(),
    }
}

fn start() -> (tempfile::TempDir, ServerHandle, String) {
    let dir = tempfile::tempdir().unwrap();
    let (server, admin) = support::spawn_with_admin(dir.path());
    (dir, server, admin)
}

fn create_upload_session(server: &ServerHandle, token: &str) -> String {
    let body = br#"{"trials":2,"playback":"upload"}"#;
    let r = send(
        server,
        token,
        &format!(
            "POST /v1/sessions HTTP/1.1\r\nContent-Type: application/json\r\nContent-Length: {}",
            body.len()
        ),
        body,
    );
    assert_eq!(r.status, 201, "{}", r.body);
    let v: serde_json::Value = serde_json::from_str(&r.body).unwrap();
    v["id"].as_str().unwrap().to_owned()
}

#[test]
fn every_rejection_is_the_json_error_shape() {
    let (_dir, server, admin) = start();
    let id = create_upload_session(&server, &admin);
    let cases: Vec<(String, Vec<u8>, u16)> = vec![
        ("GET /v1/sessions/%ff HTTP/1.1".into(), vec![], 404),
        ("GET /share/%ff%fe HTTP/1.1".into(), vec![], 400),
        ("GET /v1/sessions/%ff/report HTTP/1.1".into(), vec![], 404),
        (
            "POST /v1/sessions HTTP/1.1\r\nContent-Type: application/json\r\nContent-Length: 1"
                .into(),
            b"{".to_vec(),
            400,
        ),
        ("PATCH /v1/sessions HTTP/1.1".into(), vec![], 405),
        ("GET /nowhere HTTP/1.1".into(), vec![], 404),
        (
            format!(
                "POST /v1/sessions/{id}/trials HTTP/1.1\r\nContent-Type: image/png\r\nContent-Length: 1"
            ),
            b"x".to_vec(),
            415,
        ),
    ];
    for (head, body, status) in cases {
        let r = send(&server, &admin, &head, &body);
        assert_eq!(r.status, status, "{head}: {}", r.body);
        let (code, message) = r.error();
        assert!(
            !code.is_empty() && !message.is_empty(),
            "{head}: {}",
            r.body
        );
    }
    server.stop();
}

#[test]
fn a_resumed_uploads_total_is_fixed_by_its_first_chunk() {
    let (_dir, server, admin) = start();
    let id = create_upload_session(&server, &admin);
    let chunk = |range: &str, bytes: &[u8]| {
        send(
            &server,
            &admin,
            &format!(
                "PUT /v1/sessions/{id}/recording HTTP/1.1\r\nIdempotency-Key: k1\r\n\
                 Content-Type: application/octet-stream\r\nContent-Range: bytes {range}\r\n\
                 Content-Length: {}",
                bytes.len()
            ),
            bytes,
        )
    };
    let r = chunk("0-9/1000", &[7; 10]);
    assert_eq!(r.status, 200, "{}", r.body);
    let r = chunk("10-19/5000", &[7; 10]);
    assert_eq!(r.status, 409, "{}", r.body);
    let (code, message) = r.error();
    assert_eq!(code, "conflict");
    assert!(
        message.contains("5000") && message.contains("1000"),
        "{message}"
    );
    // The kept prefix is untouched and continues under its first total.
    let r = chunk("10-19/1000", &[7; 10]);
    assert_eq!(r.status, 200, "{}", r.body);
    assert!(r.body.contains("\"received\":20"), "{}", r.body);
    server.stop();
}

#[test]
fn an_absurd_pose_is_refused_naming_its_line() {
    let (_dir, server, admin) = start();
    let id = create_upload_session(&server, &admin);
    let trial = "# tum\n0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 1\n0.2 1e308 0 0 0 0 0 1\n";
    let r = send(
        &server,
        &admin,
        &format!(
            "POST /v1/sessions/{id}/trials HTTP/1.1\r\nContent-Type: text/plain\r\n\
             Content-Length: {}",
            trial.len()
        ),
        trial.as_bytes(),
    );
    assert_eq!(r.status, 422, "{}", r.body);
    let (code, message) = r.error();
    assert_eq!(code, "invalid_content");
    assert!(message.contains(":4: "), "{message}");
    server.stop();
}

#[test]
fn an_absurd_content_length_gets_a_json_413() {
    let (_dir, server, admin) = start();
    let id = create_upload_session(&server, &admin);
    // Lengths hyper itself refuses before the router (beyond u64, or u64::MAX) still get
    // its empty 400/431; anything it passes on is ours to answer.
    for length in ["1000000000000000000", "18446744073709551612"] {
        let r = send(
            &server,
            &admin,
            &format!(
                "PUT /v1/sessions/{id}/recording HTTP/1.1\r\n\
                 Content-Type: application/octet-stream\r\nContent-Length: {length}"
            ),
            b"",
        );
        assert_eq!(r.status, 413, "{length}: {} {}", r.head, r.body);
        assert_eq!(r.error().0, "too_large");
    }
    server.stop();
}

#[test]
fn a_session_request_is_bounded_and_never_echoed_whole() {
    let (_dir, server, admin) = start();
    // Declared too large: refused before a byte is read.
    let r = send(
        &server,
        &admin,
        "POST /v1/sessions HTTP/1.1\r\nContent-Type: application/json\r\nContent-Length: 67108864",
        b"",
    );
    assert_eq!(r.status, 413, "{}", r.body);
    assert!(r.body.len() <= 1024, "{} bytes", r.body.len());
    assert_eq!(r.error().0, "too_large");
    // Chunked (no declared length) past the limit: cut off while streaming.
    let mut chunked = Vec::new();
    for _ in 0..20 {
        chunked.extend_from_slice(format!("{:x}\r\n", 8192).as_bytes());
        chunked.extend_from_slice(&[b' '; 8192]);
        chunked.extend_from_slice(b"\r\n");
    }
    chunked.extend_from_slice(b"0\r\n\r\n");
    let r = send(
        &server,
        &admin,
        "POST /v1/sessions HTTP/1.1\r\nContent-Type: application/json\r\nTransfer-Encoding: chunked",
        &chunked,
    );
    assert_eq!(r.status, 413, "{}", r.body);
    // A long setting within the limit: the answer quotes a short prefix of it.
    let body = format!(r#"{{"setting":"{}"}}"#, "x".repeat(60_000));
    let r = send(
        &server,
        &admin,
        &format!(
            "POST /v1/sessions HTTP/1.1\r\nContent-Type: application/json\r\nContent-Length: {}",
            body.len()
        ),
        body.as_bytes(),
    );
    assert_eq!(r.status, 400, "{}", r.body);
    assert!(r.body.len() <= 1024, "{} bytes: {}", r.body.len(), r.body);
    assert!(r.error().1.contains("setting"));
    server.stop();
}
