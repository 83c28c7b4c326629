//! Limits per token over loopback: sessions per hour, concurrent uploads and bytes per day
//! answer 429 with `Retry-After`, per token, and a freed upload slot lets the next one in.

use std::io::Write;
use std::net::TcpStream;
use std::time::{Duration, Instant};

use sitar_server::Limits;
use sitar_tests::*;

fn create(base: &str, token: &str) -> (u16, String, String) {
    let mut response = bare_agent()
        .post(&format!("{base}/v1/sessions"))
        .header("authorization", &format!("Bearer {token}"))
        .header("content-type", "application/json")
        .send(r#"{"playback":"upload","trials":100}"#)
        .unwrap();
    let retry = response
        .headers()
        .get("retry-after")
        .map(|v| v.to_str().unwrap().to_owned())
        .unwrap_or_default();
    let body = response.body_mut().read_to_string().unwrap();
    (response.status().as_u16(), retry, body)
}

fn post_trial(base: &str, id: &str, token: &str, text: &str) -> (u16, String, String) {
    let mut response = bare_agent()
        .post(&format!("{base}/v1/sessions/{id}/trials"))
        .header("authorization", &format!("Bearer {token}"))
        .header("content-type", "text/plain")
        .send(text)
        .unwrap();
    let retry = response
        .headers()
        .get("retry-after")
        .map(|v| v.to_str().unwrap().to_owned())
        .unwrap_or_default();
    let body = response.body_mut().read_to_string().unwrap();
    (response.status().as_u16(), retry, body)
}

#[test]
fn each_limit_answers_429_with_retry_after_and_recovers() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = sim_config(&dir.path().join("data"), 20.0, 1);
    config.limits = Limits {
        sessions_per_hour: 2,
        upload_bytes_per_day: 20_000,
        concurrent_uploads: 1,
    };
    let server = start(config);
    let base = server.url();

    // Sessions per hour: the third is refused, with the wait until the first leaves the hour.
    let id = |body: &str| {
        serde_json::from_str::<serde_json::Value>(body).unwrap()["id"]
            .as_str()
            .unwrap()
            .to_owned()
    };
    let (status, _, first) = create(&base, APP_TOKEN);
    assert_eq!(status, 201);
    let first = id(&first);
    assert_eq!(create(&base, APP_TOKEN).0, 201);
    let (status, retry, body) = create(&base, APP_TOKEN);
    assert_eq!(status, 429, "{body}");
    assert_eq!(
        error_code(status, "application/json", &body, 429),
        "too_many_requests"
    );
    let retry: u64 = retry.parse().unwrap();
    assert!((3590..=3600).contains(&retry), "{retry}");
    // Another token has its own count.
    assert_eq!(create(&base, APP2_TOKEN).0, 201);

    // Concurrent uploads: one body held open takes the only slot.
    let addr = server.addr();
    let mut held = TcpStream::connect(addr).unwrap();
    write!(
        held,
        "POST /v1/sessions/{first}/trials HTTP/1.1\r\nHost: {addr}\r\nAuthorization: Bearer {APP_TOKEN}\r\n\
         Content-Type: text/plain\r\nContent-Length: 100000\r\n\r\n0.0 0 0 0 0 0 0 1\n"
    )
    .unwrap();
    held.flush().unwrap();
    let text = tum_walk(200, 0.0);
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let (status, retry, body) = post_trial(&base, &first, APP_TOKEN, &text);
        if status == 429 {
            assert_eq!(retry, "5", "{body}");
            assert!(body.contains("uploads in progress"), "{body}");
            break;
        }
        // The held request may not have reached the server yet.
        assert!(Instant::now() < deadline, "never refused: {status} {body}");
        std::thread::sleep(Duration::from_millis(20));
    }
    // Dropping the held connection frees the slot.
    drop(held);
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let (status, _, body) = post_trial(&base, &first, APP_TOKEN, &text);
        if status == 201 {
            break;
        }
        assert_eq!(status, 429, "{body}");
        assert!(
            Instant::now() < deadline,
            "the slot never came back: {body}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }

    // Bytes per day: uploads go on until 20 000 bytes are used, then wait for a day.
    let mut refused = None;
    for _ in 0..10 {
        let (status, retry, body) = post_trial(&base, &first, APP_TOKEN, &text);
        if status == 429 {
            refused = Some((retry, body));
            break;
        }
        assert_eq!(status, 201, "{body}");
    }
    let (retry, body) = refused.expect("the day's bytes run out");
    assert!(body.contains("last 24 hours"), "{body}");
    // Bytes are counted per whole hour: they leave the 24-hour window 23 to 24 hours on.
    let retry: u64 = retry.parse().unwrap();
    assert!((82_800..=86_400).contains(&retry), "{retry}");
}
