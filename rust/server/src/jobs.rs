//! Session jobs: playback, progressive estimates, adaptive stopping, the final estimate.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use crate::Error;
use crate::estimation::{self, Published};
use crate::playback::{PlaybackJob, TrialOutput};
use crate::state::{Live, Shared};

/// How a job ended.
enum Outcome {
    Done,
    /// The server is stopping: the session stays in flight for the next start.
    Interrupted,
}

/// Checks and stores one trial's TUM text under the next index; with an
/// idempotency key seen before, returns the earlier index and stores nothing.
pub(crate) fn store_trial(
    shared: &Shared,
    id: &str,
    key: Option<&str>,
    play_index: Option<u32>,
    tum: &str,
    source: &str,
) -> Result<(u32, bool), Error> {
    let trajectory = estimation::parse_trial(tum, "trial")?;
    shared
        .db
        .add_trial(id, key, play_index, trajectory.len(), source, |index| {
            let dest = shared.files.trial(id, index);
            shared.files.write_atomic(&dest, tum.as_bytes())
        })
}

/// Estimates over every stored trial (off the async runtime) and publishes the results.
pub(crate) async fn estimate_and_publish(
    shared: &Arc<Shared>,
    id: &str,
    setting: &str,
) -> Result<Published, Error> {
    let paths: Vec<_> = shared
        .db
        .trials_in_order(id)?
        .into_iter()
        .map(|i| shared.files.trial(id, i))
        .collect();
    let (setting, thresholds) = (setting.to_string(), shared.config.thresholds);
    let published = tokio::task::spawn_blocking(move || {
        estimation::estimate_files(&paths, &setting, thresholds)
    })
    .await
    .map_err(|e| Error::Internal(format!("estimate task: {e}")))??;
    shared
        .files
        .write_atomic(&shared.files.results_csv(id), published.csv.as_bytes())?;
    shared
        .files
        .write_atomic(&shared.files.results_json(id), published.json.as_bytes())?;
    shared.db.set_results(id, published.trials)?;
    Ok(published)
}

/// Starts the playback job of a session in the background.
pub(crate) fn spawn_session(shared: Arc<Shared>, id: String) {
    tokio::spawn(async move {
        let job = shared.db.start_job(&id, "playback").ok();
        let outcome = play_and_estimate(&shared, &id).await;
        shared.set_live(&id, None);
        match outcome {
            Ok(Outcome::Done) => {
                if let Some(job) = job {
                    let _ = shared.db.finish_job(job, "done", None);
                }
            }
            Ok(Outcome::Interrupted) => {
                log::info!("session {id}: interrupted by shutdown, resumes on next start")
            }
            // An error while the server stops (a cancelled playback, a refused blocking
            // task) is the stop's doing: the session stays in flight for the next start.
            Err(e) if shared.stopping() => {
                log::info!("session {id}: interrupted by shutdown ({e}), resumes on next start")
            }
            Err(e) => {
                let message = e.to_string();
                log::warn!("session {id} failed: {message}");
                let _ = shared.db.set_state(&id, "failed", Some(&message));
                if let Some(job) = job {
                    let _ = shared.db.finish_job(job, "failed", Some(&message));
                }
            }
        }
    });
}

/// Starts the estimate of an `upload` session in the background. The session is
/// `estimating` when this returns (so a delete under the session lock sees it in flight).
pub(crate) fn spawn_estimate(shared: Arc<Shared>, id: String, setting: String) {
    let _ = shared.db.set_state(&id, "estimating", None);
    tokio::spawn(async move {
        let job = shared.db.start_job(&id, "estimate").ok();
        match estimate_and_publish(&shared, &id, &setting).await {
            Ok(_) => {
                let _ = shared.db.set_state(&id, "done", None);
                if let Some(job) = job {
                    let _ = shared.db.finish_job(job, "done", None);
                }
            }
            Err(e) if shared.stopping() => log::info!("session {id}: estimate interrupted: {e}"),
            Err(e) => {
                let message = e.to_string();
                let _ = shared.db.set_state(&id, "failed", Some(&message));
                if let Some(job) = job {
                    let _ = shared.db.finish_job(job, "failed", Some(&message));
                }
            }
        }
    });
}

