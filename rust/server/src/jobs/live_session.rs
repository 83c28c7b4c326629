//! A session's trials in memory (`estimate::live_sessions`): there already, or rebuilt from
//! its stored trial files (and the phone's walk, when the session uses it) after a restart,
//! with the server's thresholds and the session's calibration.

use std::sync::Arc;

use crate::app_state::App;
use crate::error::Error;
use crate::estimate::live_sessions::LiveSession;
use crate::ingest::phone_log::parse_walk;
use crate::ingest::trials::{parse_trial, read_trial};
use crate::model::Session;
use crate::storage::keys::SessionObject;

/// The live session of `session`: in memory already, or rebuilt from its trial files (after
/// a restart). Reading the files runs off the async runtime.
pub(crate) async fn live_session(
    shared: &Arc<App>,
    session: &Session,
) -> Result<Arc<LiveSession>, Error> {
    if let Some(live) = shared.live.get(&session.id) {
        return Ok(live);
    }
    let (shared, session) = (shared.clone(), session.clone());
    let id = session.id.clone();
    tokio::task::spawn_blocking(move || {
        let thresholds = session
            .settings
            .thresholds(shared.config.thresholds, shared.config.thresholds_deg);
        let calibration = shared
            .config
            .calibrations
            .for_session(session.calibration.as_deref());
        if let crate::estimate::calibrations::SessionCalibration::Missing(name) = &calibration {
            log::warn!(
                "session {}: calibration {name} is not on this server (sitar serve \
                 --calibration {name}=FILE): its estimates are published uncalibrated",
                session.id
            );
        }
        let live = shared.live.get_or_insert(
            &session.id,
            session.settings,
            calibration,
            thresholds,
            session.results_trials,
            || {
                shared
                    .db
                    .trials_in_order(&session.id)?
                    .into_iter()
                    .map(|(index, play_index)| {
                        let bytes = read_trial(&*shared.blobs, &session.id, index)?;
                        let source = format!("trial_{index:03}.txt");
                        Ok((play_index, index, parse_trial(&bytes, &source)?))
                    })
                    .collect()
            },
        )?;
        live.restore_walk(
            || match shared.blobs.get(&session.id, SessionObject::Walk)? {
                Some(bytes) => {
                    let text = String::from_utf8(bytes)
                        .map_err(|e| Error::Internal(format!("walk.txt: {e}")))?;
                    parse_walk(&text).map(Some)
                }
                None => Ok(None),
            },
        );
        Ok(live)
    })
    .await
    .map_err(|e| Error::Internal(format!("rebuilding session {id}: {e}")))?
}
