//! The only writer of a session's state: every transition is a method here, checked against
//! [`Step::next`] inside the transaction that writes it, so two requests racing for one step
//! cannot both take it. A refused step is [`Error::Transition`], a 409 naming the state.

use rusqlite::{OptionalExtension, params};

use crate::Error;
use crate::config::PlaybackKind;
use crate::session::state::{SessionState, Step};
use crate::storage::db::{CachedSql, Db, now_ms};

/// The transitions of the sessions in one database.
#[derive(Clone, Copy)]
pub(crate) struct Lifecycle<'a> {
    db: &'a Db,
}

/// What a step writes besides the state.
enum Also<'a> {
    Nothing,
    RecordingBytes(u64),
    ResultsTrials(u32),
    StopReason(&'a str),
    Error(&'a str),
}

impl<'a> Lifecycle<'a> {
    pub fn new(db: &'a Db) -> Lifecycle<'a> {
        Lifecycle { db }
    }

    /// A whole recording is in place. Returns the state before: `created` means it is the
    /// first, and a sim or adb session's playback is to start.
    pub fn accept_recording(&self, id: &str, bytes: u64) -> Result<SessionState, Error> {
        self.take(id, Step::AcceptRecording, Also::RecordingBytes(bytes))
    }

    /// The playback job starts: `uploaded → playing`.
    pub fn start_playing(&self, id: &str) -> Result<(), Error> {
        self.take(id, Step::StartPlaying, Also::Nothing).map(drop)
    }

    /// After a restart: a sim or adb session's job goes on playing; an `upload` session's
    /// final estimate runs again.
    pub fn resume(&self, id: &str) -> Result<(), Error> {
        self.take(id, Step::Resume, Also::Nothing).map(drop)
    }

    /// The final estimate starts: `playing → estimating` (sim, adb), `created|uploaded →
    /// estimating` (`upload`).
    pub fn start_estimating(&self, id: &str) -> Result<(), Error> {
        self.take(id, Step::StartEstimating, Also::Nothing)
            .map(drop)
    }

    /// An estimate over `trials` trials is published (its files are in place).
    pub fn publish(&self, id: &str, trials: u32) -> Result<(), Error> {
        self.take(id, Step::Publish, Also::ResultsTrials(trials))
            .map(drop)
    }

    /// Playback stops before its last trial; `reason` says why (`stop_reason`).
    pub fn stop(&self, id: &str, reason: &str) -> Result<(), Error> {
        self.take(id, Step::Stop, Also::StopReason(reason))
            .map(drop)
    }

    /// The final results are published: `estimating → done`.
    pub fn finish(&self, id: &str) -> Result<(), Error> {
        self.take(id, Step::Finish, Also::Nothing).map(drop)
    }

    /// The session ends without final results; `why` becomes its `error`.
    pub fn fail(&self, id: &str, why: &str) -> Result<(), Error> {
        self.take(id, Step::Fail, Also::Error(why)).map(drop)
    }

    /// A session whose row cannot be read (a value no version writes: `trials_total = -5`,
    /// an unknown playback) fails with `why`, whatever its state: the one step that needs no
    /// typed row, so one bad row never stops the server.
    pub fn fail_unreadable(&self, id: &str, why: &str) -> Result<(), Error> {
        self.db.with(|c| {
            c.execute_cached(
                "UPDATE sessions SET state = ?2, error = ?3, finished_ms = ?4 WHERE id = ?1",
                params![id, SessionState::Failed.as_str(), why, now_ms()],
            )
        })?;
        Ok(())
    }

    /// Checks `step` against the session's state and writes the state it leads to, with what
    /// the step records. Returns the state before.
    fn take(&self, id: &str, step: Step, also: Also<'_>) -> Result<SessionState, Error> {
        self.db.transaction(|tx| {
            let row: Option<(String, String)> = tx
                .query_row_cached(
                    "SELECT state, playback FROM sessions WHERE id = ?1",
                    [id],
                    |r| Ok((r.get(0)?, r.get(1)?)),
                )
                .optional()?;
            let (state, playback) =
                row.ok_or_else(|| Error::NotFound(format!("no session {id:?}")))?;
            let unknown = |column: &str, value: &str| {
                Error::Internal(format!("session {id}: unknown {column} {value:?}"))
            };
            let before = SessionState::from_wire(&state).ok_or_else(|| unknown("state", &state))?;
            let playback = playback
                .parse::<PlaybackKind>()
                .map_err(|_| unknown("playback", &playback))?;
            let after = step.next(before, playback).ok_or(Error::Transition {
                session: id.to_string(),
                state: before.as_str(),
                action: step.describe(),
            })?;
            let finished = after.is_finished().then(now_ms);
            tx.execute_cached(
                "UPDATE sessions SET state = ?2, finished_ms = COALESCE(?3, finished_ms) WHERE id = ?1",
                params![id, after.as_str(), finished],
            )?;
            match also {
                Also::Nothing => 0,
                Also::RecordingBytes(bytes) => tx.execute_cached(
                    "UPDATE sessions SET recording_bytes = ?2 WHERE id = ?1",
                    params![id, bytes as i64],
                )?,
                Also::ResultsTrials(trials) => tx.execute_cached(
                    "UPDATE sessions SET results_trials = ?2 WHERE id = ?1",
                    params![id, trials],
                )?,
                Also::StopReason(reason) => tx.execute_cached(
                    "UPDATE sessions SET stop_reason = ?2 WHERE id = ?1",
                    params![id, reason],
                )?,
                Also::Error(why) => tx.execute_cached(
                    "UPDATE sessions SET error = ?2 WHERE id = ?1",
                    params![id, why],
                )?,
            };
            Ok(before)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::estimate_settings::EstimateSettings;
    use crate::session::record::NewSession;

    fn db_with(playback: PlaybackKind) -> (tempfile::TempDir, Db) {
        let dir = tempfile::tempdir().unwrap();
        let db = Db::open(&dir.path().join("sitar.db")).unwrap();
        let new = NewSession {
            idempotency_key: None,
            trials_total: 5,
            playback,
            settings: EstimateSettings::defaults(&crate::ServerConfig::new("unused")).unwrap(),
            adaptive_min: None,
            adaptive_k: 3,
            legacy: false,
            owner: None,
        };
        db.insert_session("a", &new).unwrap();
        (dir, db)
    }

    #[test]
    fn a_sim_session_walks_its_life_and_records_what_each_step_says() {
        let (_dir, db) = db_with(PlaybackKind::Sim);
        let life = Lifecycle::new(&db);
        assert_eq!(
            life.accept_recording("a", 42).unwrap(),
            SessionState::Created
        );
        life.start_playing("a").unwrap();
        life.publish("a", 2).unwrap();
        life.stop("a", "adaptive stop").unwrap();
        life.start_estimating("a").unwrap();
        life.publish("a", 3).unwrap();
        let estimating = db.session("a").unwrap().unwrap();
        assert_eq!(estimating.state, SessionState::Estimating);
        assert_eq!(estimating.recording_bytes, Some(42));
        assert_eq!(estimating.results_trials, 3);
        assert_eq!(estimating.stop_reason.as_deref(), Some("adaptive stop"));
        life.finish("a").unwrap();
        assert_eq!(db.session("a").unwrap().unwrap().state, SessionState::Done);
        assert_eq!(
            db.latest_session(true, false, None).unwrap().as_deref(),
            Some("a")
        );
    }

    #[test]
    fn a_refused_step_names_the_state_and_writes_nothing() {
        let (_dir, db) = db_with(PlaybackKind::Upload);
        let life = Lifecycle::new(&db);
        life.start_estimating("a").unwrap();
        let err = life.accept_recording("a", 7).unwrap_err();
        assert!(
            matches!(
                err,
                Error::Transition {
                    state: "estimating",
                    ..
                }
            ),
            "{err:?}"
        );
        assert_eq!(err.status_and_code().0, axum::http::StatusCode::CONFLICT);
        assert_eq!(
            err.to_string(),
            "session a is estimating: it cannot take a recording"
        );
        assert_eq!(db.session("a").unwrap().unwrap().recording_bytes, None);
        life.fail("a", "disk full").unwrap();
        let failed = db.session("a").unwrap().unwrap();
        assert_eq!(failed.state, SessionState::Failed);
        assert_eq!(failed.error.as_deref(), Some("disk full"));
        // A failed session stays failed: a second failure does not rewrite its reason.
        assert!(life.fail("a", "again").is_err());
        assert!(matches!(life.finish("b"), Err(Error::NotFound(_))));
    }
}
