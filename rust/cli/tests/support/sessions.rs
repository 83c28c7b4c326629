//! Sim sessions for the real-process tests, and what the embedded server answers for the
//! same: the reference a cluster's answers must equal byte for byte.

use std::path::Path;
use std::time::Duration;

use sitar_client::{Client, NewSession};

/// Creates a sim session of `trials` trials with estimator `setting` and uploads
/// `recording` to it: its id.
pub fn sim_session(client: &Client, recording: &Path, trials: u32, setting: &str) -> String {
    let id = client
        .create_session(&NewSession {
            trials,
            setting: setting.into(),
            playback: "sim".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    client
        .upload_recording(&id, recording, &mut |_, _| {})
        .unwrap();
    id
}

/// `results.json` and `results.csv` of the same session played in-process by the embedded
/// server (sim playback at 200×, 3 phones).
pub fn embedded_results(recording: &Path, trials: u32, setting: &str) -> (String, String) {
    let data = tempfile::tempdir().unwrap();
    let server = sitar_tests::start(sitar_tests::sim_config(data.path(), 200.0, 3));
    let client = sitar_tests::client_with(&server, sitar_tests::APP_TOKEN);
    let id = sim_session(&client, recording, trials, setting);
    let status = client
        .wait(
            &id,
            Duration::from_millis(50),
            Duration::from_secs(120),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(status.state.as_str(), "done", "{status:?}");
    let results = (
        client.results_json(&id).unwrap(),
        client.results_csv(&id).unwrap(),
    );
    server.stop();
    results
}

/// The number of trial files in session `id`'s `trials.zip` at `url`.
pub fn trials_in_zip(url: &str, token: &str, id: &str) -> usize {
    let zip = ureq::get(&format!("{url}/v1/sessions/{id}/trials.zip"))
        .header("authorization", &format!("Bearer {token}"))
        .call()
        .unwrap()
        .body_mut()
        .read_to_vec()
        .unwrap();
    zip::ZipArchive::new(std::io::Cursor::new(zip))
        .unwrap()
        .len()
}
