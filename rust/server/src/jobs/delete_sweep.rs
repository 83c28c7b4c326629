//! Deletes that finish: removing a deleted session's bytes (by the request that deleted it,
//! or later by a sweep), and the sweep every instance runs every `delete_sweep` for deletes
//! a crash cut off between the row and the bytes (`storage::deletes`). The instance deleting
//! a session holds its delete for [`claim_for`] that period; after that any live instance's
//! sweep claims it and removes what is left. Removing bytes already gone is success, so two
//! instances finishing one delete (a slow deleter and a sweeper) never fail each other.

use std::sync::Arc;
use std::time::Duration;

use crate::app_state::App;
use crate::error::Error;
use crate::storage::Claim;

/// Unfinished deletes one sweep claims at most; more wait for the next period.
pub(crate) const PER_SWEEP: u32 = 64;

/// How long an instance holds a delete it works on: twice the sweep period, so a delete is
/// taken over at most three periods after its instance died.
pub(crate) fn claim_for(period: Duration) -> Duration {
    period * 2
}

/// The claim of this instance on a delete from now on.
pub(crate) fn claim(shared: &App) -> Claim<'_> {
    let hold = claim_for(shared.config.delete_sweep).as_millis() as i64;
    Claim {
        instance: &shared.instance,
        until_ms: crate::storage::now_ms() + hold,
    }
}

/// Removes deleted session `id`'s bytes and its playback hosts' leases, then forgets its
/// unfinished delete. On an error the delete stays recorded: a sweep tries again once the
/// claim lapses.
pub(crate) fn finish(shared: &App, id: &str) -> Result<(), Error> {
    shared.blobs.remove_session(id)?;
    shared.workers.forget(id)?;
    shared.db.finish_delete(id)
}

/// One sweep: claims the unfinished deletes whose claim lapsed and finishes them; how many
/// it finished.
pub(crate) fn sweep(shared: &App) -> Result<usize, Error> {
    let now = crate::storage::now_ms();
    let ids = shared
        .db
        .claim_unfinished_deletes(claim(shared), now, PER_SWEEP)?;
    let mut finished = 0;
    for id in ids {
        match finish(shared, &id) {
            Ok(()) => {
                log::info!("session {id}: the bytes its interrupted delete left are removed");
                finished += 1;
            }
            Err(e) => log::warn!("session {id}: its interrupted delete is left for later: {e}"),
        }
    }
    Ok(finished)
}

/// Sweeps at start and then every `delete_sweep`, until the server stops.
pub(crate) fn spawn(shared: Arc<App>) {
    tokio::spawn(async move {
        while !shared.stopping() {
            if let Err(e) = sweep(&shared) {
                log::warn!("delete sweep: {e}");
            }
            tokio::time::sleep(shared.config.delete_sweep).await;
        }
    });
}
