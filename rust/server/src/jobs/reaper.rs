//! The lease reaper of remote playback: a host that stops heartbeating loses its leases after
//! `lease_timeout`, and their trials are offered to the other phones (or given up after
//! `MAX_ATTEMPTS`). Each expiry counts as a failure of the phone that held it.

use std::sync::Arc;
use std::time::Duration;

use crate::app_state::App;
use crate::storage::now_ms;
use crate::storage::workers::{Requeued, TrialFailure};

/// How often leases are checked: a quarter of the lease, between 50 ms and 5 s.
fn period(lease: Duration) -> Duration {
    (lease / 4).clamp(Duration::from_millis(50), Duration::from_secs(5))
}

/// Starts the reaper; it ends when the server stops.
pub(crate) fn spawn(shared: Arc<App>) {
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(period(shared.config.lease_timeout));
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        while !shared.stopping() {
            tick.tick().await;
            let shared = shared.clone();
            let reaped = tokio::task::spawn_blocking(move || reap(&shared)).await;
            if let Ok(Err(e)) = reaped {
                log::warn!("lease reaper: {e}");
            }
        }
    });
}

fn reap(shared: &App) -> Result<(), crate::error::Error> {
    let expired = shared.workers.expire(now_ms())?;
    for lease in &expired {
        let host = shared
            .workers
            .host(&lease.host)?
            .map_or_else(|| lease.host.clone(), |h| h.name);
        let why = format!(
            "lease expired: host {host} sent no heartbeat for {} s",
            shared.config.lease_timeout.as_secs_f64()
        );
        log::warn!(
            "session {}: trial {} on {host}/{}: {why}; {}",
            lease.session,
            lease.index,
            lease.phone,
            match lease.requeued {
                Requeued::Again => "offered again",
                Requeued::GivenUp => "given up",
            }
        );
        shared
            .workers
            .phone_result(&lease.host, &lease.phone, Some(&why))?;
        if lease.requeued == Requeued::GivenUp {
            let failure = TrialFailure {
                index: lease.index,
                source: format!("{host}/{}", lease.phone),
                error: why,
                at_ms: now_ms(),
            };
            shared.workers.record_failure(&lease.session, &failure)?;
        }
    }
    if !expired.is_empty() {
        shared.board.wake();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reaper_looks_four_times_a_lease() {
        assert_eq!(period(Duration::from_secs(60)), Duration::from_secs(5));
        assert_eq!(period(Duration::from_secs(2)), Duration::from_millis(500));
        assert_eq!(period(Duration::from_millis(10)), Duration::from_millis(50));
    }
}
