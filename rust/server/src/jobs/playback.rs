//! Session jobs: playback with progressive estimates and adaptive stopping (on the
//! playback workers, which take sessions from the queue), the final estimate, `upload`
//! sessions' progressive estimates (within the estimate workers' permits), cancelling, and
//! resuming after a restart.

use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::app_state::{App, RunningJob};
use crate::error::Error;
use crate::estimate::held_trials::Purpose;
use crate::estimate::live_sessions::LiveSession;
use crate::estimate::publishing::Published;
use crate::jobs::playback_run::{self as run, Outcome, publish, too_few_after_cancel};
use crate::model::{PlaybackKind, Session, SessionState, Step};
pub(crate) use crate::playback::queue::Begin;
use crate::playback::queue::{Intent, Ticket};
use crate::storage::JobEnd;
use crate::storage::keys::SessionObject;

/// How long a delete waits for a playback it stopped to end.
const STOP_WAIT: Duration = Duration::from_secs(15);

/// Ends a job's session: a failure is recorded (unless the server is stopping, which leaves
/// the session in flight), the job row closed, the live session dropped.
fn conclude(shared: &Arc<App>, id: &str, job: Option<i64>, outcome: Result<Outcome, Error>) {
    shared.set_running(id, None);
    shared.live.remove(id);
    let in_flight =
        matches!(outcome, Ok(Outcome::Interrupted | Outcome::Adopted)) || shared.stopping();
    if !in_flight {
        // Nobody plays it now: an instance waiting to delete it goes ahead.
        if let Err(e) = shared.db.release_session(id, &shared.instance) {
            log::warn!("session {id}: still marked as played by this instance: {e}");
        }
    }
    match outcome {
        Ok(Outcome::Done) => {
            if let Some(job) = job {
                let _ = shared.db.finish_job(job, JobEnd::Done, None);
            }
            crate::report::scene::prepare(shared.db.clone(), shared.blobs.clone(), id.to_string());
            // Its contribution to its venue's map, computed once now that it is final.
            let (shared, id) = (shared.clone(), id.to_string());
            tokio::task::spawn_blocking(move || {
                crate::venue::map::keep_now(&*shared.db, &*shared.blobs, &id)
            });
        }
        Ok(Outcome::Interrupted) => {
            log::info!("session {id}: interrupted by shutdown, resumes on next start")
        }
        Ok(Outcome::Deleted) => log::info!("session {id}: playback stopped for its deletion"),
        Ok(Outcome::Adopted) => {
            log::warn!(
                "session {id}: another instance plays it now (this one was silent past the \
                 instance timeout); left to it"
            );
            if let Some(job) = job {
                let why = "its session was adopted by another instance";
                let _ = shared.db.finish_job(job, JobEnd::Interrupted, Some(why));
            }
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

/// Puts a sim or adb session in the playback queue, a playback worker takes it in turn, once
/// this instance is its player (claimed in the database; false when another live instance
/// plays it, and the queue is left as it is).
pub(crate) fn enqueue(shared: &App, session: &Session, begin: Begin) -> Result<bool, Error> {
    let id = &session.id;
    if !shared
        .db
        .claim_session(id, &shared.instance, shared.alive_since_ms())?
    {
        log::info!("session {id}: another instance plays it");
        return Ok(false);
    }
    shared.queue.push(session.owner, id, begin);
    Ok(true)
}

/// Starts the playback workers: each takes the next session from the queue and plays it to
/// the end, until the server stops.
pub(crate) fn spawn_workers(shared: &Arc<App>) {
    // Remote playback: a job holds a thread while its trials are out with the hosts; the
    // hosts' phones, not these jobs, bound how many trials play at once.
    let workers = if shared.remote_playback() {
        crate::jobs::reaper::spawn(shared.clone());
        shared.config.remote_sessions.max(1)
    } else {
        shared.config.playback_workers.max(1)
    };
    for _ in 0..workers {
        let shared = shared.clone();
        tokio::spawn(async move {
            while let Some(ticket) = shared.queue.next().await {
                let id = ticket.id.clone();
                // A task of its own: a panic in one job ends that job, not the worker.
                let job = tokio::spawn(run_ticket(shared.clone(), ticket)).await;
                if let Err(e) = job {
                    log::error!("session {id}: playback job ended abnormally: {e}");
                    shared.set_running(&id, None);
                }
                shared.queue.finished(&id);
            }
        });
    }
}

async fn run_ticket(shared: Arc<App>, ticket: Ticket) {
    let id = ticket.id.clone();
    let job = shared.db.start_job(&id, "playback", &shared.instance).ok();
    let outcome = play_and_estimate(&shared, &ticket).await;
    conclude(&shared, &id, job, outcome);
}

/// Runs `work` within an estimate worker's permit; `None` when the server stops first.
async fn with_estimate_permit<T>(
    shared: &App,
    work: impl std::future::Future<Output = T>,
) -> Option<T> {
    let _permit = shared.estimates.acquire().await.ok()?;
    Some(work.await)
}

/// Runs the final estimate of an `upload` session in the background; the caller has moved
/// it to `estimating` (so a delete under the session lock sees it in flight).
pub(crate) fn spawn_estimate(shared: Arc<App>, id: String) {
    // Claimed as a playback is: an instance starting meanwhile leaves it to this one, and
    // if this one dies another adopts it.
    match shared
        .db
        .claim_session(&id, &shared.instance, shared.alive_since_ms())
    {
        Ok(true) => {}
        Ok(false) => {
            log::info!("session {id}: another instance runs its final estimate");
            return;
        }
        Err(e) => log::warn!("session {id}: not marked as estimated here: {e}"),
    }
    // Nothing new since the last progressive estimate: it is the final one.
    spawn_final_estimate(shared, id, |_, _| Ok(()));
}

/// Runs a session's final estimate in the background within an estimate worker's permit,
/// `prepare` first (the state moves the caller has not made), then publish and finish.
fn spawn_final_estimate<F>(shared: Arc<App>, id: String, prepare: F)
where
    F: FnOnce(&App, &Session) -> Result<(), Error> + Send + 'static,
{
    tokio::spawn(async move {
        let job = shared.db.start_job(&id, "estimate", &shared.instance).ok();
        let outcome = with_estimate_permit(&shared, async {
            let session = shared.session(&id)?;
            prepare(&shared, &session)?;
            let live = crate::jobs::live_session::live_session(&shared, &session).await?;
            publish(&shared, &live, &id, Purpose::Final).await?;
            shared.lifecycle().finish(&id)?;
            Ok(Outcome::Done)
        })
        .await
        .unwrap_or(Ok(Outcome::Interrupted));
        conclude(&shared, &id, job, outcome);
    });
}

/// Publishes at once what the session holds (the phone's walk just arrived: its estimate
/// alone, or with the trials held as its replays), within an estimate worker's permit;
/// `Ok(None)` when there is nothing new or the server stops.
pub(crate) async fn publish_now(
    shared: &Arc<App>,
    live: &Arc<LiveSession>,
    id: &str,
) -> Result<Option<Published>, Error> {
    with_estimate_permit(shared, publish(shared, live, id, Purpose::Progressive))
        .await
        .unwrap_or(Ok(None))
}

/// After a trial of an `upload` session: publishes progressive estimates in the background
/// until no trial is left waiting (trials that arrive during one are taken together by the
/// next). One such worker per session at a time, each within an estimate worker's permit.
pub(crate) fn spawn_progressive(shared: Arc<App>, live: Arc<LiveSession>, id: String) {
    if !shared.config.progressive_uploads || !live.claim_worker() {
        return;
    }
    tokio::spawn(async move {
        loop {
            let published =
                with_estimate_permit(&shared, publish(&shared, &live, &id, Purpose::Progressive))
                    .await;
            if let Some(Err(e)) = &published
                && !shared.stopping()
            {
                log::warn!("session {id}: progressive estimate: {e}");
            }
            if published.is_none() {
                live.release_worker();
                break;
            }
            if !live.release_worker() {
                break;
            }
        }
    });
}

/// What stopping a sim or adb session's playback found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stopped {
    /// It waited in the queue and left it: no job ever works on it now.
    Dequeued,
    /// Its job was told to stop (and, for a delete, has ended).
    Playing,
    /// Neither queued nor playing.
    Idle,
}

/// Stops session `id`'s playback on this instance for `intent` (`Cancel` or `Delete`): out
/// of the queue if it waits there, else its job is told; a delete waits (bounded) until the
/// job has ended. (`stop_requests::stop_anywhere` also reaches another instance's job.)
pub(crate) async fn stop_playback(
    shared: &App,
    id: &str,
    intent: Intent,
) -> Result<Stopped, Error> {
    if shared.queue.remove(id) {
        return Ok(Stopped::Dequeued);
    }
    let Some(control) = shared.queue.control(id) else {
        return Ok(Stopped::Idle);
    };
    control.request(intent);
    if intent == Intent::Delete {
        let deadline = Instant::now() + STOP_WAIT;
        while shared.queue.holds(id) {
            if Instant::now() >= deadline {
                return Err(Error::Conflict(format!(
                    "session {id}: its playback is still stopping; try again shortly"
                )));
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }
    Ok(Stopped::Playing)
}

/// Why a session that left the queue ends early.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum EndEarly {
    /// `POST …/cancel`.
    Cancel,
    /// `POST …/estimate`.
    Estimate,
}

/// A session taken out of the queue to end now: with 2 trials or more (played before a
/// restart) its final estimate runs; with fewer it fails with the reason.
pub(crate) fn finish_dequeued(shared: Arc<App>, id: String, why: EndEarly) -> Result<(), Error> {
    let count = shared.db.trial_count(&id)?;
    if count < 2 {
        return shared.lifecycle().fail(&id, &too_few_after_cancel(count));
    }
    // Marked as running so that a delete waits for the estimate.
    shared.set_running(
        &id,
        Some(RunningJob {
            cancel: Default::default(),
            plan: None,
            started_ms: crate::storage::now_ms(),
            done_before: count,
            needed: 0,
        }),
    );
    spawn_final_estimate(shared, id, move |shared, session| {
        let reason = match why {
            EndEarly::Cancel => format!(
                "cancelled by the client after {count} of {} trials",
                session.trials_total
            ),
            EndEarly::Estimate => format!("estimate requested after {count} trials"),
        };
        shared.lifecycle().stop(&session.id, &reason)?;
        shared.lifecycle().start_estimating(&session.id)
    });
    Ok(())
}

/// Plays a session from the queue on a thread of its own (never one of tokio's blocking
/// threads, which requests, file I/O and estimates need), publishing progressive estimates
/// as trials arrive, then its final estimate. The steps are [`crate::jobs::playback_run`]'s.
async fn play_and_estimate(shared: &Arc<App>, ticket: &Ticket) -> Result<Outcome, Error> {
    let mut run = match run::start(shared, ticket).await? {
        run::Started::Playing(run) => run,
        run::Started::Ended(outcome) => return Ok(outcome),
    };
    run.publish_resumed().await?;
    while let Some(batch) = run.next_batch().await {
        run.store(batch).await?;
        run.publish_progressive().await?;
    }
    if let Some(outcome) = run.end_playback().await? {
        return Ok(outcome);
    }
    run.estimate_final().await
}

/// After a restart: sessions in flight go back into the queue in their original order (or
/// are marked failed with a reason). This instance's heartbeat comes first, then the jobs
/// it (or a dead instance) left running are marked interrupted. With other instances on the
/// database, a session another live instance plays is left to it. A session that cannot be
/// resumed, or whose row cannot be read, fails alone: the server always starts. Then the
/// playback workers start (with `--database` the server starts the instance's loops next,
/// `jobs::instances::spawn`).
pub(crate) fn recover(shared: &Arc<App>) -> Result<(), Error> {
    shared
        .db
        .heartbeat(&shared.instance, crate::storage::now_ms())?;
    let interrupted = shared
        .db
        .interrupt_jobs(Some(&shared.instance), shared.alive_since_ms())?;
    if interrupted > 0 {
        log::info!("{interrupted} job(s) were interrupted by the last stop");
    }
    let in_flight = [
        SessionState::Created,
        SessionState::Uploaded,
        SessionState::Playing,
        SessionState::Estimating,
    ];
    let rows = shared.db.sessions_in(&in_flight)?;
    for bad in rows.unreadable {
        log::warn!("session {}: unreadable row, failed: {}", bad.id, bad.why);
        let why = format!("the server cannot read this session's row: {}", bad.why);
        if let Err(e) = shared.lifecycle().fail_unreadable(&bad.id, &why) {
            log::warn!("session {}: {e}", bad.id);
        }
    }
    for session in rows.sessions {
        resume_or_fail(shared, session);
    }
    spawn_workers(shared);
    Ok(())
}

/// Resumes one session in flight (after a restart, or adopted from a dead instance), or
/// marks it failed with the reason it cannot be.
pub(crate) fn resume_or_fail(shared: &Arc<App>, session: Session) {
    let id = session.id.clone();
    if let Err(e) = recover_one(shared, session) {
        log::warn!("session {id}: cannot resume after restart: {e}");
        let why = format!(
            "server restarted and cannot resume it: {}",
            e.client_message()
        );
        if let Err(e) = shared.lifecycle().fail(&id, &why) {
            log::warn!("session {id}: {e}");
        }
    }
}

/// The runs a session's results would count from what is stored: its trials, and the walk
/// when it has one and a calibration (results count the walk it is estimated from).
fn runs_stored(shared: &App, session: &Session) -> Result<u32, Error> {
    let walk =
        session.calibration.is_some() && shared.blobs.exists(&session.id, SessionObject::Walk);
    Ok(shared.db.trial_count(&session.id)? + u32::from(walk))
}

/// Resumes one session in flight after a restart.
fn recover_one(shared: &Arc<App>, session: Session) -> Result<(), Error> {
    let id = session.id.clone();
    if session.playback == PlaybackKind::Upload {
        if session.state == SessionState::Estimating {
            if !shared
                .db
                .claim_session(&id, &shared.instance, shared.alive_since_ms())?
            {
                log::info!("session {id}: its final estimate runs on another instance");
                return Ok(());
            }
            shared.lifecycle().resume(&id)?;
            spawn_estimate(shared.clone(), id);
        } else if shared.config.progressive_uploads
            && session.results_trials < runs_stored(shared, &session)?
        {
            // Trials arrived after the last published estimate: catch up.
            let shared = shared.clone();
            tokio::spawn(async move {
                match crate::jobs::live_session::live_session(&shared, &session).await {
                    Ok(live) => spawn_progressive(shared.clone(), live, id),
                    Err(e) => log::warn!("session {id}: cannot rebuild its trials: {e}"),
                }
            });
        }
        return Ok(());
    }
    if session.state == SessionState::Created {
        return Ok(());
    }
    // Claimed before any state moves: a session another live instance plays is its own.
    if !shared
        .db
        .claim_session(&id, &shared.instance, shared.alive_since_ms())?
    {
        log::info!("session {id}: played by another instance, left to it");
        return Ok(());
    }
    if !shared.blobs.exists(&id, SessionObject::Recording) {
        return shared
            .lifecycle()
            .fail(&id, "server restarted and the recording is missing");
    }
    log::info!("session {id}: back in the playback queue after restart");
    if session.allows(Step::StartPlaying) {
        enqueue(shared, &session, Begin::Start)?;
    } else {
        shared.lifecycle().resume(&id)?;
        enqueue(shared, &session, Begin::Resume)?;
    }
    Ok(())
}
