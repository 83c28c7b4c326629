//! Deleting sessions: `DELETE /v1/sessions/{id}` and the retention sweep, the ways to free
//! the data directory. A session is deleted whole (its row, trials, jobs, folder and
//! trials in memory) or not at all, and never while a job or an estimate works on it: its
//! rows go in one transaction, which records its bytes as still to remove; the bytes go
//! next, and if the instance dies first, any live instance's sweep removes them
//! (`delete_sweep`).

use std::sync::Arc;
use std::time::Duration;

use crate::app_state::App;
use crate::error::Error;

/// How long a delete waits for a request that is writing into the session.
const WRITER_WAIT: Duration = Duration::from_secs(5);

/// Deletes session `id` unless a job works on it (409) or it does not exist (404).
pub(crate) async fn delete_idle(shared: &Arc<App>, id: &str) -> Result<(), Error> {
    delete(shared, id, false).await
}

/// Deletes sim or adb session `id` whose playback was stopped for it (taken out of the
/// queue, or its job ended): its state may still say `uploaded` or `playing`.
pub(crate) async fn delete_stopped(shared: &Arc<App>, id: &str) -> Result<(), Error> {
    delete(shared, id, true).await
}

async fn delete(shared: &Arc<App>, id: &str, playback_stopped: bool) -> Result<(), Error> {
    let session = shared.session(id)?;
    let id = session.id;
    // A progressive estimate publishes under the session lock: let a running one end first.
    if let Some(live) = shared.live.get(&id) {
        let deadline = tokio::time::Instant::now() + WRITER_WAIT;
        while live.estimating() && tokio::time::Instant::now() < deadline {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    }
    // A finished session's scene may be being built ahead in a scratch folder: let it end,
    // so that nothing of the session is written after it is gone.
    let deadline = tokio::time::Instant::now() + WRITER_WAIT;
    while crate::report::scene::preparing(&id) && tokio::time::Instant::now() < deadline {
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let lock = shared.session_lock(&id);
    let Ok(_held) = tokio::time::timeout(WRITER_WAIT, lock.lock()).await else {
        return Err(Error::Conflict(format!(
            "session {id} is receiving an upload; try again when it ends"
        )));
    };
    // Read again under the lock: the state may have moved on meanwhile.
    let session = shared.session(&id)?;
    let stopped = playback_stopped && session.playback != crate::model::PlaybackKind::Upload;
    if !(session.is_idle() || stopped) || shared.running(&id).is_some() || shared.queue.holds(&id) {
        return Err(Error::Conflict(format!(
            "session {id} is {}: a job works on it; delete it once it is done or failed",
            session.state
        )));
    }
    if shared.live.get(&id).is_some_and(|live| live.estimating()) {
        return Err(Error::Conflict(format!(
            "session {id}: an estimate of its trials runs (a job works on it); try again shortly"
        )));
    }
    // Gone for every instance at once; another instance's delete that got here first
    // leaves nothing to delete: a 404, as for any unknown id.
    if !shared
        .db
        .delete_session(&id, crate::jobs::delete_sweep::claim(shared))?
    {
        return Err(Error::NotFound(format!("no session {id:?}")));
    }
    shared.live.remove(&id);
    shared.forget_session_lock(&id);
    crate::report::scene::forget(&*shared.blobs, &id);
    log::info!("session {id} deleted; its bytes go next");
    if let Some(pause) = shared.config.delete_pause {
        tokio::time::sleep(pause).await;
    }
    if let Err(e) = crate::jobs::delete_sweep::finish(shared, &id) {
        log::warn!("session {id}: its bytes are left for the delete sweep: {e}");
    }
    Ok(())
}

/// With a retention set, deletes sessions past it (finished that long ago, or created that
/// long ago and idle since), looking every `retention_sweep`, until the server stops.
pub(crate) fn spawn_retention_sweep(shared: Arc<App>) {
    let Some(retention) = shared.config.retention else {
        return;
    };
    tokio::spawn(async move {
        while !shared.stopping() {
            let cutoff =
                crate::storage::now_ms() - retention.as_millis().min(i64::MAX as u128) as i64;
            match shared.db.expired(cutoff) {
                Ok(ids) => {
                    for id in ids {
                        match delete_idle(&shared, &id).await {
                            Ok(()) => log::info!("session {id}: past the retention, deleted"),
                            Err(e) => log::warn!("session {id}: past the retention: {e}"),
                        }
                    }
                }
                Err(e) => log::warn!("retention sweep: {e}"),
            }
            tokio::time::sleep(shared.config.retention_sweep).await;
        }
    });
}
