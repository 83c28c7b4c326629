use serde::{Deserialize, Serialize};

/// What `POST /v1/sessions` takes: how many trials, which statistic, which playback backend.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct NewSession {
    /// Number of playback trials (≥ 2 for an estimate).
    pub trials: u32,
    /// Statistic: `mean`, `median`, `trim_mean_10|20|30|40`, `mean_inliers`.
    pub setting: String,
    /// Playback backend: `adb`, `sim` or `upload`.
    pub playback: String,
    /// Frames per estimate window (the RPE's delta); `None` leaves the server's default (10).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window_frames: Option<u32>,
    /// What the estimate measures: `"trans_part"` (metres) or `"angle_deg"`; `None` leaves
    /// the server's default (`trans_part`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose_relation: Option<String>,
}

/// Optional per-session extras beyond [`NewSession`] (adaptive stopping, calibration);
/// `None` takes the server's default.
/// Build one with `..SessionOptions::default()` so later options need no change.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct SessionOptions {
    /// Adaptive stopping: finish early once no window's class changed over the
    /// last `adaptive_k` finished trials, but never before this many trials.
    /// `None` runs every trial.
    pub adaptive_min_trials: Option<u32>,
    /// Window of finished trials over which classes must be stable (server default 3).
    pub adaptive_k: Option<u32>,
    /// The calibration the server applies to every estimate of the session (one it was
    /// started with: `sitar serve --calibration NAME=FILE`); with one that has a model for
    /// one run, the phone's `walk.txt` gives first results before any replay.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<String>,
}

/// Which world frame a session's poses are in: the phone's coordinate convention and the
/// venue whose shared frame the session joins (`POST /v1/sessions` keys `"convention"` and
/// `"venue"`). `None` sends nothing, so a backend that predates venues still takes the session;
/// build one with `..SessionFrame::default()`.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct SessionFrame {
    /// `"unity"` or `"arcore"` (the session config's `convention`); `None` leaves the
    /// server's default (`unity`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub convention: Option<String>,
    /// The venue the session joins (an id from `POST /v1/venues`, `v` and 16 hex digits);
    /// `None` joins none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub venue: Option<String>,
}

/// Life cycle of a session on the server.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SessionState {
    /// Created, nothing uploaded yet.
    Created,
    /// Recording uploaded, playback not started.
    Uploaded,
    /// Playback trials running.
    Playing,
    /// Final estimation running.
    Estimating,
    /// Results available.
    Done,
    /// Failed; `error` says why.
    Failed,
}

impl SessionState {
    /// The wire name (`"created"`, …, `"failed"`).
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

    /// Whether the session will not change any more.
    pub fn is_finished(self) -> bool {
        matches!(self, SessionState::Done | SessionState::Failed)
    }
}

impl std::fmt::Display for SessionState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// `GET /v1/sessions/{id}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SessionStatus {
    /// Server-made session id.
    pub id: String,
    /// Where the session is in its life cycle.
    pub state: SessionState,
    /// 0.0 … 1.0.
    pub progress: f64,
    /// Estimated seconds until done, when known.
    pub eta_s: Option<f64>,
    /// Trials finished so far.
    pub trials_done: u32,
    /// Trials planned.
    pub trials_total: u32,
    /// Why the session failed, if it did.
    pub error: Option<String>,
    /// Number of trials behind the latest published (possibly progressive) results; 0 = none yet.
    #[serde(default)]
    pub results_trials: u32,
    /// Why playback stopped before `trials_total` (adaptive stopping), if it did.
    #[serde(default)]
    pub stop_reason: Option<String>,
    /// Playback backend of the session (`adb`, `sim`, `upload`), when the server says.
    #[serde(default)]
    pub playback: Option<String>,
    /// Frames per results window, when the server says.
    #[serde(default)]
    pub window_frames: Option<u32>,
    /// Pose relation of the estimate (`trans_part`, `angle_deg`), when the server says.
    #[serde(default)]
    pub pose_relation: Option<String>,
    /// The venue the session joined (`None` in none, or from a backend without venues).
    #[serde(default)]
    pub venue: Option<String>,
    /// The session's alignment to its venue's frame, from the `anchors.csv` the phone sent
    /// (`None` in no venue, before the phone's log arrived, or from a backend without venues).
    #[serde(default)]
    pub alignment: Option<VenueAlignment>,
}

/// How a session sits in its venue's frame (`"alignment"` of `GET /v1/sessions/{id}`):
/// sitar-core's alignment from the session's full observations of the venue's anchor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum VenueAlignment {
    /// Aligned from `observations` full observations of `anchor`.
    Aligned {
        /// The venue's anchor id.
        anchor: String,
        /// Full observations kept (outliers rejected).
        observations: u32,
        /// RMS position deviation of the kept observations, metres.
        position_spread_m: f64,
        /// RMS heading deviation of the kept observations, degrees.
        heading_spread_deg: f64,
    },
    /// Not aligned, and why (e.g. no full observation of the anchor): the session stays out
    /// of the venue's map.
    NotAligned {
        /// The server's reason.
        error: String,
    },
}
