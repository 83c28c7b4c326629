//! This instance among others on one database (`--database`): its heartbeat, and the
//! adoption of sessions whose player died. Both loops run in the background until the server
//! stops; with the embedded default (one instance per data directory) neither runs.
//!
//! Bounds, with `T` = `--instance-timeout-s` (default 30 s): the heartbeat is renewed every
//! `T/6` (at most 5 s), the sessions in flight are scanned every `T/3` (at most 10 s), so a
//! dead instance's sessions are adopted within `T + T/3` of its last heartbeat (40 s by
//! default). A session that nobody plays (its player released it, or the upload that made it
//! in flight failed before the claim) is adopted once two scans in a row saw it so.

use std::collections::HashSet;
use std::sync::Arc;
use std::time::Duration;

use crate::Error;
use crate::app_state::App;
use crate::playback::jobs::resume_or_fail;

/// The shortest pause between two heartbeats or two scans (for tests' short timeouts).
const FLOOR: Duration = Duration::from_millis(100);

/// How often the heartbeat is renewed for `timeout`: six times within it, at most every 5 s.
pub(crate) fn heartbeat_every(timeout: Duration) -> Duration {
    (timeout / 6).clamp(FLOOR, Duration::from_secs(5))
}

/// How often the sessions in flight are scanned for adoption: three times within `timeout`,
/// at most every 10 s.
pub(crate) fn scan_every(timeout: Duration) -> Duration {
    (timeout / 3).clamp(FLOOR, Duration::from_secs(10))
}

/// Starts the heartbeat, adoption and stop-request loops of a clustered instance.
pub(crate) fn spawn(shared: Arc<App>) {
    let timeout = shared.config.instance_timeout;
    let beating = shared.clone();
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(heartbeat_every(timeout));
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        while !beating.stopping() {
            tick.tick().await;
            let now = crate::storage::now_ms();
            if let Err(e) = beating.db.heartbeat(&beating.instance, now) {
                log::warn!("instance {}: heartbeat not recorded: {e}", beating.instance);
            }
        }
    });
    let adopting = shared.clone();
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(scan_every(timeout));
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        let mut unplayed_before = HashSet::new();
        while !adopting.stopping() {
            tick.tick().await;
            if adopting.stopping() {
                break;
            }
            match adopt(&adopting, &unplayed_before) {
                Ok(unplayed) => unplayed_before = unplayed,
                Err(e) => log::warn!("instance {}: adoption scan: {e}", adopting.instance),
            }
        }
    });
    crate::playback::stop_requests::spawn(shared);
}

/// One scan: claims each session in flight whose player is dead (or that nobody played in
/// the scan before too), interrupts the dead players' running jobs and resumes what it
/// claimed as a restart would. Returns the sessions nobody plays, for the next scan.
pub(crate) fn adopt(
    shared: &Arc<App>,
    unplayed_before: &HashSet<String>,
) -> Result<HashSet<String>, Error> {
    let alive_since = shared.alive_since_ms();
    let mut unplayed_now = HashSet::new();
    for (id, player) in shared.db.unplayed_sessions(alive_since)? {
        if player.is_none() && !unplayed_before.contains(&id) {
            unplayed_now.insert(id);
            continue;
        }
        if !shared
            .db
            .claim_session(&id, &shared.instance, alive_since)?
        {
            continue;
        }
        let from = player.as_deref().unwrap_or("no instance");
        log::info!(
            "session {id}: adopted from {from} (silent for over {} s)",
            shared.config.instance_timeout.as_secs_f64()
        );
        let interrupted = shared.db.interrupt_jobs(None, alive_since)?;
        if interrupted > 0 {
            log::info!("{interrupted} job(s) of dead instances were interrupted");
        }
        match shared.db.session(&id)? {
            Some(session) => resume_or_fail(shared, session),
            None => log::info!("session {id}: deleted meanwhile"),
        }
    }
    Ok(unplayed_now)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_loops_run_within_the_timeout_and_never_spin() {
        let default = crate::config::INSTANCE_TIMEOUT;
        assert_eq!(heartbeat_every(default), Duration::from_secs(5));
        assert_eq!(scan_every(default), Duration::from_secs(10));
        let short = Duration::from_secs(3);
        assert_eq!(heartbeat_every(short), Duration::from_millis(500));
        assert_eq!(scan_every(short), Duration::from_secs(1));
        assert_eq!(heartbeat_every(Duration::ZERO), FLOOR);
        assert_eq!(
            scan_every(Duration::from_secs(3600)),
            Duration::from_secs(10)
        );
    }
}
