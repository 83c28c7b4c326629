//! The worker store: playback hosts that pull work (`sitar worker`), their phones, and the
//! leases through which each trial is played exactly once. Two traits by concern,
//! [`HostStore`] (hosts, phones, their failures) and [`LeaseStore`] (trials offered to the
//! hosts, leases, commits, failed trials); [`WorkerStore`] is both. The embedded
//! implementation is SQLite (`storage/sqlite/hosts.rs`, `leases.rs`, a versioned migration in
//! `worker_schema.rs`); the cluster one is Postgres (`storage/postgres/hosts.rs`, `leases.rs`,
//! migration `0003_workers.sql`), shared by every instance on the database.
//! `storage::worker_conformance` is the suite any implementation passes.
//!
//! A committed trial's text is stored with its lease, in the commit's transaction, and its
//! session's job takes it from there ([`LeaseStore::take_committed`]): the host may upload to
//! any instance, whichever instance runs the job.
//!
//! Every time is ms since the Unix epoch and is passed in, so the suite controls the clock.

use crate::error::Error;

/// Attempts a trial gets (a phone failing it, a lease expiring, a trial that cannot be
/// parsed) before it is given up.
pub(crate) const MAX_ATTEMPTS: u32 = 3;

/// Failures in a row that take a phone out of service.
pub(crate) const FAILURES_OUT_OF_SERVICE: u32 = 2;

/// Failed trials kept per session for its status (the newest are dropped beyond).
pub(crate) const MAX_FAILURES_KEPT: usize = 100;

/// Committed trials one [`LeaseStore::take_committed`] hands over at most (the job calls
/// again at once when it got this many): what one call holds in memory is this many trials
/// of at most `--max-trajectory-bytes` each.
pub(crate) const MAX_TAKEN_PER_CALL: usize = 32;

/// A committed trial, as its session's job takes it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CommittedTrial {
    /// The trial's playback index.
    pub index: u32,
    /// Its TUM text, as the host uploaded it.
    pub tum: String,
    /// The phone that played it (`HOST/SERIAL`).
    pub source: String,
}

/// A server-made id: `prefix` and 16 hex digits from the system's secure generator.
pub(crate) fn random_id(prefix: char) -> Result<String, Error> {
    use ring::rand::SecureRandom;
    let mut bytes = [0u8; 8];
    ring::rand::SystemRandom::new()
        .fill(&mut bytes)
        .map_err(|_| Error::Internal("the system's random generator failed".into()))?;
    Ok(format!("{prefix}{:016x}", u64::from_be_bytes(bytes)))
}

/// A phone's state as the server sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PhoneState {
    /// Takes leases.
    Ready,
    /// Failed [`FAILURES_OUT_OF_SERVICE`] times in a row: takes no lease until its host
    /// registers again.
    OutOfService,
    /// Its host's last report did not list it.
    Missing,
}

impl PhoneState {
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            PhoneState::Ready => "ready",
            PhoneState::OutOfService => "out_of_service",
            PhoneState::Missing => "missing",
        }
    }

    pub(crate) fn parse(s: &str) -> PhoneState {
        match s {
            "ready" => PhoneState::Ready,
            "out_of_service" => PhoneState::OutOfService,
            _ => PhoneState::Missing,
        }
    }
}

/// A playback host as registered.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct HostRow {
    /// Server-made id (`h` + 16 hex digits).
    pub id: String,
    /// The name the worker gave (its machine's name unless told otherwise).
    pub name: String,
    /// The token it registered with.
    pub token: i64,
    /// `sim` or `adb`.
    pub playback: String,
    /// Its last heartbeat or registration.
    pub last_seen_ms: i64,
}

/// A phone of a host.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct PhoneRow {
    pub host: String,
    pub serial: String,
    pub state: PhoneState,
    /// Failures in a row (a success resets it).
    pub failures: u32,
    /// The last failure's reason.
    pub last_error: Option<String>,
}

/// A trial leased to a phone.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Lease {
    /// Server-made id (`l` + 16 hex digits); a trial played again gets a new one.
    pub id: String,
    pub session: String,
    /// The trial's playback index.
    pub index: u32,
    pub host: String,
    pub phone: String,
    /// When it expires unless its host heartbeats.
    pub expires_ms: i64,
    /// The recording's SHA-256 (hex), the name hosts cache it under.
    pub recording_sha256: String,
}

/// What became of a trial whose lease was given back (a phone's failure, an expiry, an
/// unparsable trial).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Requeued {
    /// Offered again to any phone.
    Again,
    /// [`MAX_ATTEMPTS`] reached: given up.
    GivenUp,
}

/// A lease that expired (its host went silent).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Expired {
    pub lease: String,
    pub session: String,
    pub index: u32,
    pub host: String,
    pub phone: String,
    pub requeued: Requeued,
}

/// A session's offered trials by state.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct LeaseCounts {
    pub pending: u32,
    pub leased: u32,
    pub done: u32,
    pub failed: u32,
}

impl LeaseCounts {
    /// Trials still to come (waiting, playing or being committed).
    pub(crate) fn open(&self) -> u32 {
        self.pending + self.leased
    }
}

/// A trial that failed, as the session's status shows it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct TrialFailure {
    pub index: u32,
    /// The phone (`HOST/SERIAL`, `sim:N`, `adb:SERIAL`).
    pub source: String,
    pub error: String,
    pub at_ms: i64,
}

