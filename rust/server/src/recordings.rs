//! Accepting a whole recording: moved into place, and for sim and adb sessions a place in
//! the playback queue. Used by `PUT …/recording` (whole or resumed) and the legacy route.

use std::sync::Arc;

use crate::Error;
use crate::config::PlaybackKind;
use crate::files::TempFile;
use crate::jobs::{self, Begin};
use crate::session::{Session, SessionState, Step};
use crate::shared::Shared;

/// Moves an uploaded recording into place and queues its playback (sim, adb). `session` is read
/// under the session's lock.
///
/// Only the first whole upload starts playback. A repeated upload with the same bytes (a
/// client retry whose first answer was lost) is accepted as is; different bytes once
/// playback has started are a conflict. An `upload` session's recording may be replaced
/// until its estimate starts.
pub(crate) fn accept_recording(
    shared: &Arc<Shared>,
    session: &Session,
    temp: TempFile,
) -> Result<(), Error> {
    if temp.bytes == 0 {
        return Err(Error::BadRequest("the recording is empty".into()));
    }
    crate::mp4_check::check_recording(session.playback, &temp.path)?;
    if session.playback == PlaybackKind::Sim {
        check_sim_header(&temp.path)?;
    }
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

/// A `sim` session's recording must start with the `sitar-sim` header (magic and a format
/// version this build reads): a 422 naming what is wrong at upload, not a session that
/// fails later. Only the 12 header bytes are read; the body is checked when it is played.
fn check_sim_header(path: &std::path::Path) -> Result<(), Error> {
    use std::io::Read;
    let mut head = Vec::with_capacity(12);
    std::fs::File::open(path)
        .and_then(|f| f.take(12).read_to_end(&mut head))
        .map_err(|e| Error::io("cannot read", path, e))?;
    let magic = sitar_sim::RECORDING_MAGIC;
    if head.len() < 12 || head[..8] != magic[..] {
        let start: String = head
            .iter()
            .take(8)
            .map(|&b| if b.is_ascii_graphic() { b as char } else { '.' })
            .collect();
        return Err(Error::InvalidContent(format!(
            "the recording is not a sitar-sim recording (as `sitar simulate` writes): it starts \
             with {start:?}, not the {:?} header",
            String::from_utf8_lossy(magic)
        )));
    }
    let version = u32::from_le_bytes([head[8], head[9], head[10], head[11]]);
    if version != sitar_sim::RECORDING_VERSION {
        return Err(Error::InvalidContent(format!(
            "the recording is a sitar-sim recording of format version {version}; this server \
             reads version {}",
            sitar_sim::RECORDING_VERSION
        )));
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sim_recording_is_checked_by_its_header() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rec");
        let check = |bytes: &[u8]| {
            std::fs::write(&path, bytes).unwrap();
            check_sim_header(&path)
        };
        let mut good = sitar_sim::RECORDING_MAGIC.to_vec();
        good.extend_from_slice(&sitar_sim::RECORDING_VERSION.to_le_bytes());
        good.extend_from_slice(b"{}");
        assert!(check(&good).is_ok());
        let Err(Error::InvalidContent(garbage)) = check(b"definitely not a recording") else {
            panic!("garbage accepted");
        };
        assert_eq!(
            garbage,
            "the recording is not a sitar-sim recording (as `sitar simulate` writes): it starts \
             with \"definite\", not the \"SITARSIM\" header"
        );
        assert!(matches!(check(b"SITARSIM"), Err(Error::InvalidContent(_))));
        let mut future = good.clone();
        future[8] = 99;
        let Err(Error::InvalidContent(version)) = check(&future) else {
            panic!("version 99 accepted");
        };
        assert!(version.contains("format version 99"), "{version}");
    }
}
