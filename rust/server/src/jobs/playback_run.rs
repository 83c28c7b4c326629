//! One playback job's steps, each its own method: start (plan, mark running, the playback
//! thread), store each arriving batch of trials, publish a progressive estimate (and stop
//! adaptively), end playback (why it stopped, or why there is nothing to estimate), and the
//! final estimate. `jobs::play_and_estimate` runs them in this order.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use sitar_core::ErrorClass;
use tokio::sync::{mpsc, oneshot};

use crate::app_state::{App, RunningJob};
use crate::error::Error;
use crate::estimate::held_trials::Purpose;
use crate::estimate::live_sessions::LiveSession;
use crate::estimate::publishing::{self, Published};
use crate::ingest::trials::{self, Arrival};
use crate::model::Session;
use crate::playback::queue::{Begin, Intent, JobControl, Ticket};
use crate::playback::{PlaybackJob, TrialOutput, indices_to_play};
use crate::storage::keys::SessionObject;
use crate::storage::workers::TrialFailure;

/// Pauses between attempts to store a trial while the metadata store fails: 31.5 s in all,
/// longer than a Postgres restart takes the pool to reconnect (`RECONNECT_WAIT`, 20 s).
const STORE_RETRY_PAUSES: [Duration; 6] = [
    Duration::from_millis(500),
    Duration::from_secs(1),
    Duration::from_secs(2),
    Duration::from_secs(4),
    Duration::from_secs(8),
    Duration::from_secs(16),
];

/// How a job ended.
pub(crate) enum Outcome {
    Done,
    /// The server is stopping: the session stays in flight for the next start.
    Interrupted,
    /// A delete stopped it: nothing is published, the session goes next.
    Deleted,
    /// Another instance plays the session now (it adopted it while this one was silent past
    /// the instance timeout): this job leaves it to that one, changing nothing.
    Adopted,
}

/// Publishes the estimate over the live session's trials if any arrived since the last.
pub(crate) async fn publish(
    shared: &Arc<App>,
    live: &Arc<LiveSession>,
    id: &str,
    purpose: Purpose,
) -> Result<Option<Published>, Error> {
    let (shared, id) = (shared.clone(), id.to_string());
    live.publish(purpose, move |published| {
        let lock = shared.session_lock(&id);
        let _held = lock.blocking_lock();
        shared.session(&id)?;
        crate::estimate::results_files::write(&*shared.blobs, &shared.lifecycle(), &id, published)
    })
    .await
}

/// The reason a session cancelled after `count` trials fails with (an estimate needs 2).
pub(crate) fn too_few_after_cancel(count: u32) -> String {
    format!("cancelled by the client after {count} trial(s); an estimate needs 2")
}

/// What [`start`] came to.
pub(crate) enum Started<'a> {
    /// Trials are being played.
    Playing(Box<Run<'a>>),
    /// Nothing to play: the server stops, or the session is being deleted.
    Ended(Outcome),
}

/// A playback in progress.
pub(crate) struct Run<'a> {
    shared: &'a Arc<App>,
    id: &'a str,
    control: &'a JobControl,
    cancel: Arc<AtomicBool>,
    session: Session,
    live: Arc<LiveSession>,
    /// Trials as the phones finish them.
    trials: mpsc::UnboundedReceiver<TrialOutput>,
    /// The playback thread's answer once it ends.
    played: Option<oneshot::Receiver<Result<(), Error>>>,
    /// Trials stored before this run (a resumed session's).
    done_before: u32,
    /// Each published estimate's trial count and classes, for adaptive stopping.
    history: Vec<(u32, BTreeMap<i64, ErrorClass>)>,
    /// Why playback stopped before its last trial, once it did.
    stop_reason: Option<String>,
}

