//! Session jobs: playback with progressive estimates and adaptive stopping, the final
//! estimate, `upload` sessions' progressive estimates, and resuming after a restart.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use crate::Error;
use crate::config::PlaybackKind;
use crate::db::JobEnd;
use crate::estimation::{self, Published};
use crate::held::Purpose;
use crate::live::LiveSession;
use crate::playback::{PlaybackJob, TrialOutput};
use crate::session::{SessionState, Step};
use crate::shared::{RunningJob, Shared};
use crate::trials::{self, Arrival};

/// How a job ended.
enum Outcome {
    Done,
    /// The server is stopping: the session stays in flight for the next start.
    Interrupted,
}

/// How a playback job begins.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Begin {
    /// The recording was just accepted: `uploaded → playing`.
    Start,
    /// After a restart; the session was already resumed (`Lifecycle::resume`).
    Resume,
}

/// Publishes the estimate over the live session's trials if any arrived since the last.
async fn publish(
    shared: &Arc<Shared>,
    live: &Arc<LiveSession>,
    id: &str,
    purpose: Purpose,
) -> Result<Option<Published>, Error> {
    let (shared, id) = (shared.clone(), id.to_string());
    live.publish(purpose, move |published| {
        crate::published::write(&shared, &id, published)
    })
    .await
}

