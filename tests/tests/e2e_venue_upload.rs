//! The phone's log and venue through `sitar-client`'s upload job against the real backend:
//! an ARCore phone's session in a venue, recorded by sitar-core with observations of the
//! venue's printed anchor, goes up with `UploadJob`; the backend files it under the venue with
//! its convention, aligns it from the `anchors.csv` the job sent, and serves the phone's own
//! `trajectory.txt`.

use std::time::{Duration, Instant};

use sitar_client::{JobOptions, JobState, NewSession, SessionFrame, UploadJob, VenueAlignment};
use sitar_core::{Pose, Session, SessionConfig, Tracking};
use sitar_sim::Recording;
use sitar_tests::*;

/// The phone: every frame of the walk, and a full observation of the anchor `hall` (2 m in
/// front of the start, upright, facing the walk) every 10th frame, a limited one between.
fn record_in_venue(recording: &Recording, venue: &str) -> Session {
    let config = format!(r#"{{"convention":"arcore","venue":"{venue}"}}"#);
    let mut session = Session::new(SessionConfig::from_json(&config).unwrap());
    let gt = &recording.walk().ground_truth;
    let pose = |i: usize| Pose::new(gt.positions[i], gt.orientations[i]);
    let image = Pose::new(
        gt.positions[0] + glam::DVec3::new(0.0, 0.0, -2.0),
        glam::DQuat::IDENTITY,
    );
    let last = gt.len() - 1;
    session.start(gt.stamps[0], pose(0)).unwrap();
    for i in 1..last {
        session.frame(gt.stamps[i], pose(i)).unwrap();
        let tracking = match i % 10 {
            0 => Tracking::Full,
            5 => Tracking::Limited,
            _ => continue,
        };
        session
            .anchor(gt.stamps[i], "hall", image, tracking)
            .unwrap();
    }
    session.stop(gt.stamps[last], pose(last)).unwrap();
    session
}

fn call(method: &str, url: &str, body: &str) -> (u16, serde_json::Value) {
    let auth = format!("Bearer {APP_TOKEN}");
    let (status, _, text) = raw(
        method,
        url,
        Some("application/json"),
        body.as_bytes(),
        &[("authorization", &auth)],
    );
    (
        status,
        serde_json::from_str(&text).unwrap_or(serde_json::Value::Null),
    )
}

#[test]
fn the_upload_job_puts_a_phone_session_into_its_venue() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 40.0, 2));
    let (status, venue) = call(
        "POST",
        &format!("{}/v1/venues", server.url()),
        r#"{"name":"Hall","anchor":"hall","cell_m":0.25}"#,
    );
    assert_eq!(status, 201, "{venue}");
    let venue = venue["id"].as_str().unwrap().to_owned();

    let recording = Recording::demo(4.0, 30.0, 9).unwrap();
    let rec_path = dir.path().join("walk.rec");
    std::fs::write(&rec_path, recording.to_bytes()).unwrap();
    let session = record_in_venue(&recording, &venue);
    let folder = dir.path().join("walk.rec.session");
    session.save(&folder).unwrap();
    let full = session
        .anchors()
        .iter()
        .filter(|o| o.tracking == Tracking::Full)
        .count();
    assert!(full >= 5, "{full} full observations");

    let mut options = JobOptions::new(NewSession {
        trials: 2,
        setting: "median".into(),
        playback: "sim".into(),
        window_frames: None,
        pose_relation: None,
    });
    options.poll_interval = Duration::from_millis(20);
    options.evidence_dir = Some(folder.clone());
    options.frame = SessionFrame {
        convention: Some("arcore".into()),
        venue: Some(venue.clone()),
    };
    let client = client_with(&server, APP_TOKEN);
    let job = UploadJob::start(client, &rec_path, options, |_: &str| {
        Ok::<(), std::convert::Infallible>(())
    })
    .unwrap();
    let started = Instant::now();
    while !job.progress().state.is_finished() && started.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let progress = job.progress();
    assert_eq!(progress.state, JobState::Done, "{:?}", progress.error);
    assert_eq!(progress.logs_sent, 4, "all four files taken");
    let id = job.server_id().unwrap();

    // The backend knows the venue and aligns the session from the anchors.csv it was sent:
    // the full observations only, and they agree exactly.
    let st = client_with(&server, APP_TOKEN).status(&id).unwrap();
    assert_eq!(st.venue.as_deref(), Some(venue.as_str()));
    match st.alignment {
        Some(VenueAlignment::Aligned {
            anchor,
            observations,
            position_spread_m,
            heading_spread_deg,
        }) => {
            assert_eq!((anchor.as_str(), observations as usize), ("hall", full));
            assert!(position_spread_m < 1e-9 && heading_spread_deg < 1e-6);
        }
        other => panic!("not aligned: {other:?}"),
    }

    // The phone's own log, as the job sent it.
    let (status, _, tum) = get_bytes(
        &format!("{}/v1/sessions/{id}/trajectory.tum", server.url()),
        Some(APP_TOKEN),
    );
    assert_eq!(status, 200);
    assert_eq!(tum, std::fs::read(folder.join("trajectory.txt")).unwrap());

    // Another convention cannot join this venue's sessions: a 409 naming both.
    let (status, answer) = call(
        "POST",
        &format!("{}/v1/sessions", server.url()),
        &format!(r#"{{"trials":2,"setting":"median","playback":"sim","venue":"{venue}"}}"#),
    );
    assert_eq!(status, 409, "{answer}");
    let message = answer["error"]["message"].as_str().unwrap();
    assert!(
        message.contains("arcore") && message.contains("unity"),
        "{message}"
    );
}
