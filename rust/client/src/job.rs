//! A background upload job: create (or continue) a server session, send the recording, poll
//! while the playback devices work, and hand every published result (progressive, then
//! final) to the caller. The app polls a snapshot and may cancel.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::Ordering;

use crate::job_state::{JobOptions, JobProgress, JobState, Shared, SinkError};
use crate::{Client, Error};

/// A running (or finished) upload job; dropping it cancels it.
///
/// ```no_run
/// use sitar_client::{Client, JobOptions, NewSession, UploadJob};
///
/// # fn show(_: &str) {}
/// let client = Client::new("http://127.0.0.1:8000")?;
/// let options = JobOptions::new(NewSession {
///     trials: 5,
///     setting: "trim_mean_30".into(),
///     playback: "sim".into(),
///     window_frames: None,
///     pose_relation: None,
/// });
/// // The sink gets every published result: progressive ones, then the final one.
/// let job = UploadJob::start(client, "walk.mp4".as_ref(), options, |results: &str| {
///     show(results);
///     Ok::<(), std::convert::Infallible>(())
/// })?;
/// while !job.progress().state.is_finished() {
///     std::thread::sleep(std::time::Duration::from_millis(200));
/// }
/// # Ok::<(), sitar_client::Error>(())
/// ```
pub struct UploadJob {
    shared: Arc<Shared>,
}

impl UploadJob {
    /// Starts the job on its own thread: creates the server session (or continues
    /// `options.session_id`), sends `recording` (resumably; a cancel cuts the transfer off
    /// within one read buffer), polls every `options.poll_interval`, asks for the estimate
    /// once all trials of an `upload` session arrived, and calls `sink` with every results
    /// JSON the server publishes (progressive ones when their trial count grows, the final
    /// one last; `results.csv` if the JSON cannot be had). A sink error on progressive
    /// results is ignored (the final results decide); on the final results it fails the job.
    ///
    /// Fails at once only for what is wrong before anything is sent: `trials` below 2, a
    /// `session_id` that is not server-made, or a thread that cannot be started.
    pub fn start<F, E>(
        client: Client,
        recording: &Path,
        options: JobOptions,
        mut sink: F,
    ) -> Result<Self, Error>
    where
        F: FnMut(&str) -> Result<(), E> + Send + 'static,
        E: Into<SinkError>,
    {
        options.validate()?;
        // A local file error is the caller's, found before a server session exists.
        if options.session_id.is_none() {
            crate::client::recording_file(recording)?;
        }
        let shared = Arc::new(Shared::new(options.session.trials));
        let worker = Arc::clone(&shared);
        let recording: PathBuf = recording.to_path_buf();
        let mut sink = move |text: &str| sink(text).map_err(Into::into);
        std::thread::Builder::new()
            .name("sitar-upload".into())
            .spawn(move || {
                let outcome = catch_unwind(AssertUnwindSafe(|| {
                    crate::job_run::run(&worker, &client, &recording, &options, &mut sink)
                }));
                match outcome {
                    Ok(Ok(())) => {}
                    Ok(Err(e)) => worker.fail(e),
                    Err(payload) => worker.fail(Error::Panicked(panic_message(&*payload))),
                }
            })
            .map_err(Error::Thread)?;
        Ok(UploadJob { shared })
    }

    /// A snapshot (never blocks on the network).
    pub fn progress(&self) -> JobProgress {
        self.shared.lock().progress.clone()
    }

    /// The server's session id, once known.
    pub fn server_id(&self) -> Option<String> {
        self.shared.lock().server_id.clone()
    }

    /// Cancels the job: its state is [`JobState::Cancelled`] at once (unless it had already
    /// finished), a transfer in flight stops within one read buffer, and no results are
    /// delivered afterwards.
    pub fn cancel(&self) {
        self.shared.cancelled.store(true, Ordering::Release);
        self.shared.set_state(JobState::Cancelled);
    }
}

impl Drop for UploadJob {
    fn drop(&mut self) {
        self.shared.cancelled.store(true, Ordering::Release);
        self.shared.update(|p| p.state = JobState::Cancelled);
    }
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic with a non-string payload".to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_server::{Reply, serve};
    use crate::{NewSession, SessionFrame};
    use std::sync::Mutex;
    use std::time::Duration;
    use std::time::Instant;

