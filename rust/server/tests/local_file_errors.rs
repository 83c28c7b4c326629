//! An upload job whose recording cannot be read fails at once with a local I/O error,
//! and the real server on loopback never sees a session for it.

use sitar_client::{Client, Error, JobOptions, NewSession, UploadJob};
use sitar_server::{Server, ServerConfig};

#[test]
fn an_unreadable_recording_is_an_io_error_before_any_session_exists() {
    let dir = tempfile::tempdir().unwrap();
    let server = Server::spawn(
        ServerConfig::new(dir.path()),
        "127.0.0.1:0".parse().unwrap(),
    )
    .unwrap();
    let admin = std::fs::read_to_string(dir.path().join(sitar_server::ADMIN_TOKEN_FILE)).unwrap();
    let inputs = tempfile::tempdir().unwrap();
    let missing = inputs.path().join("missing.mp4");
    for recording in [inputs.path(), missing.as_path()] {
        let client = Client::new(&server.url())
            .unwrap()
            .with_server_token(&admin)
            .unwrap();
        let options = JobOptions::new(NewSession {
            trials: 2,
            setting: "median".to_owned(),
            playback: "upload".to_owned(),
            window_frames: None,
            pose_relation: None,
        });
        let outcome = UploadJob::start(client, recording, options, |_: &str| {
            Ok::<(), std::io::Error>(())
        });
        match outcome {
            Err(Error::Io { path, .. }) => assert_eq!(path, recording),
            Err(e) => panic!("{recording:?}: not an I/O error: {e}"),
            Ok(_) => panic!("{recording:?}: the job started"),
        }
    }
    let db = rusqlite::Connection::open(dir.path().join("sitar.db")).unwrap();
    let sessions: i64 = db
        .query_row("SELECT COUNT(*) FROM sessions", [], |row| row.get(0))
        .unwrap();
    assert_eq!(sessions, 0, "no session was created");
    server.stop();
}
