//! Accepting a whole recording: moved into place, and for sim and adb sessions a place in
//! the playback queue. Used by `PUT …/recording` (whole or resumed) and the legacy route.

use std::sync::Arc;

use crate::Error;
use crate::app_state::App;
use crate::config::PlaybackKind;
use crate::playback::jobs::{self, Begin};
use crate::session::{Session, SessionState, Step};
use crate::storage::files::TempFile;

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
    let dest = shared.files.recording(id);
    if session.playback == PlaybackKind::Upload {
        session.require(Step::AcceptRecording)?;
        temp.publish(&dest)?;
        return shared.lifecycle().accept_recording(id, bytes).map(drop);
    }
    if dest.is_file() {
        return if same_content(&temp.path, &dest)? {
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
    temp.publish(&dest)?;
    if shared.lifecycle().accept_recording(id, bytes)? == SessionState::Created {
        jobs::enqueue(shared, session, Begin::Start);
    }
    Ok(())
}

fn same_content(a: &std::path::Path, b: &std::path::Path) -> Result<bool, Error> {
    use std::io::Read;
    let open =
        |p: &std::path::Path| std::fs::File::open(p).map_err(|e| Error::io("cannot open", p, e));
    let (mut fa, mut fb) = (open(a)?, open(b)?);
    let len = |f: &std::fs::File, p| {
        f.metadata()
            .map(|m| m.len())
            .map_err(|e| Error::io("cannot stat", p, e))
    };
    if len(&fa, a)? != len(&fb, b)? {
        return Ok(false);
    }
    let (mut ba, mut bb) = (vec![0u8; 1 << 20], vec![0u8; 1 << 20]);
    loop {
        let n = fa
            .read(&mut ba)
            .map_err(|e| Error::io("cannot read", a, e))?;
        if n == 0 {
            return Ok(true);
        }
        fb.read_exact(&mut bb[..n])
            .map_err(|e| Error::io("cannot read", b, e))?;
        if ba[..n] != bb[..n] {
            return Ok(false);
        }
    }
}