/// Playback hosts and their phones.
pub(crate) trait HostStore {
    /// Registers host `name` of `token` with `phones` (all ready): a host of that token and
    /// name registered before keeps its id, its phones are put back in service and its
    /// leases are given back (a restarted worker plays none of them). Returns its id.
    fn register_host(
        &self,
        token: i64,
        name: &str,
        playback: &str,
        phones: &[String],
        now_ms: i64,
    ) -> Result<String, Error>;
    /// Host `id`, if registered.
    fn host(&self, id: &str) -> Result<Option<HostRow>, Error>;
    /// A heartbeat of host `id`: seen now, its phones as listed (new ones ready, unlisted
    /// ones missing, listed missing ones ready again), its leases renewed until
    /// `now_ms + lease_ms`. Returns those of `held` that are no longer its live leases (to
    /// abort).
    fn heartbeat(
        &self,
        id: &str,
        phones: &[String],
        held: &[String],
        now_ms: i64,
        lease_ms: i64,
    ) -> Result<Vec<String>, Error>;
    /// Every host, by name.
    fn hosts(&self) -> Result<Vec<HostRow>, Error>;
    /// Every phone of every host, by host and serial.
    fn phones(&self) -> Result<Vec<PhoneRow>, Error>;
    /// A phone succeeded (`error` None: its failures reset) or failed; returns its state
    /// after ([`PhoneState::OutOfService`] at [`FAILURES_OUT_OF_SERVICE`] in a row).
    fn phone_result(
        &self,
        host: &str,
        serial: &str,
        error: Option<&str>,
    ) -> Result<PhoneState, Error>;
}

/// Trials offered to hosts and their leases.
pub(crate) trait LeaseStore {
    /// Offers `indices` of `session` (of `owner`, to `playback` hosts): each becomes pending,
    /// whatever it was (the caller offers only trials it has not stored: a commit whose trial
    /// a crash lost is played again); the session's other open trials are withdrawn and its
    /// committed trials no job took are dropped (an earlier job's, which ended).
    fn offer(
        &self,
        session: &str,
        owner: Option<i64>,
        playback: &str,
        indices: &[u32],
        recording_sha256: &str,
        now_ms: i64,
    ) -> Result<(), Error>;
    /// Leases the next pending trial of a `playback` session to `phone` of `host` until
    /// `now_ms + lease_ms`: owners in turn (the one served longest ago first), then the
    /// oldest offer, lowest index. A lease the phone still held is given back first. None
    /// when nothing waits, or the phone is not ready.
    fn claim(
        &self,
        host: &str,
        phone: &str,
        playback: &str,
        now_ms: i64,
        lease_ms: i64,
    ) -> Result<Option<Lease>, Error>;
    /// Lease `lease` if it is `host`'s and live (not expired at `now_ms`, not withdrawn).
    fn live_lease(&self, lease: &str, host: &str, now_ms: i64) -> Result<Option<Lease>, Error>;
    /// Commits the trial of `lease` with its text `tum` (at most `--max-trajectory-bytes`, the
    /// caller's bound) and `source` — exactly once: only a live lease of `host` commits
    /// (atomically, so a late upload of an expired or replaced lease never does); the text is
    /// stored in the same statement, for [`LeaseStore::take_committed`]. `Err` names why not.
    fn commit(
        &self,
        lease: &str,
        host: &str,
        now_ms: i64,
        tum: &str,
        source: &str,
    ) -> Result<Result<Lease, String>, Error>;
    /// Takes up to [`MAX_TAKEN_PER_CALL`] committed trials of `session` not taken before, by
    /// index, and marks them taken (their text dropped) in the same transaction: each is
    /// handed over once, whichever instance asks. A job that dies before storing what it took
    /// loses nothing: the resumed session offers the indices it lacks again. With `player`
    /// (several instances on one database) nothing is taken unless `player` plays the session
    /// (`sessions.played_by`) in the same statement: an instance that woke from a pause to
    /// find its session adopted takes none of the adopter's trials.
    fn take_committed(
        &self,
        session: &str,
        player: Option<&str>,
    ) -> Result<Vec<CommittedTrial>, Error>;
    /// Gives `lease`'s trial back (its phone failed, or the trial could not be used): offered
    /// again, or given up after [`MAX_ATTEMPTS`]. None if the lease was not live.
    fn give_back(&self, lease: &str, host: &str) -> Result<Option<Requeued>, Error>;
    /// Expires leases past their time: their trials are offered again (or given up).
    fn expire(&self, now_ms: i64) -> Result<Vec<Expired>, Error>;
    /// Withdraws `session`'s open trials (cancel, delete, end of playback) and drops its
    /// committed trials no job took.
    fn withdraw(&self, session: &str) -> Result<(), Error>;
    /// `session`'s offered trials by state.
    fn counts(&self, session: &str) -> Result<LeaseCounts, Error>;
    /// Records a failed trial of `session` for its status (at most [`MAX_FAILURES_KEPT`]).
    fn record_failure(&self, session: &str, failure: &TrialFailure) -> Result<(), Error>;
    /// `session`'s failed trials, oldest first.
    fn failures(&self, session: &str) -> Result<Vec<TrialFailure>, Error>;
    /// Forgets everything of `session` (it was deleted).
    fn forget(&self, session: &str) -> Result<(), Error>;
}

/// Both concerns: what the server holds as `Arc<dyn WorkerStore>`.
pub(crate) trait WorkerStore: HostStore + LeaseStore + Send + Sync {}

impl<T> WorkerStore for T where T: HostStore + LeaseStore + Send + Sync {}
