//! A recording upload that breaks off is resumed, not sent again: the server keeps the
//! prefix (across a restart too), and the client sends only the rest.

use std::io::{Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use sitar_tests::*;

/// `HEAD` on the recording URL with an `Idempotency-Key`: the `Upload-Offset` answered.
fn kept(url: &str, key: Option<&str>) -> u64 {
    let mut request = agent().head(url);
    if let Some(key) = key {
        request = request.header("idempotency-key", key);
    }
    let response = request.call().unwrap();
    assert_eq!(response.status().as_u16(), 200);
    response
        .headers()
        .get("upload-offset")
        .expect("HEAD answers Upload-Offset")
        .to_str()
        .unwrap()
        .parse()
        .unwrap()
}

fn wait_until_kept(url: &str, key: &str, wanted: u64) {
    let deadline = Instant::now() + Duration::from_secs(20);
    while kept(url, Some(key)) != wanted {
        assert!(
            Instant::now() < deadline,
            "the server never kept {wanted} bytes"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// A raw connection with the head of a recording PUT that announces `announced` bytes.
fn open_put(url: &str, key: &str, announced: usize) -> TcpStream {
    let rest = url.strip_prefix("http://").unwrap();
    let (host, path) = rest.split_at(rest.find('/').unwrap());
    let mut stream = TcpStream::connect(host).unwrap();
    write!(
        stream,
        "PUT {path} HTTP/1.1\r\nhost: {host}\r\ncontent-type: application/octet-stream\r\n\
         authorization: Bearer {ADMIN_TOKEN}\r\n\
         idempotency-key: {key}\r\ncontent-length: {announced}\r\n\r\n"
    )
    .unwrap();
    stream
}

/// A PUT that announces `announced` bytes, sends `body`, and hangs up.
fn put_and_hang_up(url: &str, key: &str, announced: usize, body: &[u8]) {
    let mut stream = open_put(url, key, announced);
    stream.write_all(body).unwrap();
    stream.flush().unwrap();
    stream.shutdown(Shutdown::Both).unwrap();
}

fn resume_put(url: &str, key: &str, range: &str, body: &[u8]) -> (u16, String, Option<String>) {
    let mut response = agent()
        .put(url)
        .header("content-type", "application/octet-stream")
        .header("content-range", range)
        .header("idempotency-key", key)
        .send(body)
        .unwrap();
    let offset = response
        .headers()
        .get("upload-offset")
        .map(|v| v.to_str().unwrap().to_string());
    let text = response.body_mut().read_to_string().unwrap();
    (response.status().as_u16(), text, offset)
}

fn stored(data: &Path, id: &str, name: &str) -> Option<Vec<u8>> {
    std::fs::read(data.join("sessions").join(id).join(name)).ok()
}

#[test]
fn a_broken_upload_keeps_its_prefix_across_a_restart_and_resumes_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let mut config = sim_config(&data, 10.0, 1);
    config.max_recording_bytes = 1 << 20;
    let server = start(config.clone());
    let id = upload_session(&client(&server), 2);
    let url = format!("{}/v1/sessions/{id}/recording", server.url());
    let bytes = recording_bytes(300_000);

    assert_eq!(kept(&url, Some("k1")), 0);
    put_and_hang_up(&url, "k1", bytes.len(), &bytes[..120_000]);
    wait_until_kept(&url, "k1", 120_000);
    assert_eq!(stored(&data, &id, "recording"), None);
    // The bytes belong to their upload's key: another key (or none) sees nothing kept.
    assert_eq!(kept(&url, None), 0);
    assert_eq!(kept(&url, Some("k2")), 0);
    // The latest broken upload's prefix replaces an older one.
    put_and_hang_up(&url, "k2", bytes.len(), &bytes[..50_000]);
    wait_until_kept(&url, "k2", 50_000);
    assert_eq!(kept(&url, Some("k1")), 0);
    put_and_hang_up(&url, "k1", bytes.len(), &bytes[..120_000]);
    wait_until_kept(&url, "k1", 120_000);

    // The prefix outlives the server.
    server.stop();
    let server = start(config);
    let url = format!("{}/v1/sessions/{id}/recording", server.url());
    assert_eq!(kept(&url, Some("k1")), 120_000);

    // Refused before the body is read, so the bodies are short: another key's resume (409,
    // offset 0), a resume from the wrong byte (409 naming the kept length), malformed
    // ranges, a body that disagrees with its range, a total over the limit. None changes
    // what is kept.
    let ten = &bytes[120_000..120_010];
    let (status, text, offset) = resume_put(&url, "k2", "bytes 120000-120009/300000", ten);
    assert_eq!((status, offset.as_deref()), (409, Some("0")), "{text}");
    let (status, text, offset) = resume_put(&url, "k1", "bytes 100-109/300000", ten);
    assert_eq!(status, 409, "{text}");
    assert!(text.contains("resume from byte 120000"), "{text}");
    assert_eq!(offset.as_deref(), Some("120000"));
    for (range, wanted) in [
        ("bytes 120009-120000/300000", 400),
        ("bytes=120000-120009/300000", 400),
        ("bytes 120000-120009", 400),
        ("bytes 120000-299999/300000", 400),
        ("bytes 120000-120009/2000001", 413),
    ] {
        let (status, text, _) = resume_put(&url, "k1", range, ten);
        assert_eq!(status, wanted, "{range}: {text}");
        assert!(text.contains("\"error\""), "{text}");
    }
    assert_eq!(kept(&url, Some("k1")), 120_000);

    // A middle chunk, then the last one.
    let (status, text, offset) = resume_put(
        &url,
        "k1",
        "bytes 120000-199999/300000",
        &bytes[120_000..200_000],
    );
    assert_eq!(status, 200, "{text}");
    assert_eq!(offset.as_deref(), Some("200000"));
    let (status, text, _) = resume_put(&url, "k1", "bytes 200000-299999/300000", &bytes[200_000..]);
    assert_eq!(status, 202, "{text}");
    assert!(text.contains("\"uploaded\""), "{text}");
    assert_eq!(stored(&data, &id, "recording").as_deref(), Some(&bytes[..]));
    assert_eq!(stored(&data, &id, "recording.part"), None);
    assert_eq!(stored(&data, &id, "recording.part.key"), None);
    assert_eq!(kept(&url, Some("k1")), 0);
    server.stop();
}

fn wait_for(path: &Path) {
    let deadline = Instant::now() + Duration::from_secs(20);
    while !path.exists() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A TCP proxy that cuts the first connection to carry `cut_after` request bytes, once the
/// server has kept what it got (`kept_marker` exists), so the client can only resume.
/// Counts the request bytes it forwards on every other connection.
struct CuttingProxy {
    url: String,
    forwarded_after_cut: Arc<AtomicU64>,
}

fn cutting_proxy(server_url: &str, kept_marker: PathBuf, cut_after: u64) -> CuttingProxy {
    let upstream = server_url.strip_prefix("http://").unwrap().to_string();
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}", listener.local_addr().unwrap());
    let forwarded_after_cut = Arc::new(AtomicU64::new(0));
    let counter = forwarded_after_cut.clone();
    let cut = Arc::new(AtomicBool::new(false));
    std::thread::spawn(move || {
        for client in listener.incoming() {
            let Ok(client) = client else { return };
            let server = TcpStream::connect(&upstream).unwrap();
            let (mut from_client, mut to_server) =
                (client.try_clone().unwrap(), server.try_clone().unwrap());
            let (mut from_server, mut to_client) = (server, client);
            // The client learns of the cut only once the server kept the prefix.
            let this_cut = Arc::new(AtomicBool::new(false));
            let (cut_here, marker) = (this_cut.clone(), kept_marker.clone());
            std::thread::spawn(move || {
                let _ = std::io::copy(&mut from_server, &mut to_client);
                if cut_here.load(Ordering::SeqCst) {
                    wait_for(&marker);
                }
                let _ = to_client.shutdown(Shutdown::Both);
            });
            let counter = counter.clone();
            let kept_marker = kept_marker.clone();
            let cut = cut.clone();
            std::thread::spawn(move || {
                let mut buf = vec![0u8; 64 << 10];
                let mut sent = 0u64;
                loop {
                    let limit = if cut.load(Ordering::SeqCst) {
                        u64::MAX
                    } else {
                        cut_after
                    };
                    let want = buf.len().min((limit - sent).min(1 << 30) as usize);
                    if want == 0 && !cut.swap(true, Ordering::SeqCst) {
                        // Cut: the server sees the body break off; wait until it kept the
                        // prefix, then hang up on the client too.
                        counter.fetch_sub(sent, Ordering::SeqCst);
                        this_cut.store(true, Ordering::SeqCst);
                        let _ = to_server.shutdown(Shutdown::Both);
                        wait_for(&kept_marker);
                        let _ = from_client.shutdown(Shutdown::Both);
                        return;
                    }
                    let Ok(got) = from_client.read(&mut buf[..want]) else {
                        return;
                    };
                    if got == 0 || to_server.write_all(&buf[..got]).is_err() {
                        let _ = to_server.shutdown(Shutdown::Write);
                        return;
                    }
                    sent += got as u64;
                    counter.fetch_add(got as u64, Ordering::SeqCst);
                }
            });
        }
    });
    CuttingProxy {
        url,
        forwarded_after_cut,
    }
}

#[test]
fn the_client_resumes_a_cut_upload_and_sends_only_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let server = start(sim_config(&data, 10.0, 1));
    let id = upload_session(&client(&server), 2);
    let bytes = recording_bytes(8 << 20);
    let path = dir.path().join("recording.mp4");
    std::fs::write(&path, &bytes).unwrap();

    let marker = data.join("sessions").join(&id).join("recording.part.key");
    let proxy = cutting_proxy(&server.url(), marker, 3 << 20);
    let through_proxy = sitar_client::Client::new(&proxy.url)
        .unwrap()
        .with_timeout(Duration::from_secs(20))
        .with_retries(3, Duration::from_millis(20))
        .with_server_token(ADMIN_TOKEN)
        .unwrap();
    let mut reports = Vec::new();
    through_proxy
        .upload_recording(&id, &path, &mut |sent, total| reports.push((sent, total)))
        .unwrap();

    assert_eq!(stored(&data, &id, "recording").as_deref(), Some(&bytes[..]));
    assert_eq!(stored(&data, &id, "recording.part"), None);
    assert_eq!(stored(&data, &id, "recording.part.key"), None);
    // After the cut only the rest went through (plus a HEAD and headers): under 5.1 MiB of 8.
    let after = proxy.forwarded_after_cut.load(Ordering::SeqCst);
    assert!(
        after < (5 << 20) + (100 << 10),
        "{after} bytes sent after the cut"
    );
    assert!(after > (4 << 20), "{after} bytes sent after the cut");
    // Progress restarts at the kept offset, not at 0, and ends whole.
    let total = bytes.len() as u64;
    assert_eq!(reports.last(), Some(&(total, total)));
    let restart = reports
        .windows(2)
        .find(|w| w[1].0 <= w[0].0)
        .map(|w| w[1].0)
        .expect("progress starts again after the cut");
    assert!(restart > (2 << 20), "resumed at {restart}");
}

#[test]
fn a_later_call_for_the_same_file_resumes_what_a_failed_one_left() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let server = start(sim_config(&data, 10.0, 1));
    let id = upload_session(&client(&server), 2);
    let bytes = recording_bytes(6 << 20);
    let path = dir.path().join("recording.mp4");
    std::fs::write(&path, &bytes).unwrap();

    // The app gives up (no retries) when its connection is cut...
    let marker = data.join("sessions").join(&id).join("recording.part.key");
    let proxy = cutting_proxy(&server.url(), marker, 2 << 20);
    let impatient = sitar_client::Client::new(&proxy.url)
        .unwrap()
        .with_timeout(Duration::from_secs(20))
        .with_retries(0, Duration::from_millis(20))
        .with_server_token(ADMIN_TOKEN)
        .unwrap();
    let err = impatient
        .upload_recording(&id, &path, &mut |_, _| {})
        .unwrap_err();
    assert!(
        matches!(err, sitar_client::Error::Network { .. }),
        "{err:?}"
    );
    assert_eq!(stored(&data, &id, "recording"), None);

    // ...and a later call (a new client, as after an app restart) sends only the rest.
    let mut reports = Vec::new();
    client(&server)
        .upload_recording(&id, &path, &mut |sent, total| reports.push((sent, total)))
        .unwrap();
    let total = bytes.len() as u64;
    let first = reports.first().unwrap().0;
    assert!((1 << 20..2 << 20).contains(&first), "resumed at {first}");
    assert_eq!(reports.last(), Some(&(total, total)));
    assert_eq!(stored(&data, &id, "recording").as_deref(), Some(&bytes[..]));
    assert_eq!(stored(&data, &id, "recording.part"), None);
}

#[test]
fn a_stalled_upload_is_cut_off_and_its_prefix_resumed_while_it_still_hangs() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let mut config = sim_config(&data, 10.0, 1);
    config.upload_idle_timeout = Duration::from_millis(300);
    let server = start(config);
    let id = upload_session(&client(&server), 2);
    let url = format!("{}/v1/sessions/{id}/recording", server.url());
    let bytes = recording_bytes(200_000);

    // A client that sends half and then goes silent, keeping the connection open.
    let mut silent = open_put(&url, "k1", bytes.len());
    silent.write_all(&bytes[..80_000]).unwrap();
    silent.flush().unwrap();

    // The server gives up on it, keeps the prefix, and answers it with a 400 naming why.
    wait_until_kept(&url, "k1", 80_000);
    silent
        .set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    let mut answer = [0u8; 512];
    let n = silent.read(&mut answer).unwrap();
    let answer = String::from_utf8_lossy(&answer[..n]);
    assert!(answer.starts_with("HTTP/1.1 400"), "{answer}");
    assert!(answer.contains("no data for 0.3 s"), "{answer}");

    let (status, text, _) = resume_put(&url, "k1", "bytes 80000-199999/200000", &bytes[80_000..]);
    assert_eq!(status, 202, "{text}");
    assert_eq!(stored(&data, &id, "recording").as_deref(), Some(&bytes[..]));
}
