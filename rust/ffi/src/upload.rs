//! The bridge to `sitar-client`'s [`UploadJob`]: the upload options JSON, a results sink
//! that loads into the phone's session, and the job's snapshot as a [`SitarJobProgress`].

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde::Deserialize;
use sitar_client::{Client, JobOptions, JobState, NewSession, SessionFrame, UploadJob};
use sitar_core::{Convention, PoseRelation, Session};

use crate::error::Error;
use crate::types::{SitarJobProgress, SitarJobState};

/// The upload options JSON (every key optional).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct UploadOptions {
    server_url: Option<String>,
    /// The backend's access token (`sitar token create --role app`), sent as
    /// `Authorization: Bearer …`.
    server_token: Option<String>,
    /// Pins the backend's TLS certificate: its SHA-256 fingerprint (`AB:CD:…`).
    server_cert_sha256: Option<String>,
    session_id: Option<String>,
    trials: u32,
    setting: String,
    playback: String,
    poll_interval_ms: u64,
    window_frames: Option<u32>,
    pose_relation: Option<PoseRelation>,
    /// A session folder (as `sitar_session_save` writes it) whose log (`trajectory.txt`,
    /// `subtrajectories.csv`, `anchors.csv`) goes to the backend before the recording and
    /// whose camera evidence (`evidence.csv`, `thumbnails/`) after it. Without it, a started
    /// session is saved next to the recording (`RECORDING.session/`, or under the config's
    /// `data_dir`) and sent from there.
    evidence_dir: Option<PathBuf>,
}

impl Default for UploadOptions {
    fn default() -> Self {
        UploadOptions {
            server_url: None,
            server_token: None,
            server_cert_sha256: None,
            session_id: None,
            trials: 10,
            setting: sitar_core::DEFAULT_SETTING.to_owned(),
            playback: "adb".to_owned(),
            poll_interval_ms: 500,
            window_frames: None,
            pose_relation: None,
            evidence_dir: None,
        }
    }
}

/// The window settings the backend uses when a session request names none.
const BACKEND_WINDOW_FRAMES: u32 = 10;

/// Starts the job that uploads `recording` and loads the results into `session`.
pub(crate) fn start(
    session: Arc<Mutex<Session>>,
    recording: &Path,
    options_json: &str,
) -> Result<UploadJob, Error> {
    let o: UploadOptions = if options_json.trim().is_empty() {
        UploadOptions::default()
    } else {
        serde_json::from_str(options_json)?
    };
    let config = crate::error::lock(&session)?.config().clone();
    let url = o.server_url.or(config.server_url.clone()).ok_or_else(|| {
        Error::invalid(
            "options_json",
            "no server_url in the upload options or the session config",
        )
    })?;
    // Results of other windows or another relation would be refused when they arrive.
    let frames = config.subtrajectory_frames;
    let window_frames = o.window_frames.unwrap_or(frames);
    if window_frames != frames {
        return Err(Error::invalid(
            "options_json",
            format!(
                "window_frames {window_frames} differs from the session config's \
                 subtrajectory_frames {frames}: the results could not be shown"
            ),
        ));
    }
    let relation = o.pose_relation.unwrap_or(config.pose_relation);
    if relation != config.pose_relation {
        return Err(Error::invalid(
            "options_json",
            format!(
                "pose_relation {relation} differs from the session config's pose_relation {}: \
                 the results could not be shown",
                config.pose_relation
            ),
        ));
    }
    let options = JobOptions {
        // Sent only where they differ from the backend's defaults, so a phone with default
        // settings also works with a backend that predates window settings (and one that
        // does not know them refuses a session it would estimate wrong).
        session: NewSession {
            trials: o.trials,
            setting: o.setting,
            playback: o.playback,
            window_frames: (window_frames != BACKEND_WINDOW_FRAMES).then_some(window_frames),
            pose_relation: (relation != PoseRelation::TransPart)
                .then(|| relation.name().to_owned()),
        },
        session_id: o.session_id,
        poll_interval: Duration::from_millis(o.poll_interval_ms),
        evidence_dir: o
            .evidence_dir
            .or_else(|| save_session_folder(&session, recording, &config)),
        frame: session_frame(&config),
    };
    let mut client = Client::new(&url)?;
    if let Some(token) = &o.server_token {
        client = client.with_server_token(token)?;
    }
    if let Some(fingerprint) = &o.server_cert_sha256 {
        client = client.with_server_cert_sha256(fingerprint)?;
    }
    let job = UploadJob::start(client, recording, options, move |text: &str| {
        let _trace = crate::trace::section("sitar load results");
        crate::error::lock(&session)?.load_results(text)?;
        Ok::<(), Error>(())
    })?;
    Ok(job)
}

/// The C view of a job's snapshot.
pub(crate) fn progress(job: &UploadJob) -> SitarJobProgress {
    let p = job.progress();
    SitarJobProgress {
        state: state(p.state) as i32,
        error_code: p.error.as_deref().map_or(0, crate::error::client_code),
        progress: p.progress,
        eta_s: p.eta_s.unwrap_or(-1.0),
        bytes_sent: p.bytes_sent,
        bytes_total: p.bytes_total,
        trials_done: p.trials_done,
        trials_total: p.trials_total,
        results_revision: p.results_revision,
        results_trials: p.results_trials,
    }
}

/// Why the job failed ("" otherwise).
pub(crate) fn message(job: &UploadJob) -> String {
    job.progress()
        .error
        .map(|e| e.to_string())
        .unwrap_or_default()
}