    #[derive(Debug, thiserror::Error)]
    #[error("sink refused: {0}")]
    struct Refused(String);

    fn options(window: Option<u32>, relation: Option<&str>) -> JobOptions {
        JobOptions {
            poll_interval: Duration::from_millis(10),
            ..JobOptions::new(NewSession {
                trials: 3,
                setting: "median".into(),
                playback: "sim".into(),
                window_frames: window,
                pose_relation: relation.map(str::to_owned),
            })
        }
    }

    fn recording(dir: &tempfile::TempDir) -> PathBuf {
        let path = dir.path().join("rec.mp4");
        std::fs::write(&path, b"0123456789").unwrap();
        path
    }

    fn client(base: &str) -> Client {
        Client::new(base)
            .unwrap()
            .with_retries(0, Duration::from_millis(10))
    }

    /// Polls until the job finished (10 s at most).
    fn finished(job: &UploadJob) -> JobProgress {
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            let p = job.progress();
            if p.state.is_finished() || Instant::now() > deadline {
                return p;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    type Collected = Arc<Mutex<Vec<String>>>;

    /// A collecting sink and what it collected.
    fn collector() -> (
        Collected,
        impl FnMut(&str) -> Result<(), Refused> + Send + 'static,
    ) {
        let got = Arc::new(Mutex::new(Vec::new()));
        let log = Arc::clone(&got);
        (got, move |text: &str| {
            log.lock().unwrap().push(text.to_owned());
            Ok(())
        })
    }

    const PLAYING: &str = r#"{"id":"s1","state":"playing","progress":0.5,"eta_s":2.0,"trials_done":2,"trials_total":3,"error":null,"results_trials":2}"#;
    const DONE: &str = r#"{"id":"s1","state":"done","progress":1.0,"eta_s":0.0,"trials_done":3,"trials_total":3,"error":null,"results_trials":3}"#;

    #[test]
    fn a_job_creates_uploads_and_delivers_progressive_then_final_results() {
        let (base, seen) = serve(vec![
            Reply::Answer(201, r#"{"id":"s1"}"#),
            Reply::Offset(0),
            Reply::Answer(202, "{}"),
            Reply::Answer(200, PLAYING),
            Reply::Answer(200, "progressive, 2 trials"),
            Reply::Answer(200, DONE),
            Reply::Answer(200, "final, 3 trials"),
            Reply::Answer(200, DONE),
        ]);
        let dir = tempfile::tempdir().unwrap();
        let (got, sink) = collector();
        let job = UploadJob::start(
            client(&base),
            &recording(&dir),
            options(Some(20), Some("angle_deg")),
            sink,
        )
        .unwrap();
        let p = finished(&job);
        assert_eq!(p.state, JobState::Done, "{:?}", p.error);
        assert_eq!((p.results_revision, p.results_trials), (2, 3));
        assert_eq!((p.bytes_sent, p.bytes_total), (10, 10));
        assert_eq!((p.trials_done, p.trials_total, p.progress), (3, 3, 1.0));
        assert_eq!(job.server_id().as_deref(), Some("s1"));
        assert_eq!(
            *got.lock().unwrap(),
            ["progressive, 2 trials", "final, 3 trials"]
        );
        let seen = seen.lock().unwrap();
        let paths: Vec<String> = seen
            .iter()
            .map(|s| format!("{} {}", s.method, s.path))
            .collect();
        assert_eq!(
            paths,
            [
                "POST /v1/sessions",
                "HEAD /v1/sessions/s1/recording",
                "PUT /v1/sessions/s1/recording",
                "GET /v1/sessions/s1",
                "GET /v1/sessions/s1/results.json",
                "GET /v1/sessions/s1",
                "GET /v1/sessions/s1/results.json",
                "GET /v1/sessions/s1",
            ]
        );
        // The window settings travel with the session request.
        let body: serde_json::Value = serde_json::from_slice(&seen[0].body).unwrap();
        assert_eq!(
            body,
            serde_json::json!({"trials":3,"setting":"median","playback":"sim",
                               "window_frames":20,"pose_relation":"angle_deg"})
        );
        assert_eq!(seen[2].body, b"0123456789");
    }

    #[test]
    fn unset_window_settings_are_not_sent() {
        let (base, seen) = serve(vec![Reply::Answer(500, "{}")]);
        let dir = tempfile::tempdir().unwrap();
        let job = UploadJob::start(
            client(&base),
            &recording(&dir),
            options(None, None),
            |_: &str| Ok::<(), Refused>(()),
        )
        .unwrap();
        let p = finished(&job);
        assert_eq!(p.state, JobState::Failed);
        assert!(matches!(
            p.error.as_deref(),
            Some(Error::Server { status: 500, .. })
        ));
        let body: serde_json::Value =
            serde_json::from_slice(&seen.lock().unwrap()[0].body).unwrap();
        assert_eq!(
            body,
            serde_json::json!({"trials":3,"setting":"median","playback":"sim"})
        );
    }

    /// A session folder with the phone's log (contents abridged) and no evidence.
    fn session_folder(dir: &tempfile::TempDir) -> PathBuf {
        let folder = dir.path().join("walk.mp4.session");
        std::fs::create_dir(&folder).unwrap();
        std::fs::write(folder.join("trajectory.txt"), "0 0 0 0 0 0 0 1\n").unwrap();
        std::fs::write(folder.join("subtrajectories.csv"), "index\n0\n").unwrap();
        std::fs::write(folder.join("anchors.csv"), "t_ns,anchor\n").unwrap();
        folder
    }

    fn paths(seen: &[crate::test_server::Seen]) -> Vec<String> {
        seen.iter()
            .map(|s| format!("{} {}", s.method, s.path))
            .collect()
    }

    #[test]
    fn a_job_in_a_venue_sends_the_frame_and_the_phone_log_before_the_recording() {
        let (base, seen) = serve(vec![
            Reply::Answer(201, r#"{"id":"s1"}"#),
            Reply::Answer(204, ""),
            Reply::Answer(200, r#"{"subtrajectories":1}"#),
            Reply::Answer(204, ""),
            Reply::Offset(0),
            Reply::Answer(202, "{}"),
            Reply::Answer(200, DONE),
            Reply::Answer(200, "final"),
            Reply::Answer(200, DONE),
        ]);
        let dir = tempfile::tempdir().unwrap();
        let mut o = options(None, None);
        o.evidence_dir = Some(session_folder(&dir));
        o.frame = SessionFrame {
            convention: Some("arcore".into()),
            venue: Some("v0123456789abcdef".into()),
        };
        let (got, sink) = collector();
        let job = UploadJob::start(client(&base), &recording(&dir), o, sink).unwrap();
        let p = finished(&job);
        assert_eq!(p.state, JobState::Done, "{:?}", p.error);
        assert_eq!(p.logs_sent, 3);
        // No evidence.csv in the folder: no evidence, and subtrajectories.csv only once.
        assert!(!p.evidence_sent);
        assert_eq!(*got.lock().unwrap(), ["final"]);
        let seen = seen.lock().unwrap();
        assert_eq!(
            paths(&seen),
            [
                "POST /v1/sessions",
                "PUT /v1/sessions/s1/trajectory.txt",
                "PUT /v1/sessions/s1/subtrajectories.csv",
                "PUT /v1/sessions/s1/anchors.csv",
                "HEAD /v1/sessions/s1/recording",
                "PUT /v1/sessions/s1/recording",
                "GET /v1/sessions/s1",
                "GET /v1/sessions/s1/results.json",
                "GET /v1/sessions/s1",
            ]
        );
        let body: serde_json::Value = serde_json::from_slice(&seen[0].body).unwrap();
        assert_eq!(
            body,
            serde_json::json!({"trials":3,"setting":"median","playback":"sim",
                               "convention":"arcore","venue":"v0123456789abcdef"})
        );
        assert_eq!(seen[1].body, b"0 0 0 0 0 0 0 1\n");
        assert_eq!(seen[3].body, b"t_ns,anchor\n");
    }

    #[test]
    fn a_refused_log_fails_the_job_naming_the_file_before_the_recording_is_sent() {
        let (base, seen) = serve(vec![
            Reply::Answer(201, r#"{"id":"s1"}"#),
            Reply::Answer(
                422,
                r#"{"error":{"code":"invalid_content","message":"trajectory.txt line 1: 7 columns, expected 8"}}"#,
            ),
        ]);
        let dir = tempfile::tempdir().unwrap();
        let mut o = options(None, None);
        o.evidence_dir = Some(session_folder(&dir));
        let job = UploadJob::start(client(&base), &recording(&dir), o, |_: &str| {
            Ok::<(), Refused>(())
        })
        .unwrap();
        let p = finished(&job);
        assert_eq!(p.state, JobState::Failed);
        assert_eq!((p.logs_sent, p.bytes_sent), (0, 0));
        let error = p.error.unwrap();
        assert!(
            matches!(&*error, Error::FileRefused { file, status: 422, .. } if file == "trajectory.txt"),
            "{error:?}"
        );
        assert_eq!(
            error.to_string(),
            "the server refused trajectory.txt (422 invalid_content): \
             trajectory.txt line 1: 7 columns, expected 8"
        );
        std::thread::sleep(Duration::from_millis(50));
        assert_eq!(
            paths(&seen.lock().unwrap()),
            ["POST /v1/sessions", "PUT /v1/sessions/s1/trajectory.txt"]
        );
    }

    #[test]
    fn an_older_backend_without_log_routes_still_completes_the_session() {
        let (base, seen) = serve(vec![
            Reply::Answer(201, r#"{"id":"s1"}"#),
            Reply::Answer(
                404,
                r#"{"error":{"code":"not_found","message":"no such route"}}"#,
            ),
            // An older backend has subtrajectories.csv (camera evidence), not anchors.csv.
            Reply::Answer(200, r#"{"subtrajectories":1}"#),
            Reply::Answer(
                404,
                r#"{"error":{"code":"not_found","message":"no such route"}}"#,
            ),
            Reply::Offset(0),
            Reply::Answer(202, "{}"),
            Reply::Answer(200, DONE),
            Reply::Answer(200, "final"),
            Reply::Answer(200, DONE),
        ]);
        let dir = tempfile::tempdir().unwrap();
        let mut o = options(None, None);
        o.evidence_dir = Some(session_folder(&dir));
        let (got, sink) = collector();
        let job = UploadJob::start(client(&base), &recording(&dir), o, sink).unwrap();
        let p = finished(&job);
        assert_eq!(p.state, JobState::Done, "{:?}", p.error);
        assert_eq!(p.logs_sent, 1);
        assert_eq!(*got.lock().unwrap(), ["final"]);
        assert_eq!(seen.lock().unwrap().len(), 9);
        // No frame set: the session request carries neither key.
        let body: serde_json::Value =
            serde_json::from_slice(&seen.lock().unwrap()[0].body).unwrap();
        assert!(body.get("convention").is_none() && body.get("venue").is_none());
    }

    #[test]
    fn a_continued_upload_session_skips_the_sent_recording_and_asks_for_the_estimate() {
        let (base, seen) = serve(vec![
            Reply::Answer(
                200,
                r#"{"id":"s2","state":"uploaded","progress":0.0,"eta_s":null,"trials_done":0,"trials_total":2,"error":null,"playback":"upload"}"#,
            ),
            Reply::Answer(
                200,
                r#"{"id":"s2","state":"playing","progress":0.9,"eta_s":null,"trials_done":2,"trials_total":2,"error":null}"#,
            ),
            Reply::Answer(202, "{}"),
            Reply::Answer(
                200,
                r#"{"id":"s2","state":"done","progress":1.0,"eta_s":0.0,"trials_done":2,"trials_total":2,"error":null,"results_trials":2}"#,
            ),
            Reply::Answer(200, "final"),
            Reply::Answer(
                200,
                r#"{"id":"s2","state":"done","progress":1.0,"eta_s":0.0,"trials_done":2,"trials_total":2,"error":null,"results_trials":2}"#,
            ),
        ]);
        let dir = tempfile::tempdir().unwrap();
        let (got, sink) = collector();
        let mut o = options(None, None);
        o.session_id = Some("s2".into());
        let job = UploadJob::start(client(&base), &recording(&dir), o, sink).unwrap();
        let p = finished(&job);
        assert_eq!(p.state, JobState::Done, "{:?}", p.error);
        assert_eq!((p.bytes_sent, p.trials_total), (10, 2));
        assert_eq!(*got.lock().unwrap(), ["final"]);
        let seen = seen.lock().unwrap();
        assert_eq!(seen[2].method, "POST");
        assert_eq!(seen[2].path, "/v1/sessions/s2/estimate");
        assert!(seen.iter().all(|s| s.method != "PUT" && s.method != "HEAD"));
    }

    /// Runs a job against a server that creates `s1`, takes the recording and then gives
    /// `after`, and returns the finished job's snapshot.
    fn failed_with(
        after: &[Reply],
        sink: impl FnMut(&str) -> Result<(), Refused> + Send + 'static,
    ) -> JobProgress {
        let replies = [
            Reply::Answer(201, r#"{"id":"s1"}"#),
            Reply::Offset(0),
            Reply::Answer(202, "{}"),
        ];
        let (base, _) = serve(replies.iter().chain(after).cloned().collect());
        let dir = tempfile::tempdir().unwrap();
        let job =
            UploadJob::start(client(&base), &recording(&dir), options(None, None), sink).unwrap();
        let p = finished(&job);
        assert_eq!(p.state, JobState::Failed, "{p:?}");
        p
    }

    #[test]
    fn failures_say_why_a_refused_final_result_a_failed_session_and_a_panic() {
        let done = [
            Reply::Answer(200, DONE),
            Reply::Answer(200, "final"),
            Reply::Answer(200, DONE),
        ];
        // The sink refuses the final results.
        let p = failed_with(&done, |t: &str| Err(Refused(t.to_owned())));
        assert_eq!(p.results_revision, 0);
        assert_eq!(p.error.as_ref().unwrap().to_string(), "sink refused: final");
        assert!(matches!(p.error.as_deref(), Some(Error::Results(e)) if e.is::<Refused>()));

        // The server failed the session.
        let failed = [Reply::Answer(
            200,
            r#"{"id":"s1","state":"failed","progress":0.3,"eta_s":null,"trials_done":1,"trials_total":3,"error":"adb: no device"}"#,
        )];
        let p = failed_with(&failed, |_: &str| Ok(()));
        assert_eq!(
            p.error.as_ref().unwrap().to_string(),
            "the server failed session s1: adb: no device"
        );

        // A panic in the sink fails the job instead of leaving it running forever.
        let p = failed_with(&done, |_: &str| panic!("sink broke"));
        assert!(matches!(p.error.as_deref(), Some(Error::Panicked(m)) if m == "sink broke"));
    }

    #[test]
    fn a_cancel_is_at_once_and_nothing_is_delivered_after_it() {
        let (base, _) = serve(vec![Reply::Hang, Reply::Hang]);
        let dir = tempfile::tempdir().unwrap();
        let (got, sink) = collector();
        let job =
            UploadJob::start(client(&base), &recording(&dir), options(None, None), sink).unwrap();
        job.cancel();
        assert_eq!(job.progress().state, JobState::Cancelled);
        std::thread::sleep(Duration::from_millis(100));
        assert_eq!(job.progress().state, JobState::Cancelled);
        assert!(got.lock().unwrap().is_empty());
        // Dropping a running job cancels it too.
        let shared = {
            let job = UploadJob::start(
                client(&base),
                &recording(&dir),
                options(None, None),
                |_: &str| Ok::<(), Refused>(()),
            )
            .unwrap();
            Arc::clone(&job.shared)
        };
        assert!(shared.is_cancelled());
        assert_eq!(shared.lock().progress.state, JobState::Cancelled);
    }

    #[test]
    fn bad_options_are_refused_before_anything_is_sent() {
        let dir = tempfile::tempdir().unwrap();
        let mut o = options(None, None);
        o.session.trials = 1;
        let err = UploadJob::start(
            client("http://127.0.0.1:9"),
            &recording(&dir),
            o,
            |_: &str| Ok::<(), Refused>(()),
        )
        .err()
        .unwrap();
        assert!(
            err.to_string().contains("trials must be at least 2"),
            "{err}"
        );
        let mut o = options(None, None);
        o.session_id = Some("../x".into());
        let err = UploadJob::start(
            client("http://127.0.0.1:9"),
            &recording(&dir),
            o,
            |_: &str| Ok::<(), Refused>(()),
        )
        .err()
        .unwrap();
        assert!(
            matches!(&err, Error::InvalidArgument(m) if m.contains("session_id")),
            "{err}"
        );
    }
}
