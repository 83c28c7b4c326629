//! The status document of a session (`GET /v1/sessions/{id}`, and each entry of the list):
//! its state, progress and ETA (d·⌈T/D⌉ from the playback plan), trials and settings, and
//! its place in the playback queue while it waits (the same from every instance of a
//! cluster: `jobs::progress_view`).

use serde_json::json;

use crate::app_state::App;
use crate::error::Error;
use crate::jobs::progress_view::{self, ProgressView};
use crate::model::{Session, SessionState};
use crate::venue::alignment::alignment_json;

/// Progress (0 … 1) and seconds left, when known; `view` is where the session stands in its
/// player's queue and playback (this instance's or, clustered, the player's).
fn progress(session: &Session, view: &ProgressView, done: u32) -> (f64, Option<f64>) {
    let total = session.trials_total.max(1) as f64;
    match session.state {
        SessionState::Done => (1.0, Some(0.0)),
        SessionState::Failed => (done as f64 / total, None),
        SessionState::Estimating => (0.97, Some(0.5)),
        SessionState::Playing => match &view.playing {
            Some(playing) => {
                let expected = playing.expected_s.max(1e-9);
                let elapsed = playing.elapsed_s(crate::storage::now_ms());
                let by_time = (playing.done_before as f64
                    + playing.needed as f64 * (elapsed / expected).min(1.0))
                    / total;
                let by_trials = done as f64 / total;
                (
                    0.95 * by_time.max(by_trials).min(1.0),
                    Some((expected - elapsed).max(0.0) + 0.5),
                )
            }
            None => (0.95 * done as f64 / total, None),
        },
        SessionState::Created | SessionState::Uploaded => (0.0, None),
    }
}

/// The status document of `session`.
pub(crate) fn status_json(shared: &App, session: &Session) -> Result<serde_json::Value, Error> {
    let done = shared.db.trial_count(&session.id)?;
    let view = match session.state {
        SessionState::Uploaded | SessionState::Playing => {
            progress_view::of_session(shared, &session.id)?
        }
        _ => ProgressView::default(),
    };
    let (progress, eta) = progress(session, &view, done);
    let jobs: Vec<_> = shared
        .db
        .jobs_of(&session.id)?
        .into_iter()
        .map(|(kind, state)| json!({"kind": kind, "state": state}))
        .collect();
    let failed_trials: Vec<_> = shared
        .workers
        .failures(&session.id)?
        .into_iter()
        .map(|f| json!({"index": f.index, "source": f.source, "error": f.error}))
        .collect();
    let settings = &session.settings;
    let mut doc = json!({
        "id": session.id,
        "state": session.state.as_str(),
        "progress": (progress * 1000.0).round() / 1000.0,
        "eta_s": eta.map(|e: f64| (e * 10.0).round() / 10.0),
        "trials_done": done,
        "trials_total": session.trials_total,
        "error": session.error,
        "results_trials": session.results_trials,
        "stop_reason": session.stop_reason,
        "playback": session.playback.as_str(),
        "setting": settings.setting.to_string(),
        "window_frames": settings.window_frames,
        "pose_relation": settings.pose_relation.to_string(),
        "jobs": jobs,
        // Where it waits for a playback worker (1: next); null when not queued.
        "queue_position": view.queue_position,
        // Trials a phone played that could not be used (unparsable, failed on its phone),
        // each with why; a trial played again elsewhere is listed once per failure.
        "failed_trials": failed_trials,
        "venue": session.venue,
        // From the phone's anchors.csv; null in no venue or without one.
        "alignment": alignment_json(&*shared.db, &*shared.blobs, session)?,
        // The calibration its estimates are calibrated with (null: uncalibrated).
        "calibration": session.calibration,
    });
    // Asked for, but this server was started without it: its estimates are published
    // uncalibrated (and their results say so).
    if let Some(name) = &session.calibration
        && shared.config.calibrations.get(name).is_none()
    {
        doc["calibration_missing"] = true.into();
    }
    Ok(doc)
}
