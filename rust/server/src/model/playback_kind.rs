//! How a session's trials are played: the kinds of playback a session names.

/// Where a session's trials come from; the server's default serves sessions that name none
/// (and the legacy routes). Stored typed with every session.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlaybackKind {
    /// Real phones over adb.
    Adb,
    /// The `sitar-sim` replay (demo, tests).
    Sim,
    /// Trials come from outside via `POST /v1/sessions/{id}/trials`.
    Upload,
}

impl PlaybackKind {
    /// The wire name: `adb`, `sim` or `upload`.
    pub fn as_str(self) -> &'static str {
        match self {
            PlaybackKind::Adb => "adb",
            PlaybackKind::Sim => "sim",
            PlaybackKind::Upload => "upload",
        }
    }
}

impl std::str::FromStr for PlaybackKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "adb" => Ok(PlaybackKind::Adb),
            "sim" => Ok(PlaybackKind::Sim),
            "upload" => Ok(PlaybackKind::Upload),
            other => Err(format!(
                "unknown playback {other:?}: expected adb, sim or upload"
            )),
        }
    }
}
