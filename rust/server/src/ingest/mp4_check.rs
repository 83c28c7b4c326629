//! Is an uploaded recording an MP4? Checked at upload, so a wrong file is a 422
//! to the phone that sent it instead of a session that fails later on the
//! playback phones.
//!
//! An MP4 (ISO base media file, what ARCore's Recording API writes) is a chain
//! of boxes: 4 bytes size, 4 bytes type, then the payload. The check walks the
//! top-level boxes by their headers only (a seek per box, nothing is decoded)
//! and wants an `ftyp` box (the file type) and a `moov` box (the movie header,
//! which Android's muxer writes at the end, after the media data). It is
//! deliberately tolerant of everything else: ARCore recordings carry extra
//! tracks (IMU, camera metadata) that a full MP4 parser may not know.

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use crate::error::Error;
use crate::model::PlaybackKind;

/// Top-level boxes looked at before giving up (a recording has fewer than ten), so a
/// file of millions of tiny boxes costs no more than this many reads.
const MAX_BOXES: usize = 4096;

/// The upload hook: a recording for a session played over adb must be an MP4, one for a
/// `sim` session a `sitar-sim` recording (`upload` sessions are not played).
pub(crate) fn check_recording(playback: PlaybackKind, path: &Path) -> Result<(), Error> {
    match playback {
        PlaybackKind::Adb => check_mp4_file(path),
        PlaybackKind::Sim => check_sim_header(path),
        PlaybackKind::Upload => Ok(()),
    }
}

/// The largest `sitar-sim` recording this server reads (its JSON takes about 160 bytes a
/// frame: an hour at 30 fps is 17 MB). A sim recording is the only kind ever read whole —
/// every other recording is only streamed or peeked at — so this bounds what reading one
/// costs; a larger `sim` upload is refused.
pub(crate) const MAX_SIM_RECORDING_BYTES: u64 = 64 << 20;

/// Bytes of a recording that tell whether it is a `sitar-sim` one (magic and version).
pub(crate) const SIM_HEADER_BYTES: usize = 12;

/// Whether `head`, a recording's first bytes, is the `sitar-sim` header.
pub(crate) fn is_sim_header(head: &[u8]) -> bool {
    head.starts_with(sitar_sim::RECORDING_MAGIC)
}

/// The `sitar-sim` recording at `path`: its header is checked (and its length against
/// [`MAX_SIM_RECORDING_BYTES`]) before it is read whole.
pub(crate) fn read_sim_recording(path: &Path) -> Result<sitar_sim::Recording, Error> {
    check_sim_header(path)?;
    let bytes = std::fs::read(path).map_err(|e| Error::io("cannot read", path, e))?;
    sitar_sim::Recording::from_bytes(&bytes).map_err(|e| {
        Error::InvalidContent(format!("the recording is not a sitar-sim recording: {e}"))
    })
}

