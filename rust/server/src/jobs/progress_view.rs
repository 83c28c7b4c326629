//! Where a session stands in its player's queue and playback, as every instance answers it.
//! The queue and the running jobs live in the memory of the instance that plays the session;
//! with several instances on one database (`--database`) that instance publishes, for each
//! session it holds, a small JSON view on the session's row (`sessions.progress_view`): the
//! queue position while it waits, and while it plays when playback started (ms since the
//! epoch) and how long the plan expects it to take. Another instance asked for the session's
//! status reads that view, so `queue_position`, `progress` and `eta_s` are the same whichever
//! instance a client asks.
//!
//! Bounds: the views are looked at every [`EVERY`] and a view is written only when it changed
//! (one `UPDATE` per changed session); the ETA is worked out when read from the published
//! start, so it runs down between writes. A queue position read elsewhere is at most
//! [`EVERY`] (plus a write) old. The write names its player, so an instance that lost the
//! session to an adopter cannot overwrite the adopter's view, and an adoption clears the
//! dead player's view (`InstanceStore::claim_session`).

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::app_state::{App, RunningJob};
use crate::error::Error;

/// How often a clustered instance looks for changed views to publish.
pub(crate) const EVERY: Duration = Duration::from_secs(1);

/// A session's place in its player's queue and playback.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct ProgressView {
    /// Where it waits for a playback worker (1: next); absent when not queued.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub queue_position: Option<usize>,
    /// Its playback's timing; absent when not playing or when nothing predicts it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub playing: Option<PlayingView>,
}

/// A playing session's timing, as its playback plan predicts it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct PlayingView {
    /// When this run of playback started (ms since the epoch, the player's clock).
    pub started_ms: i64,
    /// Seconds the plan expects this run to take (d·⌈T/D⌉).
    pub expected_s: f64,
    /// Trials stored before this run started.
    pub done_before: u32,
    /// Trials this run plays.
    pub needed: u32,
}

impl PlayingView {
    /// The timing of `job`, when its plan predicts one (phones on this host play it).
    pub(crate) fn of(job: &RunningJob) -> Option<PlayingView> {
        let plan = job.plan.filter(|plan| plan.devices > 0)?;
        Some(PlayingView {
            started_ms: job.started_ms,
            expected_s: plan.seconds_for(job.needed),
            done_before: job.done_before,
            needed: job.needed,
        })
    }

    /// Seconds since playback started, at `now_ms`.
    pub(crate) fn elapsed_s(&self, now_ms: i64) -> f64 {
        (now_ms.saturating_sub(self.started_ms)).max(0) as f64 / 1000.0
    }
}

/// This instance's view of session `id`, if it holds the session (queued or running here).
fn local(shared: &App, id: &str) -> Option<ProgressView> {
    let queue_position = shared.queue.position(id);
    let running = shared.running(id);
    if queue_position.is_none() && running.is_none() {
        return None;
    }
    Some(ProgressView {
        queue_position,
        playing: running.as_ref().and_then(PlayingView::of),
    })
}

/// Session `id`'s view: this instance's own when it holds the session, else (clustered) the
/// one its player published; empty when neither knows.
pub(crate) fn of_session(shared: &App, id: &str) -> Result<ProgressView, Error> {
    if let Some(view) = local(shared, id) {
        return Ok(view);
    }
    if !shared.clustered() {
        return Ok(ProgressView::default());
    }
    match shared.db.published_progress(id)? {
        Some((player, text)) if player != shared.instance => Ok(serde_json::from_str(&text)
            .unwrap_or_else(|e| {
                log::warn!("session {id}: unreadable progress from instance {player}: {e}");
                ProgressView::default()
            })),
        _ => Ok(ProgressView::default()),
    }
}

/// Every view this instance holds, serialised as published.
fn local_views(shared: &App) -> HashMap<String, String> {
    let mut views: HashMap<String, ProgressView> = HashMap::new();
    for (id, position) in shared.queue.positions() {
        views.entry(id).or_default().queue_position = Some(position);
    }
    for (id, job) in shared.running_all() {
        views.entry(id).or_default().playing = PlayingView::of(&job);
    }
    views
        .into_iter()
        .map(|(id, view)| {
            let text = serde_json::to_string(&view).unwrap_or_else(|_| "{}".to_string());
            (id, text)
        })
        .collect()
}

/// Writes the views that changed since `published` (what was last written) and clears those
/// of sessions that left this instance; `published` becomes what the database now holds.
fn publish_changes(shared: &App, published: &mut HashMap<String, String>) -> Result<(), Error> {
    let now = local_views(shared);
    let gone: Vec<String> = published
        .keys()
        .filter(|id| !now.contains_key(*id))
        .cloned()
        .collect();
    for id in gone {
        shared.db.publish_progress(&id, &shared.instance, None)?;
        published.remove(&id);
    }
    for (id, text) in now {
        if published.get(&id) != Some(&text) {
            shared
                .db
                .publish_progress(&id, &shared.instance, Some(&text))?;
            published.insert(id, text);
        }
    }
    Ok(())
}

/// Starts the publishing loop of a clustered instance (until the server stops).
pub(crate) fn spawn(shared: Arc<App>) {
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(EVERY);
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        let mut published = HashMap::new();
        while !shared.stopping() {
            tick.tick().await;
            if let Err(e) = publish_changes(&shared, &mut published) {
                // Written again on the next round: what failed is not marked published.
                log::warn!("instance {}: progress not published: {e}", shared.instance);
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_view_reads_back_as_written_and_an_empty_one_is_empty_json() {
        let view = ProgressView {
            queue_position: Some(3),
            playing: Some(PlayingView {
                started_ms: 1_700_000_000_123,
                expected_s: 12.5,
                done_before: 4,
                needed: 6,
            }),
        };
        let text = serde_json::to_string(&view).unwrap();
        assert_eq!(serde_json::from_str::<ProgressView>(&text).unwrap(), view);
        assert_eq!(
            serde_json::to_string(&ProgressView::default()).unwrap(),
            "{}"
        );
        let playing = view.playing.unwrap();
        assert_eq!(playing.elapsed_s(1_700_000_002_623), 2.5);
        // A clock behind the player's reads no negative time.
        assert_eq!(playing.elapsed_s(1_600_000_000_000), 0.0);
    }
}
