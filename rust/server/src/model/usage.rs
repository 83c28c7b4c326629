//! The limits' units: the windows over which the per-token usage ledger
//! ([`crate::storage::metadata::UsageStore`]) counts, and what a refusal says.

pub(crate) const HOUR_MS: i64 = 3_600_000;
/// Uploaded bytes count against the day in whole hours: the last 24 hourly buckets.
pub(crate) const DAY_HOURS: i64 = 24;

/// A refusal: the limit was reached; the earliest time (ms since the epoch) the oldest
/// counted use leaves the window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct UsageFull {
    pub used: u64,
    pub frees_at_ms: i64,
}