/// Ends a job's session: a failure is recorded (unless the server is stopping, which leaves
/// the session in flight), the job row closed, the live session dropped.
fn conclude(shared: &Shared, id: &str, job: Option<i64>, outcome: Result<Outcome, Error>) {
    shared.set_running(id, None);
    shared.live.remove(id);
    match outcome {
        Ok(Outcome::Done) => {
            if let Some(job) = job {
                let _ = shared.db.finish_job(job, JobEnd::Done, None);
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
            // The stored reason is shown to clients: no server paths in it.
            let message = e.client_message();
            log::warn!("session {id} failed: {e}");
            if let Err(e) = shared.lifecycle().fail(id, &message) {
                log::warn!("session {id}: {e}");
            }
            if let Some(job) = job {
                let _ = shared.db.finish_job(job, JobEnd::Failed, Some(&message));
            }
        }
    }
}

/// Starts the playback job of a session in the background.
pub(crate) fn spawn_session(shared: Arc<Shared>, id: String, begin: Begin) {
    tokio::spawn(async move {
        let job = shared.db.start_job(&id, "playback").ok();
        let outcome = play_and_estimate(&shared, &id, begin).await;
        conclude(&shared, &id, job, outcome);
    });
}

/// Runs the final estimate of an `upload` session in the background; the caller has moved
/// it to `estimating` (so a delete under the session lock sees it in flight).
pub(crate) fn spawn_estimate(shared: Arc<Shared>, id: String) {
    tokio::spawn(async move {
        let job = shared.db.start_job(&id, "estimate").ok();
        let outcome = async {
            let session = shared.session(&id)?;
            let live = trials::live_session(&shared, &session).await?;
            // Nothing new since the last progressive estimate: it is the final one.
            publish(&shared, &live, &id, Purpose::Final).await?;
            shared.lifecycle().finish(&id)?;
            Ok(Outcome::Done)
        }
        .await;
        conclude(&shared, &id, job, outcome);
    });
}

/// After a trial of an `upload` session: publishes progressive estimates in the background
/// until no trial is left waiting (trials that arrive during one are taken together by the
/// next). One such worker per session at a time.
pub(crate) fn spawn_progressive(shared: Arc<Shared>, live: Arc<LiveSession>, id: String) {
    if !shared.config.progressive_uploads || !live.claim_worker() {
        return;
    }
    tokio::spawn(async move {
        loop {
            if let Err(e) = publish(&shared, &live, &id, Purpose::Progressive).await
                && !shared.stopping()
            {
                log::warn!("session {id}: progressive estimate: {e}");
            }
            if !live.release_worker() {
                break;
            }
        }
    });
}

async fn play_and_estimate(shared: &Arc<Shared>, id: &str, begin: Begin) -> Result<Outcome, Error> {
    let session = shared.session(id)?;
    let backend = shared.backend(session.playback);
    let done_before = shared.db.trial_count(id)?;
    let needed = session.trials_total.saturating_sub(done_before);
    let recording = shared.files.recording(id);
    let plan = {
        let (backend, recording) = (backend.clone(), recording.clone());
        tokio::task::spawn_blocking(move || backend.plan(&recording, needed))
            .await
            .map_err(|e| Error::Internal(format!("plan task: {e}")))??
    };
    let cancel = Arc::new(AtomicBool::new(shared.stopping()));
    shared.set_running(
        id,
        Some(RunningJob {
            cancel: cancel.clone(),
            plan: Some(plan),
            started: Instant::now(),
            done_before,
            needed,
        }),
    );
    if begin == Begin::Start {
        shared.lifecycle().start_playing(id)?;
    }
    let live = trials::live_session(shared, &session).await?;

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

    let adaptive = session
        .adaptive_min
        .map(|min| (min.max(2), session.adaptive_k.max(1)));
    let mut history = Vec::new();
    let mut stop_reason: Option<String> = None;
    let stop = |reason: String, stop_reason: &mut Option<String>| -> Result<(), Error> {
        shared.lifecycle().stop(id, &reason)?;
        *stop_reason = Some(reason);
        cancel.store(true, Ordering::SeqCst);
        Ok(())
    };
    if done_before >= 2
        && let Some(p) = publish(shared, &live, id, Purpose::Progressive).await?
    {
        history.push((p.trials, p.classes));
    }
    while let Some(first) = rx.recv().await {
        // Trials that queued up while the last estimate ran go in together.
        let mut batch = vec![first];
        while let Ok(more) = rx.try_recv() {
            batch.push(more);
        }
        for trial in batch {
            let arrival = Arrival {
                key: None,
                play_index: Some(trial.index),
                source: &trial.source,
            };
            let bytes = trial.tum.as_bytes();
            let stored = trials::parse_trial(bytes, "trial")
                .and_then(|parsed| trials::store_trial(shared, &live, id, arrival, bytes, parsed));
            match stored {
                Ok(_) => {}
                // The memory bound: what is there is estimated, nothing more is played.
                Err(e @ (Error::TooLarge { .. } | Error::Busy(_))) if stop_reason.is_none() => {
                    let count = shared.db.trial_count(id)?;
                    stop(
                        format!("memory bound: {e} (stopped after {count} trials)"),
                        &mut stop_reason,
                    )?;
                }
                Err(e) => log::warn!(
                    "session {id}: trial {} from {} dropped: {e}",
                    trial.index,
                    trial.source
                ),
            }
        }
        let count = shared.db.trial_count(id)?;
        if count < 2 || stop_reason.is_some() {
            continue;
        }
        // Progressive results: a first picture from the 2nd trial on.
        let Some(p) = publish(shared, &live, id, Purpose::Progressive).await? else {
            continue;
        };
        history.push((p.trials, p.classes));
        if let Some((min, k)) = adaptive
            && count >= min
            && count < session.trials_total
            && estimation::classes_stable(&history, k)
        {
            stop(
                format!(
                    "adaptive stop: no window changed class over the last {k} trials (stopped after {count} of {})",
                    session.trials_total
                ),
                &mut stop_reason,
            )?;
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
        Err(e) => stop(
            format!("playback failed after {count} trials: {e}"),
            &mut stop_reason,
        )?,
        Ok(()) if count < 2 => {
            return Err(Error::Playback(format!(
                "only {count} trial(s) finished; an estimate needs 2"
            )));
        }
        Ok(()) => {
            if count < session.trials_total
                && stop_reason.is_none()
                && cancel.load(Ordering::SeqCst)
            {
                stop(
                    format!("estimate requested after {count} trials"),
                    &mut stop_reason,
                )?;
            }
        }
    }
    shared.lifecycle().start_estimating(id)?;
    publish(shared, &live, id, Purpose::Final).await?;
    shared.lifecycle().finish(id)?;
    Ok(Outcome::Done)
}

/// After a restart: resume sessions in flight or mark them failed with a reason. Jobs a dead
/// process left running are marked interrupted first.
pub(crate) fn recover(shared: &Arc<Shared>) -> Result<(), Error> {
    let interrupted = shared.db.interrupt_running_jobs()?;
    if interrupted > 0 {
        log::info!("{interrupted} job(s) were interrupted by the last stop");
    }
    let in_flight = [
        SessionState::Created,
        SessionState::Uploaded,
        SessionState::Playing,
        SessionState::Estimating,
    ];
    for session in shared.db.sessions_in(&in_flight)? {
        let id = session.id.clone();
        if session.playback == PlaybackKind::Upload {
            if session.state == SessionState::Estimating {
                shared.lifecycle().resume(&id)?;
                spawn_estimate(shared.clone(), id);
            } else if shared.config.progressive_uploads
                && session.results_trials < shared.db.trial_count(&id)?
            {
                // Trials arrived after the last published estimate: catch up.
                let shared = shared.clone();
                tokio::spawn(async move {
                    match trials::live_session(&shared, &session).await {
                        Ok(live) => spawn_progressive(shared.clone(), live, id),
                        Err(e) => log::warn!("session {id}: cannot rebuild its trials: {e}"),
                    }
                });
            }
            continue;
        }
        if session.state == SessionState::Created {
            continue;
        }
        if !shared.files.recording(&id).is_file() {
            shared
                .lifecycle()
                .fail(&id, "server restarted and the recording is missing")?;
            continue;
        }
        log::info!("session {id}: resuming after restart");
        if session.allows(Step::StartPlaying) {
            spawn_session(shared.clone(), id, Begin::Start);
        } else {
            shared.lifecycle().resume(&id)?;
            spawn_session(shared.clone(), id, Begin::Resume);
        }
    }
    Ok(())
}
