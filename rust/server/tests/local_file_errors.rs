//! An upload job whose recording cannot be read fails at once with a local I/O error,
//! and the real server on loopback never sees a session for it.

mod support;

use sitar_client::{Client, Error, JobOptions, NewSession, UploadJob};

#[test]
fn an_unreadable_recording_is_an_io_error_before_any_session_exists() {
    let dir = tempfile::tempdir().unwrap();
    let (server, admin) = support::spawn_with_admin(dir.path());
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