/// Marks the job running, plans it, starts the session playing and its playback thread.
pub(crate) async fn start<'a>(
    shared: &'a Arc<App>,
    ticket: &'a Ticket,
) -> Result<Started<'a>, Error> {
    let (id, control) = (ticket.id.as_str(), &*ticket.control);
    let cancel = control.cancel.clone();
    // Marked running before anything else: a delete now waits for this job.
    let running = |plan, done_before, needed| RunningJob {
        cancel: cancel.clone(),
        plan,
        started_ms: crate::storage::now_ms(),
        done_before,
        needed,
    };
    shared.set_running(id, Some(running(None, 0, 0)));
    if shared.stopping() {
        return Ok(Started::Ended(Outcome::Interrupted));
    }
    if control.intent() == Intent::Delete {
        return Ok(Started::Ended(Outcome::Deleted));
    }
    let session = shared.session(id)?;
    let backend = shared.backend(session.playback);
    // One row per stored trial: their count, and the playback indices a resume skips.
    let stored_trials = shared.db.trials_in_order(id)?;
    let done_before = stored_trials.len() as u32;
    let stored: BTreeSet<u32> = stored_trials.into_iter().map(|(_, index)| index).collect();
    let needed = session.trials_total.saturating_sub(done_before);
    let recording = shared.blobs.local_file(id, SessionObject::Recording);
    let plan = {
        let (backend, recording) = (backend.clone(), recording.clone());
        tokio::task::spawn_blocking(move || backend.plan(&recording, needed))
            .await
            .map_err(|e| Error::Internal(format!("plan task: {e}")))??
    };
    shared.set_running(id, Some(running(Some(plan), done_before, needed)));
    if ticket.begin == Begin::Start {
        shared.lifecycle().start_playing(id)?;
    }
    let live = crate::jobs::live_session::live_session(shared, &session).await?;
    let (tx, rx) = mpsc::unbounded_channel::<TrialOutput>();
    let job = PlaybackJob {
        session: id.to_string(),
        recording,
        work_dir: shared.blobs.playback_folder(id),
        indices: indices_to_play(&stored, needed),
        cancel: cancel.clone(),
    };
    let (played_tx, played_rx) = oneshot::channel();
    if cancel.load(Ordering::SeqCst) {
        // Stopped before it began: nothing to play.
        drop(tx);
        let _ = played_tx.send(Ok(()));
    } else {
        std::thread::Builder::new()
            .name(format!("sitar-play-{id}"))
            .spawn(move || {
                let sink = move |trial: TrialOutput| {
                    let _ = tx.send(trial);
                };
                let _ = played_tx.send(backend.play(&job, &sink));
            })
            .map_err(|e| Error::Internal(format!("playback thread: {e}")))?;
    }
    if shared.stopping() {
        cancel.store(true, Ordering::SeqCst);
    }
    Ok(Started::Playing(Box::new(Run {
        shared,
        id,
        control,
        cancel,
        session,
        live,
        trials: rx,
        played: Some(played_rx),
        done_before,
        history: Vec::new(),
        stop_reason: None,
    })))
}

