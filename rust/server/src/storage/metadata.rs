//! The metadata store: every row the server keeps (sessions, trials, jobs, devices, tokens,
//! share links, per-token usage, idempotency keys, venues and their members), as operations
//! named by what they mean.
//! No SQL and no connection type crosses this seam; [`super::sqlite::SqliteStore`] is the
//! embedded implementation (`DATA/sitar.db`), and `storage::conformance` is the test suite
//! every implementation passes.
//!
//! The store is split by concern into small traits; [`MetadataStore`] is all of them, and the
//! server holds an `Arc<dyn MetadataStore>`. A module imports the concern traits it uses, so
//! its imports say which rows it touches.

use crate::error::Error;
use crate::model::{
    Caller, NewSession, NewVenue, Role, Session, SessionState, Step, TokenInfo, UsageFull, Venue,
};
use crate::storage::deletes::{Claim, DeleteStore};
use crate::storage::instances::InstanceStore;

/// How a job ended (a job is `running`, then one of these; also `interrupted` when its
/// instance restarts, or another adopts its session, and finds it left running by a dead
/// process).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum JobEnd {
    Done,
    Failed,
    /// Its session was adopted by another instance while this one was silent.
    Interrupted,
}

impl JobEnd {
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            JobEnd::Done => "done",
            JobEnd::Failed => "failed",
            JobEnd::Interrupted => "interrupted",
        }
    }
}

/// A playback device as last reported: serial, state, the session it plays (if any), last
/// seen (ms since the Unix epoch).
pub(crate) type DeviceRow = (String, String, Option<String>, i64);

/// A session row the server cannot read (a value no version writes).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Unreadable {
    pub id: String,
    /// What is wrong with it, naming the column.
    pub why: String,
}

/// Sessions read from the store, and the rows that could not be read (skipped).
#[derive(Debug, Default)]
pub(crate) struct Rows {
    pub sessions: Vec<Session>,
    pub unreadable: Vec<Unreadable>,
}

