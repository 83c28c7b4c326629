//! The phone's own log of a session: the session folder's `trajectory.txt`,
//! `subtrajectories.csv` and `anchors.csv` (sitar-core's formats), which the backend uses to put
//! the session into a venue's frame and to draw it from what the phone saw, and `walk.txt`
//! (every frame's pose), from which a backend with the session's calibration publishes first
//! results before any replay, and which it keeps as the live run of every later estimate.

use std::path::Path;

use crate::client::Payload;
use crate::{Client, Error, check_session_id};

/// The files of a phone session folder that make up its log, in the order they are sent, with
/// their content types: `PUT /v1/sessions/{id}/<name>` each.
pub const PHONE_LOG_FILES: [(&str, &str); 4] = [
    ("trajectory.txt", "text/plain; charset=utf-8"),
    ("subtrajectories.csv", "text/csv"),
    ("anchors.csv", "text/csv"),
    ("walk.txt", "text/plain; charset=utf-8"),
];

/// What [`Client::upload_phone_logs`] did with each file of [`PHONE_LOG_FILES`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PhoneLogsSent {
    /// Files the server took, in the order sent.
    pub sent: Vec<&'static str>,
    /// Files the server has no route for (404 or 405: a backend that predates venues), not
    /// sent; each was logged as a warning.
    pub unsupported: Vec<&'static str>,
    /// Files the folder does not hold (e.g. `anchors.csv` of a folder saved before anchors).
    pub missing: Vec<&'static str>,
}