impl Run<'_> {
    /// Playback stops before its last trial for `reason` (recorded once).
    fn stop(&mut self, reason: String) -> Result<(), Error> {
        self.shared.lifecycle().stop(self.id, &reason)?;
        self.stop_reason = Some(reason);
        self.cancel.store(true, Ordering::SeqCst);
        Ok(())
    }

    /// A resumed session with 2 trials or more shows their estimate at once.
    pub(crate) async fn publish_resumed(&mut self) -> Result<(), Error> {
        if self.done_before >= 2
            && let Some(p) = publish(self.shared, &self.live, self.id, Purpose::Progressive).await?
        {
            self.history.push((p.trials, p.classes));
        }
        Ok(())
    }

    /// The trials that arrived since the last batch (those that queued up while the last
    /// estimate ran go in together); `None` once playback ends. While the session is being
    /// deleted, what the phones still deliver is dropped.
    pub(crate) async fn next_batch(&mut self) -> Option<Vec<TrialOutput>> {
        loop {
            let first = self.trials.recv().await?;
            if self.control.intent() == Intent::Delete {
                continue;
            }
            let mut batch = vec![first];
            while let Ok(more) = self.trials.try_recv() {
                batch.push(more);
            }
            return Some(batch);
        }
    }

    /// Parses and stores each trial of `batch`; at the memory bound, playback stops with
    /// what is there. A trial the metadata store could not take (Postgres restarting, a
    /// transaction lost with its connection) is stored again after a pause, for up to
    /// [`STORE_RETRY_PAUSES`]: a remote trial was already taken from its lease, so giving up
    /// on it would lose a trial the phone played.
    pub(crate) async fn store(&mut self, batch: Vec<TrialOutput>) -> Result<(), Error> {
        for trial in batch {
            let bytes = trial.tum.as_bytes();
            let mut pauses = STORE_RETRY_PAUSES.iter();
            // The key makes a second attempt find the first one's row if that committed (API
            // trials, the only others with keys, never go to a played session).
            let key = format!("play:{}", trial.index);
            let mut retried = false;
            let stored = loop {
                let arrival = Arrival {
                    key: Some(&key),
                    play_index: Some(trial.index),
                    source: &trial.source,
                    retried,
                };
                let stored = trials::parse_trial(bytes, "trial").and_then(|parsed| {
                    trials::store_trial(
                        self.shared.stores(),
                        &self.live,
                        self.id,
                        arrival,
                        bytes,
                        parsed,
                    )
                });
                match (&stored, pauses.next()) {
                    (Err(e @ Error::Database(_)), Some(pause)) if !self.shared.stopping() => {
                        log::warn!(
                            "session {}: trial {} not stored yet ({e}); trying again in {} ms",
                            self.id,
                            trial.index,
                            pause.as_millis()
                        );
                        tokio::time::sleep(*pause).await;
                        retried = true;
                    }
                    _ => break stored,
                }
            };
            match stored {
                Ok(_) => {}
                Err(e @ (Error::TooLarge { .. } | Error::Busy(_)))
                    if self.stop_reason.is_none() =>
                {
                    let count = self.shared.db.trial_count(self.id)?;
                    self.stop(format!("memory bound: {e} (stopped after {count} trials)"))?;
                }
                Err(e) => {
                    log::warn!(
                        "session {}: trial {} from {} failed: {e}",
                        self.id,
                        trial.index,
                        trial.source
                    );
                    // Shown in the session's status (`failed_trials`), not dropped unseen.
                    let failure = TrialFailure {
                        index: trial.index,
                        source: trial.source.clone(),
                        error: e.client_message(),
                        at_ms: crate::storage::now_ms(),
                    };
                    self.shared.workers.record_failure(self.id, &failure)?;
                }
            }
        }
        Ok(())
    }

    /// From the 2nd trial on (the 1st, with the phone's walk as the live run), a progressive
    /// estimate; with adaptive stopping, playback stops once no window changed class over the
    /// last k trials.
    pub(crate) async fn publish_progressive(&mut self) -> Result<(), Error> {
        let count = self.shared.db.trial_count(self.id)?;
        let least = if self.live.has_walk() { 1 } else { 2 };
        if count < least || self.stop_reason.is_some() {
            return Ok(());
        }
        let Some(p) = publish(self.shared, &self.live, self.id, Purpose::Progressive).await? else {
            return Ok(());
        };
        self.history.push((p.trials, p.classes));
        let total = self.session.trials_total;
        let adaptive = self
            .session
            .adaptive_min
            .map(|min| (min.max(2), self.session.adaptive_k.max(1)));
        if let Some((min, k)) = adaptive
            && count >= min
            && count < total
            && publishing::classes_stable(&self.history, k)
        {
            self.stop(format!(
                "adaptive stop: no window changed class over the last {k} trials (stopped after {count} of {total})"
            ))?;
        }
        Ok(())
    }

    /// Waits for the playback thread and decides what follows: nothing (the server stops,
    /// the session is deleted: `Some(outcome)`), a failure (fewer than 2 trials), or the
    /// final estimate, with the reason playback stopped early recorded.
    pub(crate) async fn end_playback(&mut self) -> Result<Option<Outcome>, Error> {
        let played = match self.played.take() {
            Some(played) => played.await.map_err(|_| {
                Error::Internal("the playback thread ended without an answer".into())
            })?,
            None => Ok(()),
        };
        if self.shared.stopping() {
            return Ok(Some(Outcome::Interrupted));
        }
        let intent = self.control.intent();
        if intent == Intent::Delete {
            return Ok(Some(Outcome::Deleted));
        }
        if self.shared.clustered()
            && self.shared.db.session_player(self.id)?.as_deref() != Some(&self.shared.instance)
        {
            return Ok(Some(Outcome::Adopted));
        }
        let count = self.shared.db.trial_count(self.id)?;
        let total = self.session.trials_total;
        match played {
            Ok(()) if count < 2 && intent == Intent::Cancel => {
                return Err(Error::Playback(too_few_after_cancel(count)));
            }
            Err(e) if count < 2 => return Err(e),
            Err(e) => self.stop(format!("playback failed after {count} trials: {e}"))?,
            Ok(()) if count < 2 => {
                return Err(Error::Playback(format!(
                    "only {count} trial(s) finished; an estimate needs 2"
                )));
            }
            Ok(()) => {
                if count < total && self.stop_reason.is_none() && self.cancel.load(Ordering::SeqCst)
                {
                    let reason = match intent {
                        Intent::Cancel => {
                            format!("cancelled by the client after {count} of {total} trials")
                        }
                        _ => format!("estimate requested after {count} trials"),
                    };
                    self.stop(reason)?;
                }
            }
        }
        Ok(None)
    }

    /// The final estimate over every stored trial, published; the session is done.
    pub(crate) async fn estimate_final(self) -> Result<Outcome, Error> {
        self.shared.lifecycle().start_estimating(self.id)?;
        publish(self.shared, &self.live, self.id, Purpose::Final).await?;
        self.shared.lifecycle().finish(self.id)?;
        Ok(Outcome::Done)
    }
}