async fn play_and_estimate(shared: &Arc<Shared>, id: &str) -> Result<Outcome, Error> {
    let row = shared
        .db
        .session(id)?
        .ok_or_else(|| Error::NotFound(format!("no session {id}")))?;
    let backend = shared.backend(&row.playback)?;
    let done_before = shared.db.trial_count(id)?;
    let needed = row.trials_total.saturating_sub(done_before);
    let recording = shared.files.recording(id);
    let plan = {
        let (backend, recording) = (backend.clone(), recording.clone());
        tokio::task::spawn_blocking(move || backend.plan(&recording, needed))
            .await
            .map_err(|e| Error::Internal(format!("plan task: {e}")))??
    };
    let cancel = Arc::new(AtomicBool::new(shared.stopping()));
    shared.set_live(
        id,
        Some(Live {
            cancel: cancel.clone(),
            plan: Some(plan),
            started: Instant::now(),
            done_before,
            needed,
        }),
    );
    shared.db.set_state(id, "playing", None)?;

    let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel::<TrialOutput>();
    let job = PlaybackJob {
        session: id.to_string(),
        recording,
        first_index: done_before,
        trials: needed,
        cancel: cancel.clone(),
    };
    let player = tokio::task::spawn_blocking(move || {
        let sink = move |trial: TrialOutput| {
            let _ = tx.send(trial);
        };
        backend.play(&job, &sink)
    });

    let adaptive = row
        .adaptive_min
        .map(|min| (min.max(2), row.adaptive_k.max(1)));
    let mut history = Vec::new();
    let mut published_trials = 0;
    let mut stop_reason: Option<String> = None;
    if done_before >= 2 {
        let p = estimate_and_publish(shared, id, &row.setting).await?;
        published_trials = p.trials;
        history.push((p.trials, p.classes));
    }
    while let Some(first) = rx.recv().await {
        // Trials that queued up while the last estimate ran go in together.
        let mut batch = vec![first];
        while let Ok(more) = rx.try_recv() {
            batch.push(more);
        }
        for trial in batch {
            if let Err(e) = store_trial(
                shared,
                id,
                None,
                Some(trial.index),
                &trial.tum,
                &trial.source,
            ) {
                log::warn!(
                    "session {id}: trial {} from {} dropped: {e}",
                    trial.index,
                    trial.source
                );
            }
        }
        let count = shared.db.trial_count(id)?;
        if count < 2 || stop_reason.is_some() {
            continue;
        }
        // Progressive results: a first picture from the 2nd trial on.
        let p = estimate_and_publish(shared, id, &row.setting).await?;
        published_trials = p.trials;
        history.push((p.trials, p.classes));
        if let Some((min, k)) = adaptive
            && count >= min
            && count < row.trials_total
            && estimation::classes_stable(&history, k)
        {
            let reason = format!(
                "adaptive stop: no window changed class over the last {k} trials (stopped after {count} of {})",
                row.trials_total
            );
            shared.db.set_stop_reason(id, &reason)?;
            stop_reason = Some(reason);
            cancel.store(true, Ordering::SeqCst);
        }
    }
    let played = player
        .await
        .map_err(|e| Error::Internal(format!("playback task: {e}")))?;
    if shared.stopping() {
        return Ok(Outcome::Interrupted);
    }
    let count = shared.db.trial_count(id)?;
    match played {
        Err(e) if count < 2 => return Err(e),
        Err(e) => {
            let reason = format!("playback failed after {count} trials: {e}");
            shared.db.set_stop_reason(id, &reason)?;
        }
        Ok(()) if count < 2 => {
            return Err(Error::Playback(format!(
                "only {count} trial(s) finished; an estimate needs 2"
            )));
        }
        Ok(()) => {
            if count < row.trials_total && stop_reason.is_none() && cancel.load(Ordering::SeqCst) {
                shared
                    .db
                    .set_stop_reason(id, &format!("estimate requested after {count} trials"))?;
            }
        }
    }
    shared.db.set_state(id, "estimating", None)?;
    if published_trials != count {
        estimate_and_publish(shared, id, &row.setting).await?;
    }
    shared.db.set_state(id, "done", None)?;
    Ok(Outcome::Done)
}

/// After a restart: resume sessions in flight or mark them failed with a reason.
pub(crate) fn recover(shared: &Arc<Shared>) -> Result<(), Error> {
    let interrupted = shared.db.interrupt_running_jobs()?;
    if interrupted > 0 {
        log::info!("{interrupted} job(s) were interrupted by the last stop");
    }
    for row in shared
        .db
        .sessions_in_states(&["uploaded", "playing", "estimating"])?
    {
        let id = row.id.clone();
        if row.playback == "upload" {
            if row.state == "estimating" {
                spawn_estimate(shared.clone(), id, row.setting.clone());
            }
            continue;
        }
        if shared.files.recording(&id).is_file() {
            log::info!("session {id}: resuming after restart");
            spawn_session(shared.clone(), id);
        } else {
            shared.db.set_state(
                &id,
                "failed",
                Some("server restarted and the recording is missing"),
            )?;
        }
    }
    Ok(())
}
