//! The states of a session and the one table of which step each allows.

use crate::model::PlaybackKind;

/// Where a session is in its life (the wire names are those of `GET /v1/sessions/{id}`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum SessionState {
    /// Made; no recording yet (an `upload` session may already take trials).
    Created,
    /// The recording is in place; playback has not started (`upload`: waiting for trials).
    Uploaded,
    /// Playback phones are running trials.
    Playing,
    /// The final estimate runs.
    Estimating,
    /// The final results are published.
    Done,
    /// Ended without final results; `error` says why.
    Failed,
}

impl SessionState {
    /// Every state, in the order a session passes them.
    pub const ALL: [SessionState; 6] = [
        SessionState::Created,
        SessionState::Uploaded,
        SessionState::Playing,
        SessionState::Estimating,
        SessionState::Done,
        SessionState::Failed,
    ];

    /// The wire name: `created`, `uploaded`, `playing`, `estimating`, `done` or `failed`.
    pub fn as_str(self) -> &'static str {
        match self {
            SessionState::Created => "created",
            SessionState::Uploaded => "uploaded",
            SessionState::Playing => "playing",
            SessionState::Estimating => "estimating",
            SessionState::Done => "done",
            SessionState::Failed => "failed",
        }
    }

    /// The inverse of [`SessionState::as_str`].
    pub fn from_wire(name: &str) -> Option<SessionState> {
        SessionState::ALL.into_iter().find(|s| s.as_str() == name)
    }

    /// Done or failed: nothing changes any more.
    pub fn is_finished(self) -> bool {
        matches!(self, SessionState::Done | SessionState::Failed)
    }
}

impl std::fmt::Display for SessionState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Something asked of a session. Each step either moves it to a state ([`Step::next`]) or is
/// refused in its current one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Step {
    /// A whole recording arrives (sim, adb: once, from `created`; `upload`: may be replaced
    /// until the estimate starts).
    AcceptRecording,
    /// A trial arrives through the API (`upload` sessions, until the estimate starts).
    AddTrial,
    /// The playback job starts.
    StartPlaying,
    /// After a restart, the job of a session a dead process left in flight goes on.
    Resume,
    /// The final estimate starts (sim, adb: when playback ends; `upload`: on request).
    StartEstimating,
    /// A (progressive or final) estimate is published; before playback, the estimate from
    /// the phone's walk alone.
    Publish,
    /// Playback stops before its last trial, with a reason.
    Stop,
    /// The final estimate is published.
    Finish,
    /// The session ends without final results.
    Fail,
}