/// A `sim` session's recording must start with the `sitar-sim` header (magic and a format
/// version this build reads) and be at most [`MAX_SIM_RECORDING_BYTES`]: a 422 naming what
/// is wrong at upload, not a session that fails later. Only the 12 header bytes are read;
/// the body is checked when it is played.
fn check_sim_header(path: &std::path::Path) -> Result<(), Error> {
    let mut head = Vec::with_capacity(SIM_HEADER_BYTES);
    let file = std::fs::File::open(path).map_err(|e| Error::io("cannot read", path, e))?;
    let len = file
        .metadata()
        .map_err(|e| Error::io("cannot stat", path, e))?
        .len();
    file.take(SIM_HEADER_BYTES as u64)
        .read_to_end(&mut head)
        .map_err(|e| Error::io("cannot read", path, e))?;
    let magic = sitar_sim::RECORDING_MAGIC;
    if head.len() < SIM_HEADER_BYTES || !is_sim_header(&head) {
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
    if len > MAX_SIM_RECORDING_BYTES {
        return Err(Error::InvalidContent(format!(
            "the sitar-sim recording is {len} bytes; this server reads at most \
             {MAX_SIM_RECORDING_BYTES}"
        )));
    }
    Ok(())
}

/// Checks that the file at `path` is an MP4: an [`Error::InvalidContent`] (422)
/// saying what is wrong otherwise.
pub(crate) fn check_mp4_file(path: &Path) -> Result<(), Error> {
    let mut file = std::fs::File::open(path).map_err(|e| Error::io("cannot open", path, e))?;
    let len = file
        .metadata()
        .map_err(|e| Error::io("cannot stat", path, e))?
        .len();
    match check_mp4(&mut file, len) {
        Ok(()) => Ok(()),
        Err(Problem::Io(e)) => Err(Error::io("cannot read", path, e)),
        Err(Problem::NotMp4(why)) => Err(Error::InvalidContent(format!(
            "the recording is not an MP4 (as ARCore's Recording API writes): {why}"
        ))),
    }
}

#[derive(Debug)]
enum Problem {
    Io(std::io::Error),
    NotMp4(String),
}

/// Walks the top-level boxes of the `len` bytes of `reader`.
fn check_mp4<R: Read + Seek>(reader: &mut R, len: u64) -> Result<(), Problem> {
    let (mut ftyp, mut moov) = (false, false);
    let mut seen: Vec<String> = Vec::new();
    let mut offset = 0u64;
    while offset < len && !(ftyp && moov) {
        if seen.len() == MAX_BOXES {
            return Err(Problem::NotMp4(format!(
                "no {} among its first {MAX_BOXES} top-level boxes",
                missing(ftyp, moov)
            )));
        }
        let header_at = |what: &str| {
            Problem::NotMp4(format!(
                "the {what} at byte {offset} is not an MP4 box header{}",
                if offset == 0 {
                    " (an MP4 starts with a box such as `ftyp`)".to_owned()
                } else {
                    format!(" (after the boxes {})", seen.join(", "))
                }
            ))
        };
        if len - offset < 8 {
            return Err(header_at("end"));
        }
        reader.seek(SeekFrom::Start(offset)).map_err(Problem::Io)?;
        let mut header = [0u8; 16];
        reader.read_exact(&mut header[..8]).map_err(Problem::Io)?;
        let kind = &header[4..8];
        // Box types are four printable ASCII characters (`©` boxes live inside `moov`, not here).
        if !kind.iter().all(|b| b.is_ascii_graphic() || *b == b' ') {
            return Err(header_at("box type"));
        }
        let kind = String::from_utf8_lossy(kind).into_owned();
        // ISO 14496-12: `ftyp` comes first, only padding may precede it.
        if !ftyp && !matches!(kind.as_str(), "ftyp" | "free" | "skip" | "wide") {
            return Err(Problem::NotMp4(format!(
                "it starts with {}a {kind:?} box where the `ftyp` (file type) box must be",
                if seen.is_empty() {
                    String::new()
                } else {
                    format!("{} and then ", seen.join(", "))
                }
            )));
        }
        let size = match u32::from_be_bytes([header[0], header[1], header[2], header[3]]) {
            // The last box: it runs to the end of the file.
            0 => len - offset,
            // A 64-bit size follows the type.
            1 => {
                if len - offset < 16 {
                    return Err(header_at("64-bit box size"));
                }
                reader.read_exact(&mut header[8..16]).map_err(Problem::Io)?;
                let large = u64::from_be_bytes(header[8..16].try_into().unwrap_or([0; 8]));
                if large < 16 {
                    return Err(header_at("64-bit box size"));
                }
                large
            }
            n if n < 8 => return Err(header_at("box size")),
            n => u64::from(n),
        };
        if size > len - offset {
            return Err(Problem::NotMp4(format!(
                "its `{kind}` box at byte {offset} claims {size} bytes, but only {} are left \
                 (the file is cut short?)",
                len - offset
            )));
        }
        ftyp |= kind == "ftyp";
        moov |= kind == "moov";
        seen.push(format!("`{kind}`"));
        offset += size;
    }
    if ftyp && moov {
        Ok(())
    } else if seen.is_empty() {
        Err(Problem::NotMp4("it is empty".into()))
    } else {
        Err(Problem::NotMp4(format!(
            "no {} among its top-level boxes ({}){}",
            missing(ftyp, moov),
            seen.join(", "),
            if ftyp {
                "; a recording whose app stopped before finishing it lacks the movie header"
            } else {
                ""
            }
        )))
    }
}

fn missing(ftyp: bool, moov: bool) -> &'static str {
    match (ftyp, moov) {
        (false, false) => "`ftyp` (file type) or `moov` (movie header) box",
        (false, true) => "`ftyp` (file type) box",
        _ => "`moov` (movie header) box",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    fn boxed(kind: &[u8; 4], payload: &[u8]) -> Vec<u8> {
        let mut b = ((8 + payload.len()) as u32).to_be_bytes().to_vec();
        b.extend_from_slice(kind);
        b.extend_from_slice(payload);
        b
    }

    fn check(bytes: &[u8]) -> Result<(), String> {
        match check_mp4(&mut Cursor::new(bytes), bytes.len() as u64) {
            Ok(()) => Ok(()),
            Err(Problem::NotMp4(why)) => Err(why),
            Err(Problem::Io(e)) => panic!("io: {e}"),
        }
    }

    /// An independent reader (the `mp4` crate) agrees that the bytes are an MP4.
    fn mp4_crate_reads(bytes: &[u8]) -> bool {
        mp4::Mp4Reader::read_header(Cursor::new(bytes), bytes.len() as u64).is_ok()
    }

    #[test]
    fn minimal_mp4s_pass_in_the_orders_muxers_write() {
        let header = crate::ingest::minimal_mp4::minimal_mp4(1000, 2500);
        assert!(mp4_crate_reads(&header));
        assert_eq!(check(&header), Ok(()));
        // Android's MediaMuxer: ftyp, then the media data, the movie header last.
        let ftyp = &header[..20];
        let moov = &header[20..];
        let mut muxed = ftyp.to_vec();
        muxed.extend(boxed(b"mdat", &[0xAB; 1000]));
        muxed.extend_from_slice(moov);
        assert!(mp4_crate_reads(&muxed));
        assert_eq!(check(&muxed), Ok(()));
        // A 64-bit mdat size (recordings over 4 GiB use it) and a `free` box.
        let mut large = ftyp.to_vec();
        large.extend(boxed(b"free", &[]));
        large.extend_from_slice(&1u32.to_be_bytes());
        large.extend_from_slice(b"mdat");
        large.extend_from_slice(&(16u64 + 64).to_be_bytes());
        large.extend_from_slice(&[7; 64]);
        large.extend_from_slice(moov);
        assert!(mp4_crate_reads(&large));
        assert_eq!(check(&large), Ok(()));
        // Size 0: the last box runs to the end of the file.
        let mut to_end = header.clone();
        to_end.extend_from_slice(&0u32.to_be_bytes());
        to_end.extend_from_slice(b"mdat");
        to_end.extend_from_slice(&[1; 33]);
        assert_eq!(check(&to_end), Ok(()));
    }

    #[test]
    fn garbage_and_broken_files_are_refused_with_the_reason() {
        assert_eq!(check(b""), Err("it is empty".into()));
        let text = check(b"this is a text file, not a recording at all").unwrap_err();
        assert!(
            text.contains("starts with a \" is \" box where the `ftyp`"),
            "{text}"
        );
        let binary = check(b"\x00\x00\x00\x10\x01\x02\x03\x04").unwrap_err();
        assert!(
            binary.contains("box type at byte 0 is not an MP4 box header"),
            "{binary}"
        );
        // Pseudo-random bytes (a fixed LCG, so the test is repeatable).
        let mut x = 0x2545_F491_4F6C_DD1Du64;
        let random: Vec<u8> = (0..4096)
            .map(|_| {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (x >> 56) as u8
            })
            .collect();
        assert!(!mp4_crate_reads(&random));
        assert!(check(&random).is_err());
        let header = crate::ingest::minimal_mp4::minimal_mp4(1000, 2500);
        // Cut short inside the movie header.
        let cut = check(&header[..header.len() - 10]).unwrap_err();
        assert!(cut.contains("`moov` box at byte 20 claims"), "{cut}");
        assert!(cut.contains("cut short"), "{cut}");
        // The media data without the movie header (the app died before Stop).
        let mut no_moov = header[..20].to_vec();
        no_moov.extend(boxed(b"mdat", &[0; 100]));
        let why = check(&no_moov).unwrap_err();
        assert!(why.contains("no `moov` (movie header) box"), "{why}");
        assert!(why.contains("`ftyp`, `mdat`"), "{why}");
        // A movie header without a file type; padding before the file type is fine.
        let why = check(&header[20..]).unwrap_err();
        assert!(
            why.contains("starts with a \"moov\" box where the `ftyp`"),
            "{why}"
        );
        let mut padded = boxed(b"free", &[0; 4]);
        padded.extend_from_slice(&header);
        assert_eq!(check(&padded), Ok(()));
        let mut late = boxed(b"free", &[]);
        late.extend(boxed(b"mdat", &[]));
        let why = check(&late).unwrap_err();
        assert!(
            why.contains("starts with `free` and then a \"mdat\" box"),
            "{why}"
        );
        // Box sizes that cannot be.
        let mut tiny = header[..20].to_vec();
        tiny.extend_from_slice(&4u32.to_be_bytes());
        tiny.extend_from_slice(b"moov");
        let why = check(&tiny).unwrap_err();
        assert!(why.contains("box size at byte 20"), "{why}");
        assert!(why.contains("after the boxes `ftyp`"), "{why}");
        let mut trailing = header[..20].to_vec();
        trailing.extend_from_slice(b"abc");
        let why = check(&trailing).unwrap_err();
        assert!(why.contains("end at byte 20"), "{why}");
    }

    #[test]
    fn many_tiny_boxes_stop_at_the_bound() {
        let mut many = Vec::new();
        for _ in 0..(MAX_BOXES + 10) {
            many.extend(boxed(b"free", &[]));
        }
        many.extend(crate::ingest::minimal_mp4::minimal_mp4(1000, 10));
        let why = check(&many).unwrap_err();
        assert!(why.contains("first 4096 top-level boxes"), "{why}");
    }

    #[test]
    fn only_adb_recordings_are_checked() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("recording");
        std::fs::write(&path, b"SITARSIM recording, not an mp4").unwrap();
        assert!(
            check_recording(PlaybackKind::Sim, &path).is_err(),
            "not a sim header"
        );
        assert!(check_recording(PlaybackKind::Upload, &path).is_ok());
        assert!(matches!(
            check_recording(PlaybackKind::Adb, &path),
            Err(Error::InvalidContent(_))
        ));
    }

    #[test]
    fn the_file_check_names_the_problem_and_the_status() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("recording");
        std::fs::write(&path, b"\x89PNG\r\n\x1a\n....").unwrap();
        let err = check_mp4_file(&path).unwrap_err();
        assert_eq!(err.status_and_code().1, "invalid_content");
        assert!(
            err.to_string().starts_with("the recording is not an MP4"),
            "{err}"
        );
        std::fs::write(&path, crate::ingest::minimal_mp4::minimal_mp4(1000, 10)).unwrap();
        assert!(check_mp4_file(&path).is_ok());
        assert!(matches!(
            check_mp4_file(&dir.path().join("missing")),
            Err(Error::Io { .. })
        ));
    }

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
