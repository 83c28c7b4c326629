//! Several API instances on one database: each instance's heartbeat, which instance plays
//! which session in flight, and the stop requests (cancel, delete) a client sent to another
//! instance than the one playing. An instance is alive while its heartbeat is newer than a
//! cutoff the caller gives (`now − --instance-timeout-s`); a session whose player is not
//! alive is adopted by exactly one other instance (a conditional update).

use crate::error::Error;

/// What a client asked of a session's playback through another instance, weakest first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum StopRequest {
    /// `POST …/estimate`: stop playing, estimate what was played ("estimate requested").
    Estimate,
    /// `POST …/cancel`: stop playing, estimate what was played ("cancelled by the client").
    Cancel,
    /// `DELETE`: stop playing and publish nothing; the receiving instance deletes it.
    Delete,
}

impl StopRequest {
    /// The stored name.
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            StopRequest::Estimate => "estimate",
            StopRequest::Cancel => "cancel",
            StopRequest::Delete => "delete",
        }
    }

    /// The inverse of [`StopRequest::as_str`]; `None` for a value no version writes.
    pub(crate) fn from_stored(name: &str) -> Option<StopRequest> {
        match name {
            "estimate" => Some(StopRequest::Estimate),
            "cancel" => Some(StopRequest::Cancel),
            "delete" => Some(StopRequest::Delete),
            _ => None,
        }
    }
}

/// SQL true of a session in flight, which one instance plays: a `sim` or `adb` session
/// `uploaded`, `playing` or `estimating`, or an `upload` session `estimating` (its final
/// estimate runs on one instance; adopted if that one dies).
pub(crate) const IN_FLIGHT: &str = "((playback <> 'upload' AND state IN ('uploaded', 'playing', \
     'estimating')) OR (playback = 'upload' AND state = 'estimating'))";

/// SQL that sets `sessions.stop_request` to the stronger of what it holds and the request
/// in parameter `new` (`$2`, `?2`): delete, then cancel, then estimate (both stores' SQL).
pub(crate) fn stronger_stop_request(new: &str) -> String {
    let rank = |value: &str| {
        format!(
            "CASE {value} WHEN 'delete' THEN 3 WHEN 'cancel' THEN 2 WHEN 'estimate' THEN 1 \
             ELSE 0 END"
        )
    };
    format!(
        "stop_request = CASE WHEN {} > {} THEN {new} ELSE stop_request END",
        rank(new),
        rank("stop_request")
    )
}

/// Which instance plays what, and who is alive. "In flight": see [`IN_FLIGHT`].
pub(crate) trait InstanceStore {
    /// Instance `instance` is alive at `now_ms` (its row made or renewed).
    fn heartbeat(&self, instance: &str, now_ms: i64) -> Result<(), Error>;
    /// Makes `instance` the player of in-flight session `id` unless another instance with a
    /// heartbeat at or after `alive_since_ms` plays it (checked in the same update, so of two
    /// instances claiming at once exactly one wins). Whether `instance` plays it now.
    fn claim_session(&self, id: &str, instance: &str, alive_since_ms: i64) -> Result<bool, Error>;
    /// `instance`'s job on session `id` ended: nobody plays it, and its stop request and
    /// progress are forgotten (a session another instance plays is left alone).
    fn release_session(&self, id: &str, instance: &str) -> Result<(), Error>;
    /// The instance playing session `id`, if any.
    fn session_player(&self, id: &str) -> Result<Option<String>, Error>;
    /// Whether `instance`'s heartbeat is at or after `alive_since_ms`.
    fn is_alive(&self, instance: &str, alive_since_ms: i64) -> Result<bool, Error>;
    /// In-flight sessions, oldest first, whose player has no heartbeat at or after
    /// `alive_since_ms`, or that nobody plays (`None`): what an adopter looks at.
    fn unplayed_sessions(
        &self,
        alive_since_ms: i64,
    ) -> Result<Vec<(String, Option<String>)>, Error>;
    /// Records `request` on session `id` for its player to see (a delete outranks a cancel,
    /// which outranks an estimate).
    fn request_stop(&self, id: &str, request: StopRequest) -> Result<(), Error>;
    /// The stop requests on the sessions in flight `instance` plays, oldest session first.
    fn stop_requests(&self, instance: &str) -> Result<Vec<(String, StopRequest)>, Error>;
    /// Publishes `instance`'s view of the progress of session `id`, which it plays (a JSON
    /// document, `jobs::progress_view`; `None` clears it), for the other instances'
    /// status answers. A session another instance plays now is left alone.
    fn publish_progress(&self, id: &str, instance: &str, view: Option<&str>) -> Result<(), Error>;
    /// The progress its player last published for session `id`, with the player's id; `None`
    /// when nobody plays it or its player published nothing.
    fn published_progress(&self, id: &str) -> Result<Option<(String, String)>, Error>;
    /// Marks `interrupted` the running jobs of `instance` (when given), of instances with no
    /// heartbeat at or after `alive_since_ms`, and of none (older versions); how many.
    fn interrupt_jobs(&self, instance: Option<&str>, alive_since_ms: i64) -> Result<usize, Error>;
}