impl Step {
    /// What a refusal says the session cannot do.
    pub fn describe(self) -> &'static str {
        match self {
            Step::AcceptRecording => "take a recording",
            Step::AddTrial => "take more trials",
            Step::StartPlaying => "start playing",
            Step::Resume => "resume",
            Step::StartEstimating => "start estimating",
            Step::Publish => "publish results",
            Step::Stop => "stop its playback",
            Step::Finish => "finish",
            Step::Fail => "fail",
        }
    }

    /// The state after this step from `state`, or `None` when `state` does not allow it.
    /// This table is the whole life cycle:
    ///
    /// ```text
    /// sim, adb:  created → uploaded → playing → estimating → done
    /// upload:    created ⇄ uploaded (trials arrive) → estimating → done
    /// any state but done: → failed
    /// ```
    pub fn next(self, state: SessionState, playback: PlaybackKind) -> Option<SessionState> {
        use SessionState::*;
        let upload = playback == PlaybackKind::Upload;
        match (self, state) {
            (Step::AcceptRecording, Created) => Some(Uploaded),
            (Step::AcceptRecording, Uploaded) if upload => Some(Uploaded),
            (Step::AddTrial, Created | Uploaded) if upload => Some(state),
            (Step::StartPlaying, Uploaded) if !upload => Some(Playing),
            (Step::Resume, Playing | Estimating) if !upload => Some(Playing),
            (Step::Resume, Estimating) if upload => Some(Estimating),
            (Step::StartEstimating, Playing) if !upload => Some(Estimating),
            (Step::StartEstimating, Created | Uploaded) if upload => Some(Estimating),
            // Before playback, too: the first results from the phone's walk (with a
            // calibration), an `upload` session's progressive estimates.
            (Step::Publish, Created | Uploaded | Playing | Estimating) => Some(state),
            (Step::Stop, Playing | Estimating) if !upload => Some(state),
            (Step::Finish, Estimating) => Some(Done),
            (Step::Fail, Created | Uploaded | Playing | Estimating) => Some(Failed),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use PlaybackKind::*;
    use SessionState::*;

    #[test]
    fn wire_names_round_trip() {
        for state in SessionState::ALL {
            assert_eq!(SessionState::from_wire(state.as_str()), Some(state));
        }
        assert_eq!(SessionState::from_wire("paused"), None);
    }

    /// Walks the happy paths and checks that every step outside them is refused.
    #[test]
    fn the_table_allows_the_documented_paths_and_nothing_else() {
        let path = |playback, steps: &[(Step, SessionState)]| {
            let mut state = Created;
            for &(step, expected) in steps {
                state = step
                    .next(state, playback)
                    .unwrap_or_else(|| panic!("{step:?} refused in {state} ({playback:?})"));
                assert_eq!(state, expected, "{step:?}");
            }
            state
        };
        for playback in [Sim, Adb] {
            let done = path(
                playback,
                &[
                    // The walk's results, before the recording and before playback.
                    (Step::Publish, Created),
                    (Step::AcceptRecording, Uploaded),
                    (Step::Publish, Uploaded),
                    (Step::StartPlaying, Playing),
                    (Step::Publish, Playing),
                    (Step::Stop, Playing),
                    (Step::Resume, Playing),
                    (Step::StartEstimating, Estimating),
                    (Step::Resume, Playing),
                    (Step::StartEstimating, Estimating),
                    (Step::Publish, Estimating),
                    (Step::Finish, Done),
                ],
            );
            assert_eq!(done, Done);
            // Their trials come from the phones, and the recording is set once.
            for state in SessionState::ALL {
                assert_eq!(Step::AddTrial.next(state, playback), None);
            }
            assert_eq!(Step::AcceptRecording.next(Uploaded, playback), None);
            assert_eq!(Step::StartEstimating.next(Uploaded, playback), None);
        }
        let done = path(
            Upload,
            &[
                (Step::AddTrial, Created),
                (Step::Publish, Created),
                (Step::AcceptRecording, Uploaded),
                (Step::AcceptRecording, Uploaded),
                (Step::AddTrial, Uploaded),
                (Step::StartEstimating, Estimating),
                (Step::Resume, Estimating),
                (Step::Finish, Done),
            ],
        );
        assert_eq!(done, Done);
        for state in [Estimating, Done, Failed] {
            assert_eq!(Step::AddTrial.next(state, Upload), None, "{state}");
            assert_eq!(Step::AcceptRecording.next(state, Upload), None, "{state}");
        }
        assert_eq!(Step::StartPlaying.next(Uploaded, Upload), None);
        // Finished sessions take no step at all; anything unfinished can fail.
        for playback in [Sim, Adb, Upload] {
            for state in [Done, Failed] {
                for step in [
                    Step::AcceptRecording,
                    Step::AddTrial,
                    Step::StartPlaying,
                    Step::Resume,
                    Step::StartEstimating,
                    Step::Publish,
                    Step::Stop,
                    Step::Finish,
                    Step::Fail,
                ] {
                    assert_eq!(step.next(state, playback), None, "{step:?} in {state}");
                }
            }
            for state in [Created, Uploaded, Playing, Estimating] {
                assert_eq!(Step::Fail.next(state, playback), Some(Failed));
                let finish = Step::Finish.next(state, playback);
                assert_eq!(finish, (state == Estimating).then_some(Done), "{state}");
            }
        }
    }
}