fn state(s: JobState) -> SitarJobState {
    use SitarJobState::*;
    match s {
        JobState::Starting => SITAR_JOB_STARTING,
        JobState::Uploading => SITAR_JOB_UPLOADING,
        JobState::Playing => SITAR_JOB_PLAYING,
        JobState::Estimating => SITAR_JOB_ESTIMATING,
        JobState::Downloading => SITAR_JOB_DOWNLOADING,
        JobState::Done => SITAR_JOB_DONE,
        JobState::Failed => SITAR_JOB_FAILED,
        JobState::Cancelled => SITAR_JOB_CANCELLED,
    }
}

/// The session request's frame: the config's convention and venue, each sent only where it
/// differs from the backend's default (`unity`, no venue), so a phone outside venues also
/// works with a backend that predates them.
fn session_frame(config: &sitar_core::SessionConfig) -> SessionFrame {
    SessionFrame {
        convention: (config.convention != Convention::Unity)
            .then(|| config.convention.name().to_owned()),
        venue: config.venue.clone(),
    }
}

/// Saves a started session beside the recording (`RECORDING.session/`, or under the config's
/// `data_dir`), so the job can send its log and camera evidence; `None` (and a log line) for a
/// session never started or a folder that cannot be written: the results never depend on it.
fn save_session_folder(
    session: &Arc<Mutex<Session>>,
    recording: &Path,
    config: &sitar_core::SessionConfig,
) -> Option<PathBuf> {
    let session = crate::error::lock(session).ok()?;
    if session.logged().is_empty() {
        return None;
    }
    let name = format!("{}.session", recording.file_name()?.to_string_lossy());
    let dir = match &config.data_dir {
        Some(data) => data.join(name),
        None => recording.parent()?.join(name),
    };
    match session.save(&dir) {
        Ok(()) => Some(dir),
        Err(e) => {
            log::warn!("the session's log and camera evidence not sent: {e}");
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn session(config: &str) -> Arc<Mutex<Session>> {
        let config = sitar_core::SessionConfig::from_json(config).unwrap();
        Arc::new(Mutex::new(Session::new(config)))
    }

    fn refused(config: &str, options: &str) -> Error {
        start(session(config), Path::new("/nowhere.mp4"), options)
            .err()
            .unwrap_or_else(|| panic!("{options} was accepted"))
    }

    #[test]
    fn options_that_would_give_unusable_results_are_refused_naming_both_values() {
        let url = r#""server_url":"http://127.0.0.1:9""#;
        let e = refused(
            r#"{"subtrajectory_frames":20}"#,
            &format!(r#"{{{url},"window_frames":10}}"#),
        );
        assert_eq!(
            e.code(),
            crate::SitarStatus::SITAR_ERR_INVALID_ARGUMENT as i32
        );
        let m = e.to_string();
        assert!(
            m.contains("window_frames 10") && m.contains("subtrajectory_frames 20"),
            "{m}"
        );
        let e = refused("{}", &format!(r#"{{{url},"pose_relation":"angle_deg"}}"#));
        let m = e.to_string();
        assert!(
            m.contains("pose_relation angle_deg") && m.contains("pose_relation trans_part"),
            "{m}"
        );
        // Bad values and keys are parse errors naming them.
        for (options, needle) in [
            (
                format!(r#"{{{url},"pose_relation":"angle_rad"}}"#),
                "angle_rad",
            ),
            (format!(r#"{{{url},"window_frames":-3}}"#), "-3"),
            (format!(r#"{{{url},"windowframes":20}}"#), "windowframes"),
        ] {
            let e = refused("{}", &options);
            assert_eq!(
                e.code(),
                crate::SitarStatus::SITAR_ERR_PARSE as i32,
                "{options}"
            );
            assert!(e.to_string().contains(needle), "{e}");
        }
        assert!(refused("{}", "").to_string().contains("server_url"));
    }

    #[test]
    fn a_recording_that_cannot_be_read_is_an_io_error_before_any_request() {
        // Port 9 (discard) is never asked: the file is checked first.
        let dir = tempfile::tempdir().unwrap();
        let options = r#"{"server_url":"http://127.0.0.1:9"}"#;
        for recording in [dir.path().to_path_buf(), dir.path().join("missing.mp4")] {
            let e = start(session("{}"), &recording, options)
                .err()
                .unwrap_or_else(|| panic!("{recording:?} was accepted"));
            assert_eq!(e.code(), crate::SitarStatus::SITAR_ERR_IO as i32, "{e}");
        }
    }

    #[test]
    fn the_frame_sends_only_what_differs_from_the_backends_defaults() {
        let frame =
            |config: &str| session_frame(&sitar_core::SessionConfig::from_json(config).unwrap());
        assert_eq!(frame("{}"), SessionFrame::default());
        assert_eq!(frame(r#"{"convention":"unity"}"#), SessionFrame::default());
        assert_eq!(
            frame(r#"{"convention":"arcore","venue":"v0123456789abcdef"}"#),
            SessionFrame {
                convention: Some("arcore".into()),
                venue: Some("v0123456789abcdef".into()),
            }
        );
    }

    #[test]
    fn every_job_state_has_its_c_value_in_order() {
        let all = [
            JobState::Starting,
            JobState::Uploading,
            JobState::Playing,
            JobState::Estimating,
            JobState::Downloading,
            JobState::Done,
            JobState::Failed,
            JobState::Cancelled,
        ];
        for (i, s) in all.into_iter().enumerate() {
            assert_eq!(state(s) as i32, i as i32, "{s:?}");
        }
    }
}
