//! Estimate, cancel and delete across instances. The instance a client asks records the
//! request on the session's row when another instance plays it; the player looks for
//! requests on its sessions every [`POLL`] and stops the session as if the client had asked
//! it: a queued one leaves the queue, a playing one's job is told (its backends look at the
//! cancel flag between trials). A delete waits (at most [`DELETE_WAIT`]) until the player
//! has let the session go, then deletes it itself.

use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use crate::app_state::App;
use crate::error::Error;
use crate::jobs::playback::{self as jobs, EndEarly, Stopped, finish_dequeued};
use crate::playback::queue::Intent;
use crate::storage::StopRequest;

/// How often an instance looks for stop requests on the sessions it plays.
pub(crate) const POLL: Duration = Duration::from_millis(500);

/// How long a delete waits for another instance to stop the session's playback.
pub(crate) const DELETE_WAIT: Duration = Duration::from_secs(15);

/// Stops session `id`'s playback for `intent` wherever it plays: on this instance as
/// [`jobs::stop_playback`] does, else through the database on the instance that plays it
/// (`Playing`: it was told; for a delete, it has let the session go).
pub(crate) async fn stop_anywhere(
    shared: &App,
    id: &str,
    intent: Intent,
) -> Result<Stopped, Error> {
    let request = match intent {
        Intent::Run => None,
        Intent::Cancel => Some(StopRequest::Cancel),
        Intent::Delete => Some(StopRequest::Delete),
    };
    match jobs::stop_playback(shared, id, intent).await? {
        Stopped::Idle if request.is_some() && ask_elsewhere(shared, id, request).await? => {
            Ok(Stopped::Playing)
        }
        stopped => Ok(stopped),
    }
}

/// When another instance plays session `id`: records `request` for it and, for a delete,
/// waits until it let the session go. False when no other instance plays it.
pub(crate) async fn ask_elsewhere(
    shared: &App,
    id: &str,
    request: Option<StopRequest>,
) -> Result<bool, Error> {
    let Some(request) = request else {
        return Ok(false);
    };
    if !shared.clustered() {
        return Ok(false);
    }
    let Some(player) = shared.db.session_player(id)? else {
        return Ok(false);
    };
    if player == shared.instance {
        return Ok(false);
    }
    shared.db.request_stop(id, request)?;
    if request == StopRequest::Delete && !shared.db.is_alive(&player, shared.alive_since_ms())? {
        // Its adopter will stop it (the request stays on the row); until then it is in flight.
        return Err(Error::Conflict(format!(
            "session {id}: instance {player}, which played it, is silent; another instance \
             takes it over within {} s and stops it: try again then",
            shared.config.instance_timeout.as_secs() * 4 / 3 + 1
        )));
    }
    log::info!(
        "session {id}: {} asked of instance {player}, which plays it",
        request.as_str()
    );
    if request == StopRequest::Delete {
        let deadline = Instant::now() + DELETE_WAIT;
        while let Some(player) = shared.db.session_player(id)? {
            if Instant::now() >= deadline {
                return Err(Error::Conflict(format!(
                    "session {id}: its playback on instance {player} is still stopping; \
                     try again shortly"
                )));
            }
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    }
    Ok(true)
}

/// Looks for stop requests on this instance's sessions every [`POLL`] until the server stops.
pub(crate) fn spawn(shared: Arc<App>) {
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(POLL);
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        while !shared.stopping() {
            tick.tick().await;
            match shared.db.stop_requests(&shared.instance) {
                Ok(requests) => {
                    for (id, request) in requests {
                        carry_out(&shared, &id, request);
                    }
                }
                Err(e) => log::warn!("instance {}: stop requests: {e}", shared.instance),
            }
        }
    });
}

/// Stops session `id` for `request` as this instance's own routes would. Seen again on the
/// next poll while the session is still this instance's, so each step is idempotent.
fn carry_out(shared: &Arc<App>, id: &str, request: StopRequest) {
    if shared.queue.remove(id) {
        log::info!("session {id}: left the queue ({} asked)", request.as_str());
        let done = match request {
            StopRequest::Estimate => {
                finish_dequeued(shared.clone(), id.to_string(), EndEarly::Estimate)
            }
            StopRequest::Cancel => {
                finish_dequeued(shared.clone(), id.to_string(), EndEarly::Cancel)
            }
            // The asking instance deletes it once it is let go.
            StopRequest::Delete => shared.db.release_session(id, &shared.instance),
        };
        if let Err(e) = done {
            log::warn!("session {id}: {e}");
        }
    } else if let Some(control) = shared.queue.control(id) {
        match request {
            // As the estimate route does on the player: playback stops, the job estimates.
            StopRequest::Estimate => control.cancel.store(true, Ordering::SeqCst),
            StopRequest::Cancel => control.request(Intent::Cancel),
            StopRequest::Delete => control.request(Intent::Delete),
        }
    }
}
