//! `DELETE /v1/sessions/{id}`, and the retention sweep: the ways to free the
//! data directory. A session is deleted whole (its row, trials, jobs and
//! folder) or not at all, and never while a job works on it.

use std::sync::Arc;
use std::time::Duration;

use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::Response;
use serde_json::json;

use crate::Error;
use crate::routes::{json_response, session_row};
use crate::state::Shared;

/// How long a delete waits for a request that is writing into the session.
const WRITER_WAIT: Duration = Duration::from_secs(5);

pub(crate) async fn delete_session(
    State(shared): State<Arc<Shared>>,
    Path(id): Path<String>,
) -> Result<Response, Error> {
    delete_idle(&shared, &id).await?;
    Ok(json_response(
        StatusCode::OK,
        &json!({"id": id, "deleted": true}).to_string(),
    ))
}

/// Deletes session `id` unless a job works on it (409) or it does not exist (404).
pub(crate) async fn delete_idle(shared: &Arc<Shared>, id: &str) -> Result<(), Error> {
    let id = id.to_string();
    let row = session_row(shared, &id)?;
    let lock = shared.session_lock(&row.id);
    let Ok(_held) = tokio::time::timeout(WRITER_WAIT, lock.lock()).await else {
        return Err(Error::Conflict(format!(
            "session {id} is receiving an upload; try again when it ends"
        )));
    };
    // Read again under the lock: the state may have moved on meanwhile.
    let row = session_row(shared, &id)?;
    let idle = match row.state.as_str() {
        "created" | "done" | "failed" => true,
        // An `upload` session waits for trials; any other has its playback job.
        "uploaded" => row.playback == "upload",
        _ => false,
    };
    if !idle || shared.live(&id).is_some() {
        return Err(Error::Conflict(format!(
            "session {id} is {}: a job works on it; delete it once it is done or failed",
            row.state
        )));
    }
    let trash = shared.files.trash_session_dir(&id)?;
    if let Err(e) = shared.db.delete_session(&id) {
        if let Some(trash) = &trash {
            shared.files.restore_session_dir(&id, trash)?;
        }
        return Err(e);
    }
    shared.forget_session_lock(&id);
    if let Some(trash) = trash {
        // Already out of sight; what a failure leaves, the next start removes.
        if let Err(e) = std::fs::remove_dir_all(&trash) {
            log::warn!("cannot remove {}: {e}", trash.display());
        }
    }
    log::info!("session {id} deleted");
    Ok(())
}

/// With a retention set, deletes sessions past it (finished that long ago, or created that
/// long ago and idle since), looking every `retention_sweep`, until the server stops.
pub(crate) fn spawn_retention_sweep(shared: Arc<Shared>) {
    let Some(retention) = shared.config.retention else {
        return;
    };
    tokio::spawn(async move {
        while !shared.stopping() {
            let cutoff = crate::db::now_ms() - retention.as_millis().min(i64::MAX as u128) as i64;
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
