//! Progressive estimates of `upload` sessions (the server's incremental estimator: each trial
//! adds only its pairs): after every trial from the 2nd on, exactly (bitwise) the one-shot
//! estimate over the trials so far, for every setting, both pose relations and a window
//! length other than the default; rebuilt from the trial files after a restart; and bounded
//! in memory.

use sitar_client::{NewSession, SessionState};
use sitar_estimator::{EstimateOptions, PoseRelation, Setting, Thresholds, Trajectory};
use sitar_tests::*;

/// Four trials of one walk, the third with every 7th frame dropped (so its pairs need a real
/// association, not the identical-stamps shortcut).
fn trials() -> Vec<Trajectory> {
    let rec = sitar_sim::Recording::demo(3.0, 30.0, 21).unwrap();
    let mut trials = sitar_sim::simulate_trials(&rec, 4);
    let kept: Vec<usize> = (0..trials[2].len()).filter(|k| k % 7 != 3).collect();
    trials[2] = trials[2].reduce_to_ids(&kept);
    trials
}

fn upload_session(client: &sitar_client::Client, setting: Setting) -> String {
    windowed_session(client, setting, None)
}

/// An `upload` session of 4 trials; `window` names its window frames and pose relation.
fn windowed_session(
    client: &sitar_client::Client,
    setting: Setting,
    window: Option<(u32, PoseRelation)>,
) -> String {
    let new = NewSession {
        trials: 4,
        setting: setting.to_string(),
        playback: "upload".into(),
        window_frames: window.map(|(frames, _)| frames),
        pose_relation: window.map(|(_, relation)| relation.to_string()),
    };
    client.create_session(&new).unwrap()
}

/// The f64 bits of every window's error (`error_m` or `error_deg`) in a results JSON text.
fn error_bits(json: &str) -> Vec<u64> {
    let doc: serde_json::Value = serde_json::from_str(json).unwrap();
    doc["windows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| {
            let error = w.get("error_m").or_else(|| w.get("error_deg"));
            error.and_then(|e| e.as_f64()).unwrap().to_bits()
        })
        .collect()
}

#[test]
fn progressive_results_equal_a_one_shot_estimate_bitwise_for_every_setting() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 20.0, 1));
    let client = client(&server);
    let trials = trials();
    let windows = [None, Some((7, PoseRelation::RotationAngleDeg))];
    for (setting, window) in Setting::ALL
        .into_iter()
        .flat_map(|s| windows.map(|w| (s, w)))
    {
        let id = windowed_session(&client, setting, window);
        let (delta, pose_relation) = window
            .map_or((10, PoseRelation::TranslationPart), |(f, r)| {
                (f as usize, r)
            });
        let options = EstimateOptions {
            setting,
            delta,
            pose_relation,
            ..EstimateOptions::default()
        };
        let thresholds = match pose_relation {
            PoseRelation::RotationAngleDeg => Thresholds::DEFAULT_DEG,
            _ => Thresholds::DEFAULT_M,
        };
        for n in 1..=trials.len() {
            client.upload_trial(&id, &tum_text(&trials[n - 1])).unwrap();
            if n < 2 {
                continue;
            }
            wait_results(&client, &id, n as u32);
            let got = client.results_json(&id).unwrap();
            let one_shot = direct_estimate(&trials[..n], &options);
            assert_same_results(&got, &one_shot.to_json(thresholds));
            let bits: Vec<u64> = one_shot
                .windows
                .iter()
                .map(|w| w.error_m.to_bits())
                .collect();
            assert_eq!(error_bits(&got), bits, "{setting} {window:?}, {n} trials");
            assert_same_results(&client.results_csv(&id).unwrap(), &one_shot.to_legacy_csv());
        }
        // The final estimate over trials the last progressive one already covered is that one.
        let before = client.results_json(&id).unwrap();
        client.start_estimate(&id).unwrap();
        let status = wait_done(&client, &id);
        assert_eq!(
            (status.state, status.results_trials),
            (SessionState::Done, 4)
        );
        assert_eq!(client.results_json(&id).unwrap(), before, "{setting}");
    }
}

#[test]
fn after_a_restart_the_trials_come_back_from_their_files_and_estimates_go_on() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let trials = trials();
    let server = start(sim_config(&data, 20.0, 1));
    let client = client(&server);
    let id = upload_session(&client, Setting::TrimMean(30));
    for (n, trial) in trials[..3].iter().enumerate() {
        client.upload_trial(&id, &tum_text(trial)).unwrap();
        if n >= 1 {
            wait_results(&client, &id, n as u32 + 1);
        }
    }
    server.stop();

    let server = start(sim_config(&data, 20.0, 1));
    let client = sitar_tests::client(&server);
    assert_eq!(client.status(&id).unwrap().results_trials, 3);
    client.upload_trial(&id, &tum_text(&trials[3])).unwrap();
    wait_results(&client, &id, 4);
    let expected = direct_estimate(&trials, &EstimateOptions::default());
    assert_same_results(&client.results_csv(&id).unwrap(), &expected.to_legacy_csv());
    client.start_estimate(&id).unwrap();
    assert_eq!(wait_done(&client, &id).state, SessionState::Done);
    assert_same_results(&client.results_csv(&id).unwrap(), &expected.to_legacy_csv());
}

#[test]
fn trials_beyond_the_memory_bounds_are_refused_and_nothing_of_them_is_stored() {
    let dir = tempfile::tempdir().unwrap();
    let trials = trials();
    // Parsed, a trial of 90 poses takes about 6 kB: room for two per session, three in all.
    let one = trials[0].len() * 64 + 200;
    let mut config = sim_config(&dir.path().join("data"), 20.0, 1);
    config.live_session_bytes = 2 * one;
    config.live_total_bytes = 3 * one;
    config.progressive_uploads = false;
    let server = start(config);
    let client = client(&server);
    let (a, b) = (
        upload_session(&client, Setting::Mean),
        upload_session(&client, Setting::Mean),
    );
    let url = |id: &str| format!("{}/v1/sessions/{id}/trials", server.url());
    let post = |id: &str, trial: &Trajectory| {
        raw(
            "POST",
            &url(id),
            Some("text/plain"),
            tum_text(trial).as_bytes(),
            &[],
        )
    };
    for trial in &trials[..2] {
        assert_eq!(post(&a, trial).0, 201);
    }
    let (status, ct, body) = post(&a, &trials[2]);
    assert_eq!(error_code(status, &ct, &body, 413), "too_large");
    assert!(body.contains("in memory"), "{body}");
    assert_eq!(post(&b, &trials[0]).0, 201);
    let (status, ct, body) = post(&b, &trials[1]);
    assert_eq!(error_code(status, &ct, &body, 503), "busy");
    assert_eq!(client.status(&a).unwrap().trials_done, 2);
    assert_eq!(client.status(&b).unwrap().trials_done, 1);
    // Without progressive estimates, results come with the estimate asked for.
    assert_eq!(client.status(&a).unwrap().results_trials, 0);
    client.start_estimate(&a).unwrap();
    assert_eq!(wait_done(&client, &a).state, SessionState::Done);
    let expected = direct_estimate(
        &trials[..2],
        &EstimateOptions {
            setting: Setting::Mean,
            ..EstimateOptions::default()
        },
    );
    assert_same_results(&client.results_csv(&a).unwrap(), &expected.to_legacy_csv());
    // A finished session's trials leave memory: b has room again.
    assert_eq!(post(&b, &trials[1]).0, 201);
    let (_, _, page) = raw("GET", &format!("{}/", server.url()), None, b"", &[]);
    assert!(page.contains("id=\"memory\""), "{page}");
}