impl Client {
    /// Sends the phone's log from the session folder `dir` to session `id`: each file of
    /// [`PHONE_LOG_FILES`] that `dir` holds, whole, in one idempotent `PUT` (retried like every
    /// call; a retry replaces the file).
    ///
    /// A 404 or 405 means a backend without these routes: the file is skipped with a logged
    /// warning and listed in [`PhoneLogsSent::unsupported`], so a session still completes on
    /// an older backend. Any other refusal (a 422 naming the line and column of a bad cell, a
    /// 413, …) is [`Error::FileRefused`], naming the file and carrying the server's message;
    /// a file that cannot be read is [`Error::Io`].
    pub fn upload_phone_logs(&self, id: &str, dir: &Path) -> Result<PhoneLogsSent, Error> {
        let id = check_session_id(id)?;
        let mut outcome = PhoneLogsSent::default();
        for (name, content_type) in PHONE_LOG_FILES {
            let path = dir.join(name);
            if !path.is_file() {
                outcome.missing.push(name);
                continue;
            }
            let body = std::fs::read(&path).map_err(|source| Error::Io {
                path: path.clone(),
                source,
            })?;
            let url = format!("/v1/sessions/{id}/{name}");
            match self.request("PUT", &url, Payload::Bytes(&body, content_type), None) {
                Ok(_) => outcome.sent.push(name),
                Err(Error::Server {
                    status: status @ (404 | 405),
                    message,
                    ..
                }) => {
                    log::warn!(
                        "upload: the server has no {name} route ({status}: {message}); \
                         the session goes on without it"
                    );
                    outcome.unsupported.push(name);
                }
                Err(Error::Server {
                    status,
                    code,
                    message,
                }) => {
                    return Err(Error::FileRefused {
                        file: name.to_owned(),
                        status,
                        code,
                        message,
                    });
                }
                Err(other) => return Err(other),
            }
        }
        Ok(outcome)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_server::{Reply, serve};
    use std::time::Duration;

    fn fast(base: &str) -> Client {
        Client::new(base)
            .unwrap()
            .with_retries(2, Duration::from_millis(10))
    }

    /// A session folder as sitar-core writes it (the four log files, contents abridged).
    fn folder(dir: &Path) {
        std::fs::write(dir.join("trajectory.txt"), "0 0 0 0 0 0 0 1\n").unwrap();
        std::fs::write(dir.join("walk.txt"), "0 0 0 0 0 0 0 1\n5 0 0 0 0 0 0 1\n").unwrap();
        std::fs::write(dir.join("subtrajectories.csv"), "index,start_ns\n0,0\n").unwrap();
        std::fs::write(
            dir.join("anchors.csv"),
            "t_ns,anchor,px,py,pz,qx,qy,qz,qw,tracking\n",
        )
        .unwrap();
    }

    #[test]
    fn each_log_file_is_put_whole_to_its_route_in_order() {
        let dir = tempfile::tempdir().unwrap();
        folder(dir.path());
        let (base, seen) = serve(vec![
            Reply::Answer(204, ""),
            Reply::Answer(200, r#"{"subtrajectories":1}"#),
            Reply::Answer(204, ""),
            Reply::Answer(200, r#"{"poses":2,"runs":1,"source":"walk"}"#),
        ]);
        let sent = fast(&base).upload_phone_logs("s1", dir.path()).unwrap();
        assert_eq!(
            sent.sent,
            [
                "trajectory.txt",
                "subtrajectories.csv",
                "anchors.csv",
                "walk.txt"
            ]
        );
        assert!(sent.unsupported.is_empty() && sent.missing.is_empty());
        let seen = seen.lock().unwrap();
        for (s, (name, content_type)) in seen.iter().zip(PHONE_LOG_FILES) {
            assert_eq!(s.method, "PUT");
            assert_eq!(s.path, format!("/v1/sessions/s1/{name}"));
            assert_eq!(s.header("content-type"), Some(content_type));
            assert_eq!(s.body, std::fs::read(dir.path().join(name)).unwrap());
        }
        assert_eq!(seen.len(), 4);
    }

    #[test]
    fn an_older_backend_without_the_routes_is_skipped_and_missing_files_are_not_sent() {
        let dir = tempfile::tempdir().unwrap();
        folder(dir.path());
        std::fs::remove_file(dir.path().join("anchors.csv")).unwrap();
        let (base, seen) = serve(vec![
            Reply::Answer(
                404,
                r#"{"error":{"code":"not_found","message":"no such route"}}"#,
            ),
            Reply::Answer(405, "{}"),
            Reply::Answer(
                404,
                r#"{"error":{"code":"not_found","message":"no such route"}}"#,
            ),
        ]);
        let sent = fast(&base).upload_phone_logs("s1", dir.path()).unwrap();
        assert!(sent.sent.is_empty());
        assert_eq!(
            sent.unsupported,
            ["trajectory.txt", "subtrajectories.csv", "walk.txt"]
        );
        assert_eq!(sent.missing, ["anchors.csv"]);
        // Not retried: one request per file.
        assert_eq!(seen.lock().unwrap().len(), 3);
    }

    #[test]
    fn a_refused_file_is_an_error_naming_it_with_the_servers_message() {
        let dir = tempfile::tempdir().unwrap();
        folder(dir.path());
        let (base, seen) = serve(vec![
            Reply::Answer(204, ""),
            Reply::Answer(
                422,
                r#"{"error":{"code":"invalid_content","message":"subtrajectories.csv line 2, column x: not a number"}}"#,
            ),
            Reply::Answer(204, ""),
        ]);
        let err = fast(&base).upload_phone_logs("s1", dir.path()).unwrap_err();
        match &err {
            Error::FileRefused {
                file,
                status,
                code,
                message,
            } => {
                assert_eq!(
                    (file.as_str(), *status, code.as_str()),
                    ("subtrajectories.csv", 422, "invalid_content")
                );
                assert_eq!(
                    message,
                    "subtrajectories.csv line 2, column x: not a number"
                );
            }
            other => panic!("unexpected {other:?}"),
        }
        assert_eq!(
            err.to_string(),
            "the server refused subtrajectories.csv (422 invalid_content): \
             subtrajectories.csv line 2, column x: not a number"
        );
        assert_eq!(err.status(), Some(422));
        // Nothing after the refused file.
        std::thread::sleep(Duration::from_millis(50));
        assert_eq!(seen.lock().unwrap().len(), 2);
    }

    #[test]
    fn a_bad_id_never_reaches_the_network_and_an_empty_folder_sends_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let client = fast("http://127.0.0.1:9");
        assert!(matches!(
            client.upload_phone_logs("../x", dir.path()),
            Err(Error::InvalidArgument(_))
        ));
        let sent = client.upload_phone_logs("s1", dir.path()).unwrap();
        assert_eq!(sent.missing.len(), 4);
        assert!(sent.sent.is_empty());
    }
}
