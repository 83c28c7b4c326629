//! Accepting a whole recording: moved into place, and for sim and adb sessions a place in
//! the playback queue. Used by `PUT …/recording` (whole or resumed) and the legacy route.

use std::sync::Arc;

use crate::app_state::App;
use crate::error::Error;
use crate::jobs::playback::{self as jobs, Begin};
use crate::model::{PlaybackKind, Session, SessionState, Step};
use crate::storage::keys::SessionObject;
use crate::storage::staged::TempFile;

/// Moves an uploaded recording into place and queues its playback (sim, adb). `session` is read
/// under the session's lock.
///
/// Only the first whole upload starts playback. A repeated upload with the same bytes (a
/// client retry whose first answer was lost) is accepted as is; different bytes once
/// playback has started are a conflict. An `upload` session's recording may be replaced
/// until its estimate starts.
pub(crate) fn accept_recording(
    shared: &Arc<App>,
    session: &Session,
    temp: TempFile,
) -> Result<(), Error> {
    if temp.bytes == 0 {
        return Err(Error::BadRequest("the recording is empty".into()));
    }
    crate::ingest::mp4_check::check_recording(session.playback, &temp.path)?;
    let (id, bytes) = (&session.id, temp.bytes);
    if session.playback == PlaybackKind::Upload {
        session.require(Step::AcceptRecording)?;
        shared.blobs.publish(temp, id, SessionObject::Recording)?;
        return shared.lifecycle().accept_recording(id, bytes).map(drop);
    }
    if shared.blobs.exists(id, SessionObject::Recording) {
        return if shared
            .blobs
            .same_content(&temp, id, SessionObject::Recording)?
        {
            Ok(())
        } else {
            Err(Error::Conflict(format!(
                "session {id} already has another recording and its playback has started"
            )))
        };
    }
    session.require(Step::AcceptRecording)?;
    // Refused before it is kept: a full queue is a 503 the client can retry.
    shared.queue.check_room()?;
    shared.blobs.publish(temp, id, SessionObject::Recording)?;
    if shared.lifecycle().accept_recording(id, bytes)? == SessionState::Created {
        jobs::enqueue(shared, session, Begin::Start)?;
    }
    Ok(())
}
