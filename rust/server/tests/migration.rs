//! A data directory written by the previous version: its database gains the new session
//! columns on start, and its sessions are served with the settings they were made with.

mod support;

#[test]
fn a_previous_versions_data_directory_is_served_with_the_default_window_settings() {
    let dir = tempfile::tempdir().unwrap();
    let id = "s00000000000000aa";
    {
        let db = rusqlite::Connection::open(dir.path().join("sitar.db")).unwrap();
        db.execute_batch(&format!(
            "CREATE TABLE sessions (id TEXT PRIMARY KEY, idempotency_key TEXT UNIQUE, \
             created_ms INTEGER NOT NULL, trials_total INTEGER NOT NULL, setting TEXT NOT NULL, \
             playback TEXT NOT NULL, state TEXT NOT NULL, error TEXT, stop_reason TEXT, \
             adaptive_min INTEGER, adaptive_k INTEGER NOT NULL, recording_bytes INTEGER, \
             results_trials INTEGER NOT NULL DEFAULT 0, legacy INTEGER NOT NULL DEFAULT 0, \
             finished_ms INTEGER);
             INSERT INTO sessions (id, created_ms, trials_total, setting, playback, state, \
             adaptive_k, results_trials, finished_ms) \
             VALUES ('{id}', 1, 2, 'median', 'sim', 'done', 3, 2, 2);"
        ))
        .unwrap();
    }
    let session_dir = dir.path().join("sessions").join(id);
    std::fs::create_dir_all(session_dir.join("trials")).unwrap();
    std::fs::write(session_dir.join("results.csv"), "start,error\n1,0.5\n").unwrap();

    // Twice: the second start finds the columns in place and adds nothing.
    for _ in 0..2 {
        // An old data directory gets its admin token on the first start.
        let (server, admin) = support::spawn_with_admin(dir.path());
        let client = sitar_client::Client::new(&server.url())
            .unwrap()
            .with_server_token(&admin)
            .unwrap();
        let status = client.status(id).unwrap();
        assert_eq!(status.state, sitar_client::SessionState::Done);
        assert_eq!(client.results_csv(id).unwrap(), "start,error\n1,0.5\n");
        assert_eq!(status.window_frames, Some(10));
        assert_eq!(status.pose_relation.as_deref(), Some("trans_part"));
        server.stop();
    }
}