/// What a state transition records besides the state.
#[derive(Debug, Clone, Copy)]
pub(crate) enum StepRecord<'a> {
    Nothing,
    RecordingBytes(u64),
    ResultsTrials(u32),
    StopReason(&'a str),
    Error(&'a str),
}

/// Session rows: created, read, listed, moved through their states, deleted.
pub(crate) trait SessionStore {
    /// Inserts a session (state `created`), or returns the one created earlier with the same
    /// idempotency key. The bool is true when a new row was made.
    fn insert_session(&self, id: &str, new: &NewSession<'_>) -> Result<(String, bool), Error>;
    /// Session `id`, if it exists.
    fn session(&self, id: &str) -> Result<Option<Session>, Error>;
    /// The newest `limit` sessions, newest first; of token `owner` only when given. Rows
    /// that cannot be read are logged and left out.
    fn recent_sessions(&self, owner: Option<i64>, limit: u32) -> Result<Vec<Session>, Error>;
    /// As [`SessionStore::recent_sessions`], with the unreadable rows named.
    fn recent_rows(&self, owner: Option<i64>, limit: u32) -> Result<Rows, Error>;
    /// Sessions in any of `states`, oldest first (in the order they were created).
    fn sessions_in(&self, states: &[SessionState]) -> Result<Rows, Error>;
    /// Sessions past a retention that ends at `cutoff_ms` (ms since the epoch): finished
    /// before it, or created before it and idle since (never uploaded, or an `upload` session
    /// still waiting for trials).
    fn expired(&self, cutoff_ms: i64) -> Result<Vec<String>, Error>;
    /// The newest session (by finish time when `done_only`), of the legacy routes when
    /// `legacy_only`, of token `owner` when given.
    fn latest_session(
        &self,
        done_only: bool,
        legacy_only: bool,
        owner: Option<i64>,
    ) -> Result<Option<String>, Error>;
    /// When `session` was created (ms since the Unix epoch).
    fn session_created_ms(&self, session: &str) -> Result<Option<i64>, Error>;
    /// Removes a session with its trials, jobs and share links (devices forget it), all or
    /// nothing, and records its bytes as an unfinished delete held by `claim`
    /// ([`DeleteStore`]). Returns whether it existed (nothing is recorded when it did not).
    fn delete_session(&self, id: &str, claim: Claim<'_>) -> Result<bool, Error>;
    /// Takes `step` if the session's state allows it ([`Step::next`], checked atomically with
    /// the write, so two racing requests cannot both take one step) and records `record`.
    /// Returns the state before; a refused step is [`Error::Transition`]. Only
    /// `session::lifecycle` calls it.
    fn transition(
        &self,
        id: &str,
        step: Step,
        record: StepRecord<'_>,
    ) -> Result<SessionState, Error>;
    /// Fails a session whose row cannot be read, whatever its state (`why` becomes its
    /// error). Only `session::lifecycle` calls it.
    fn fail_unreadable(&self, id: &str, why: &str) -> Result<(), Error>;
}

/// The trials of each session: their order, sources and idempotency keys.
pub(crate) trait TrialStore {
    /// Adds a trial under the next index and calls `store` with that index before the row is
    /// committed (an error from `store` adds nothing). With a key already used in this
    /// session, nothing is added and the earlier index comes back with `false`.
    fn add_trial(
        &self,
        session: &str,
        key: Option<&str>,
        play_index: Option<u32>,
        poses: usize,
        source: &str,
        store: &mut dyn FnMut(u32) -> Result<(), Error>,
    ) -> Result<(u32, bool), Error>;
    /// How many trials `session` has.
    fn trial_count(&self, session: &str) -> Result<u32, Error>;
    /// (storage index, playback index) of a session's trials in playback order, the order
    /// the estimate uses (trials of parallel devices arrive out of order).
    fn trials_in_order(&self, session: &str) -> Result<Vec<(u32, u32)>, Error>;
    /// Which phone (trial `source`: `adb:SERIAL`, `sim:N`, or the uploaded file) played which
    /// trials of `session`, in first-played order.
    fn trial_sources(&self, session: &str) -> Result<Vec<(String, Vec<u32>)>, Error>;
}

/// The jobs run on sessions (playback, estimates), for status and restarts.
pub(crate) trait JobStore {
    /// A `kind` job starts on `session`, run by instance `instance`; its id.
    fn start_job(&self, session: &str, kind: &str, instance: &str) -> Result<i64, Error>;
    /// Job `job` ended.
    fn finish_job(&self, job: i64, end: JobEnd, error: Option<&str>) -> Result<(), Error>;
    /// (kind, state) of `session`'s jobs, oldest first.
    fn jobs_of(&self, session: &str) -> Result<Vec<(String, String)>, Error>;
}

/// The playback devices the server has seen.
pub(crate) trait DeviceStore {
    /// Device `serial` is in `state`, playing `session` if given (seen now).
    fn upsert_device(&self, serial: &str, state: &str, session: Option<&str>) -> Result<(), Error>;
    /// Every device seen, by serial.
    fn devices(&self) -> Result<Vec<DeviceRow>, Error>;
}

/// Access tokens and share links; only their hashes are kept.
pub(crate) trait TokenStore {
    /// Stores `token`'s hash under `name`; a name in use is a conflict.
    fn insert_token(&self, name: &str, role: Role, token: &str) -> Result<(), Error>;
    /// Stores `token` under `name`, replacing the hash a token of that name had (preset tokens).
    fn set_token(&self, name: &str, role: Role, token: &str) -> Result<(), Error>;
    /// Whether a token named `name` exists.
    fn has_token(&self, name: &str) -> Result<bool, Error>;
    /// Every token, oldest first (never the token itself).
    fn tokens(&self) -> Result<Vec<TokenInfo>, Error>;
    /// Deletes the token named `name`; whether it existed. Its sessions stay (an admin sees
    /// them); a new token of the same name does not inherit them.
    fn revoke_token(&self, name: &str) -> Result<bool, Error>;
    /// The caller `token` belongs to, if any (full hashes compared in constant time).
    fn caller(&self, token: &str) -> Result<Option<Caller>, Error>;
    /// Stores a share link's hash for `session`.
    fn insert_share(&self, session: &str, token: &str) -> Result<(), Error>;
    /// The session a share link opens, if the link exists (constant-time hash comparison).
    fn shared_session(&self, token: &str) -> Result<Option<String>, Error>;
    /// Revokes every share link of `session`; how many there were.
    fn revoke_shares(&self, session: &str) -> Result<usize, Error>;
    /// How many tokens are stored (raw rows, for the tests of what is stored).
    #[cfg(test)]
    fn token_count(&self) -> Result<i64, Error>;
}

/// The per-token usage ledger behind the limits (kept in the store, so a restart or another
/// instance sees the same counts).
pub(crate) trait UsageStore {
    /// Records a session creation by `token` at `now_ms` if it made fewer than `max` in the
    /// hour before; else the refusal.
    fn count_session_creation(
        &self,
        token: i64,
        max: u32,
        now_ms: i64,
    ) -> Result<Result<(), UsageFull>, Error>;
    /// Bytes `token` uploaded in the last day's hourly buckets, and when the oldest of them
    /// leaves the window.
    fn uploaded_in_day(&self, token: i64, now_ms: i64) -> Result<UsageFull, Error>;
    /// Adds `bytes` to `token`'s count of the hour of `now_ms`, and forgets the hours that
    /// left the window.
    fn add_uploaded(&self, token: i64, bytes: u64, now_ms: i64) -> Result<(), Error>;
}

/// Venues, their members, and which sessions joined them. A session joins a venue when it
/// is created ([`SessionStore::insert_session`] with `NewSession::venue`), which checks
/// atomically that the venue exists and that its sessions share the new one's convention.
pub(crate) trait VenueStore {
    /// Inserts venue `id`.
    fn insert_venue(&self, id: &str, new: &NewVenue<'_>) -> Result<(), Error>;
    /// Venue `id`, if it exists.
    fn venue(&self, id: &str) -> Result<Option<Venue>, Error>;
    /// The newest `limit` venues, newest first: every one when `viewer` is `None`, else those
    /// token `viewer` owns or is a member of.
    fn venues_for(&self, viewer: Option<i64>, limit: u32) -> Result<Vec<Venue>, Error>;
    /// Whether token `token` is a member of venue `venue`.
    fn is_member(&self, venue: &str, token: i64) -> Result<bool, Error>;
    /// Makes the token named `token_name` a member of `venue` (again: no change). `false`
    /// when no token has that name.
    fn add_member(&self, venue: &str, token_name: &str) -> Result<bool, Error>;
    /// Ends the membership of the token named `token_name`: `None` when no token has that
    /// name, else whether it was a member.
    fn remove_member(&self, venue: &str, token_name: &str) -> Result<Option<bool>, Error>;
    /// The names of `venue`'s members, by name.
    fn members(&self, venue: &str) -> Result<Vec<String>, Error>;
    /// The sessions that joined `venue`, oldest first (unreadable rows left out and logged).
    fn venue_sessions(&self, venue: &str) -> Result<Vec<Session>, Error>;
    /// Deletes `venue` and its memberships (and its sessions' kept contributions); its
    /// sessions stay, in no venue. Whether it existed.
    fn delete_venue(&self, id: &str) -> Result<bool, Error>;
    /// The kept contribution of every session of `venue` (any order): its generation and its
    /// body, `None` when none is kept (never computed, or forgotten since).
    fn kept_contributions(&self, venue: &str) -> Result<Vec<KeptContribution>, Error>;
    /// Keeps `body` as `session`'s contribution if its generation is still `generation` (the
    /// one read before its files were: a contribution forgotten meanwhile is not kept) and
    /// the session is still in a venue. Whether it was kept.
    fn keep_contribution(&self, session: &str, generation: i64, body: &[u8])
    -> Result<bool, Error>;
    /// Forgets `session`'s kept contribution, raising its generation, when it is in a venue
    /// (after one of its files changed). [`SessionStore::transition`] does the same inside its
    /// transaction when a session becomes `done`, and deleting the session removes it.
    fn forget_contribution(&self, session: &str) -> Result<(), Error>;
}

/// A session's kept contribution to its venue map (`venue_contributions`): a generation,
/// raised whenever what it was computed from changes, and the body (`venue::kept`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct KeptContribution {
    pub session: String,
    pub generation: i64,
    pub body: Option<Vec<u8>>,
}

/// Every concern of the metadata store: what the server holds as `Arc<dyn MetadataStore>`.
pub(crate) trait MetadataStore:
    SessionStore
    + InstanceStore
    + DeleteStore
    + TrialStore
    + JobStore
    + DeviceStore
    + TokenStore
    + UsageStore
    + VenueStore
    + Send
    + Sync
{
}

impl<T> MetadataStore for T where
    T: SessionStore
        + InstanceStore
        + DeleteStore
        + TrialStore
        + JobStore
        + DeviceStore
        + TokenStore
        + UsageStore
        + VenueStore
        + Send
        + Sync
{
}
