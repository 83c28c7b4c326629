//! A session as the server knows it: the typed row of the `sessions` table.

use sitar_core::Convention;

use crate::model::{
    PlaybackKind,
    estimate_settings::EstimateSettings,
    session_state::{SessionState, Step},
};

/// One session, every column typed.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Session {
    /// Server-made id (`s` + 16 hex digits).
    pub id: String,
    /// Where it is in its life.
    pub state: SessionState,
    /// Where its trials come from.
    pub playback: PlaybackKind,
    /// Trials planned.
    pub trials_total: u32,
    /// How its trials are estimated.
    pub settings: EstimateSettings,
    /// Why it failed.
    pub error: Option<String>,
    /// Why playback stopped before `trials_total`.
    pub stop_reason: Option<String>,
    /// Adaptive stopping: at least this many trials (`None`: off).
    pub adaptive_min: Option<u32>,
    /// Adaptive stopping: classes unchanged over this many trials.
    pub adaptive_k: u32,
    /// Size of the accepted recording.
    pub recording_bytes: Option<u64>,
    /// Trials behind the latest published results (0: none yet).
    pub results_trials: u32,
    /// Created by the legacy `POST /recording`.
    pub legacy: bool,
    /// The token that created it (`None`: made without authentication).
    pub owner: Option<i64>,
    /// The venue it was recorded in (`None`: none, or the venue was deleted).
    pub venue: Option<String>,
    /// The coordinate convention of the phone that recorded it.
    pub convention: Convention,
    /// The calibration its estimates are calibrated with, by name (`None`: uncalibrated).
    pub calibration: Option<String>,
}

impl Session {
    /// Whether `step` is allowed now.
    pub fn allows(&self, step: Step) -> bool {
        step.next(self.state, self.playback).is_some()
    }

    /// `Ok` when `step` is allowed now, else the 409 that names the state.
    pub fn require(&self, step: Step) -> Result<(), crate::error::Error> {
        if self.allows(step) {
            Ok(())
        } else {
            Err(crate::error::Error::Transition {
                session: self.id.clone(),
                state: self.state.as_str(),
                action: step.describe(),
            })
        }
    }

    /// Whether no job of its own works on it, so it may be deleted: made and never uploaded,
    /// finished, or an `upload` session waiting for trials. (A playback job or a running
    /// estimate is checked separately: see `deletion.rs`.)
    pub fn is_idle(&self) -> bool {
        match self.state {
            SessionState::Created | SessionState::Done | SessionState::Failed => true,
            SessionState::Uploaded => self.playback == PlaybackKind::Upload,
            SessionState::Playing | SessionState::Estimating => false,
        }
    }
}

/// What a new session needs.
#[derive(Debug, Clone)]
pub(crate) struct NewSession<'a> {
    /// A client-made key: a request repeated with it gets the first session back.
    pub idempotency_key: Option<&'a str>,
    pub trials_total: u32,
    pub playback: PlaybackKind,
    pub settings: EstimateSettings,
    pub adaptive_min: Option<u32>,
    pub adaptive_k: u32,
    pub legacy: bool,
    /// The token that created it (`None`: made without authentication).
    pub owner: Option<i64>,
    /// The venue it joins (checked by the caller: one the token may see).
    pub venue: Option<&'a str>,
    /// The phone's coordinate convention (a venue's sessions share one).
    pub convention: Convention,
    /// The calibration asked for (checked by the caller: one the server has, fitted for the
    /// session's settings).
    pub calibration: Option<&'a str>,
}
