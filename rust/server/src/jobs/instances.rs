//! This instance among others on one database (`--database`): its heartbeat, and the
//! adoption of sessions whose player died. Both loops run in the background until the server
//! stops; with the embedded default (one instance per data directory) neither runs.
//!
//! Bounds, with `T` = `--instance-timeout-s` (default 30 s): the heartbeat is renewed every
//! `T/6` (at most 5 s), the sessions in flight are scanned every `T/3` (at most 10 s), so a
//! dead instance's sessions are adopted within `T + T/3` of its last heartbeat (40 s by
//! default). A session that nobody plays (its player released it, or the upload that made it
//! in flight failed before the claim) is adopted once two scans in a row saw it so.
//!
//! An instance adopts nothing while it could not keep its own heartbeat regular over the
//! last timeout (a heartbeat failed, or came over twice its period late): whatever kept it
//! from the database — Postgres restarting, a pause of its own — kept the others too, and
//! their silence says nothing until they have had a timeout to speak again. A job whose
//! session was adopted all the same (its instance paused past the timeout) sees so within
//! a second and leaves it to the adopter (`Outcome::Adopted`).

use std::collections::HashSet;
use std::sync::Arc;
use std::sync::atomic::{AtomicI64, Ordering};
use std::time::Duration;

use crate::app_state::App;
use crate::error::Error;
use crate::jobs::playback::resume_or_fail;

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

/// Starts the heartbeat, adoption, progress and stop-request loops of a clustered instance.
pub(crate) fn spawn(shared: Arc<App>) {
    let timeout = shared.config.instance_timeout;
    let beating = shared.clone();
    let steady = Arc::new(Steadiness::new(crate::storage::now_ms(), timeout));
    let beats = steady.clone();
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(heartbeat_every(timeout));
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        while !beating.stopping() {
            tick.tick().await;
            let now = crate::storage::now_ms();
            let recorded = beating.db.heartbeat(&beating.instance, now);
            beats.beat(crate::storage::now_ms(), recorded.is_ok());
            if let Err(e) = recorded {
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
            if !steady.judges(crate::storage::now_ms()) {
                // Others' silence may be this outage's: look again once steady.
                unplayed_before.clear();
                continue;
            }
            match adopt(&adopting, &unplayed_before) {
                Ok(unplayed) => unplayed_before = unplayed,
                Err(e) => log::warn!("instance {}: adoption scan: {e}", adopting.instance),
            }
        }
    });
    crate::jobs::progress_view::spawn(shared.clone());
    crate::jobs::stop_requests::spawn(shared);
}

/// Whether this instance's own heartbeat has been regular for a whole timeout: only then
/// does it judge others dead by theirs.
pub(crate) struct Steadiness {
    /// When the last heartbeat was recorded (ms since the epoch).
    last_ok_ms: AtomicI64,
    /// Until when (ms) this instance does not judge: a timeout after its last irregular beat.
    doubtful_until_ms: AtomicI64,
    period_ms: i64,
    timeout_ms: i64,
}

impl Steadiness {
    /// Started at `now_ms` (an instance judges only a timeout after its start, too: others
    /// may have been silent because of what kept it down).
    pub(crate) fn new(now_ms: i64, timeout: Duration) -> Steadiness {
        let ms = |d: Duration| i64::try_from(d.as_millis()).unwrap_or(i64::MAX);
        let timeout_ms = ms(timeout);
        Steadiness {
            last_ok_ms: AtomicI64::new(now_ms),
            doubtful_until_ms: AtomicI64::new(now_ms.saturating_add(timeout_ms)),
            period_ms: ms(heartbeat_every(timeout)),
            timeout_ms,
        }
    }

    /// A heartbeat ended at `now_ms`, recorded or not.
    pub(crate) fn beat(&self, now_ms: i64, recorded: bool) {
        let late = now_ms - self.last_ok_ms.load(Ordering::SeqCst) > 2 * self.period_ms;
        if recorded {
            self.last_ok_ms.store(now_ms, Ordering::SeqCst);
        }
        if !recorded || late {
            let until = now_ms.saturating_add(self.timeout_ms);
            self.doubtful_until_ms.fetch_max(until, Ordering::SeqCst);
        }
    }

    /// Whether at `now_ms` this instance may take others' silence for death.
    pub(crate) fn judges(&self, now_ms: i64) -> bool {
        now_ms >= self.doubtful_until_ms.load(Ordering::SeqCst)
    }
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
    fn an_instance_whose_own_heartbeat_faltered_judges_nobody_for_a_timeout() {
        let timeout = Duration::from_secs(3);
        let steady = Steadiness::new(0, timeout);
        // Not in its first timeout: others may have been down with it.
        assert!(!steady.judges(2_999));
        for t in (500..=4_000).step_by(500) {
            steady.beat(t, true);
        }
        assert!(steady.judges(4_000));
        // A beat that failed (the database restarting): a timeout of doubt from then.
        steady.beat(4_500, false);
        steady.beat(5_000, true);
        assert!(!steady.judges(7_499));
        assert!(steady.judges(7_500));
        // A beat over twice its period late (this instance paused), though recorded.
        steady.beat(7_000, true);
        steady.beat(8_100, true);
        assert!(!steady.judges(11_099));
        assert!(steady.judges(11_100));
    }

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
