//! The worker of an [`crate::UploadJob`]: create, upload, estimate, poll (delivering
//! progressive results), download.

use std::path::Path;
use std::time::Duration;

use crate::job_state::{JobOptions, JobState, Shared, SinkError, UPLOAD_SHARE};
use crate::{Client, Error, SessionOptions, SessionState};

type Sink<'a> = &'a mut dyn FnMut(&str) -> Result<(), SinkError>;

pub(crate) fn run(
    shared: &Shared,
    client: &Client,
    recording: &Path,
    options: &JobOptions,
    sink: Sink<'_>,
) -> Result<(), Error> {
    let (id, playback, needs_upload) = match &options.session_id {
        None => {
            let id = client.create_session_in(
                &options.session,
                &SessionOptions::default(),
                &options.frame,
            )?;
            (id, options.session.playback.clone(), true)
        }
        Some(id) => {
            let st = client.status(id)?;
            shared.update(|p| p.trials_total = st.trials_total);
            let playback = st
                .playback
                .unwrap_or_else(|| options.session.playback.clone());
            (id.clone(), playback, st.state == SessionState::Created)
        }
    };
    log::info!("upload: server session {id}");
    shared.set_server_id(&id);
    if shared.is_cancelled() {
        return Ok(());
    }
    if let Some(dir) = &options.evidence_dir {
        // Before the recording: the session is surely still open to its files then, and a
        // refused log fails the job before the long upload.
        shared.set_state(JobState::Uploading);
        send_phone_logs(shared, client, &id, dir)?;
    }
    if needs_upload {
        send_recording(shared, client, &id, recording)?;
    } else {
        // The server already has the whole recording.
        let size = std::fs::metadata(recording).map(|m| m.len()).unwrap_or(0);
        shared.update(|p| {
            p.bytes_sent = size;
            p.bytes_total = size;
            p.progress = p.progress.max(UPLOAD_SHARE);
        });
    }
    if shared.is_cancelled() {
        return Ok(());
    }
    if let Some(dir) = &options.evidence_dir {
        send_evidence(shared, client, &id, dir);
    }
    shared.set_state(JobState::Playing);
    // With "adb"/"sim" the server plays and estimates on its own (asking for an estimate
    // would cut playback short). With "upload" the playback devices send their trials; once
    // all are there, the job asks for the estimate.
    let mut estimate_requested = playback != "upload";
    let mut delivered_trials = 0;
    loop {
        if shared.is_cancelled() {
            return Ok(());
        }
        let st = client.status(&id)?;
        shared.update(|p| {
            p.trials_done = st.trials_done;
            p.trials_total = st.trials_total;
            p.eta_s = st.eta_s;
            p.progress = p
                .progress
                .max(UPLOAD_SHARE + (1.0 - UPLOAD_SHARE) * st.progress.clamp(0.0, 1.0));
            p.state = match st.state {
                SessionState::Estimating => JobState::Estimating,
                SessionState::Done => JobState::Downloading,
                _ => JobState::Playing,
            };
        });
        match st.state {
            SessionState::Done => break,
            SessionState::Failed => {
                return Err(Error::SessionFailed {
                    id,
                    reason: st.error.unwrap_or_else(|| "no reason given".to_owned()),
                });
            }
            _ => {}
        }
        if !estimate_requested && st.trials_total >= 2 && st.trials_done >= st.trials_total {
            client.start_estimate(&id)?;
            estimate_requested = true;
        }
        if st.results_trials > delivered_trials {
            // Progressive results: a failure here is not fatal, the final results decide.
            match client.results_json(&id) {
                Ok(text) => match shared.deliver(sink, &text, st.results_trials, false) {
                    Ok(_) => delivered_trials = st.results_trials,
                    Err(_) => log::debug!("progressive results of {id} not taken"),
                },
                Err(e) => log::debug!("progressive results not available yet: {e}"),
            }
        }
        sleep_unless_cancelled(shared, options.poll_interval.max(Duration::from_millis(10)));
    }
    let text = match client.results_json(&id) {
        Ok(text) => text,
        Err(e) => {
            log::warn!("results.json failed ({e}); trying results.csv");
            client.results_csv(&id)?
        }
    };
    let trials = client
        .status(&id)
        .map(|s| s.results_trials.max(s.trials_done))
        .unwrap_or(0);
    shared
        .deliver(sink, &text, trials, true)
        .map_err(Error::Results)?;
    log::info!("upload: results of {id} delivered");
    Ok(())
}

/// Sends the recording (resuming what the server kept of an earlier attempt); a cancel stops
/// the transfer itself, not only what comes after it.
fn send_recording(
    shared: &Shared,
    client: &Client,
    id: &str,
    recording: &Path,
) -> Result<(), Error> {
    shared.set_state(JobState::Uploading);
    let sent = client.upload_recording_cancellable(
        id,
        recording,
        &mut |sent, total| {
            shared.update(|p| {
                p.bytes_sent = sent;
                p.bytes_total = total;
                let share = if total == 0 {
                    0.0
                } else {
                    UPLOAD_SHARE * sent as f64 / total as f64
                };
                p.progress = p.progress.max(share);
            });
        },
        &shared.cancelled,
    );
    match sent {
        Err(Error::Cancelled) => Ok(()),
        other => other,
    }
}

/// Sends the phone's log from the session folder: a refused file fails the job (naming it),
/// a backend without the routes is skipped (logged by the client).
fn send_phone_logs(shared: &Shared, client: &Client, id: &str, dir: &Path) -> Result<(), Error> {
    let logs = client.upload_phone_logs(id, dir)?;
    log::info!(
        "upload: phone log of {id}: sent {:?}, not supported by the server {:?}, not in {} {:?}",
        logs.sent,
        logs.unsupported,
        dir.display(),
        logs.missing
    );
    shared.update(|p| p.logs_sent = logs.sent.len() as u32);
    Ok(())
}

/// Sends the session folder's evidence; a failure (after the client's retries) is logged
/// and leaves [`crate::JobProgress::evidence_sent`] false: the results never depend on it.
fn send_evidence(shared: &Shared, client: &Client, id: &str, dir: &Path) {
    // subtrajectories.csv went with the phone's log.
    match client.upload_evidence_files(id, dir, false) {
        Ok(Some(thumbnails)) => {
            log::info!("upload: evidence of {id} sent ({thumbnails} thumbnails)");
            shared.update(|p| p.evidence_sent = true);
        }
        Ok(None) => log::debug!("upload: {} has no evidence", dir.display()),
        Err(e) => log::warn!("upload: evidence of {id} not sent: {e}"),
    }
}

fn sleep_unless_cancelled(shared: &Shared, total: Duration) {
    let step = Duration::from_millis(20);
    let mut slept = Duration::ZERO;
    while slept < total && !shared.is_cancelled() {
        std::thread::sleep(step.min(total - slept));
        slept += step;
    }
}
