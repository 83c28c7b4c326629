//! The only writer of a session's state: every transition is a method here, checked against
//! [`Step::next`] inside the transaction that writes it, so two requests racing for one step
//! cannot both take it. A refused step is [`Error::Transition`], a 409 naming the state.

use crate::error::Error;
use crate::model::{SessionState, Step};
use crate::storage::{SessionStore, StepRecord};

/// The transitions of the sessions in one store.
#[derive(Clone, Copy)]
pub(crate) struct Lifecycle<'a> {
    store: &'a dyn SessionStore,
}

impl<'a> Lifecycle<'a> {
    pub fn new(store: &'a dyn SessionStore) -> Lifecycle<'a> {
        Lifecycle { store }
    }

    /// A whole recording is in place. Returns the state before: `created` means it is the
    /// first, and a sim or adb session's playback is to start.
    pub fn accept_recording(&self, id: &str, bytes: u64) -> Result<SessionState, Error> {
        self.take(id, Step::AcceptRecording, StepRecord::RecordingBytes(bytes))
    }

    /// The playback job starts: `uploaded → playing`.
    pub fn start_playing(&self, id: &str) -> Result<(), Error> {
        self.take(id, Step::StartPlaying, StepRecord::Nothing)
            .map(drop)
    }

    /// After a restart: a sim or adb session's job goes on playing; an `upload` session's
    /// final estimate runs again.
    pub fn resume(&self, id: &str) -> Result<(), Error> {
        self.take(id, Step::Resume, StepRecord::Nothing).map(drop)
    }

    /// The final estimate starts: `playing → estimating` (sim, adb), `created|uploaded →
    /// estimating` (`upload`).
    pub fn start_estimating(&self, id: &str) -> Result<(), Error> {
        self.take(id, Step::StartEstimating, StepRecord::Nothing)
            .map(drop)
    }

    /// An estimate over `trials` trials is published (its files are in place).
    pub fn publish(&self, id: &str, trials: u32) -> Result<(), Error> {
        self.take(id, Step::Publish, StepRecord::ResultsTrials(trials))
            .map(drop)
    }

    /// Playback stops before its last trial; `reason` says why (`stop_reason`).
    pub fn stop(&self, id: &str, reason: &str) -> Result<(), Error> {
        self.take(id, Step::Stop, StepRecord::StopReason(reason))
            .map(drop)
    }

    /// The final results are published: `estimating → done`.
    pub fn finish(&self, id: &str) -> Result<(), Error> {
        self.take(id, Step::Finish, StepRecord::Nothing).map(drop)
    }

    /// The session ends without final results; `why` becomes its `error`.
    pub fn fail(&self, id: &str, why: &str) -> Result<(), Error> {
        self.take(id, Step::Fail, StepRecord::Error(why)).map(drop)
    }

    /// A session whose row cannot be read (a value no version writes: `trials_total = -5`,
    /// an unknown playback) fails with `why`, whatever its state: the one step that needs no
    /// typed row, so one bad row never stops the server.
    pub fn fail_unreadable(&self, id: &str, why: &str) -> Result<(), Error> {
        self.store.fail_unreadable(id, why)
    }

    /// Checks `step` against the session's state and writes the state it leads to, with what
    /// the step records (atomically, in the store). Returns the state before.
    fn take(&self, id: &str, step: Step, also: StepRecord<'_>) -> Result<SessionState, Error> {
        self.store.transition(id, step, also)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::PlaybackKind;
    use crate::storage::sqlite::SqliteStore;

    fn db_with(playback: PlaybackKind) -> (tempfile::TempDir, SqliteStore) {
        let dir = tempfile::tempdir().unwrap();
        let db = SqliteStore::open(&dir.path().join("sitar.db")).unwrap();
        let new = crate::storage::conformance::new_session(None, playback, None);
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
