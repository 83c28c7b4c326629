//! Deletes that finish. A deleted session's row goes at once, and in the same transaction an
//! *unfinished delete* is recorded: its bytes are still to be removed from the blob store.
//! The instance deleting it claims that work for a while; it removes the bytes and forgets
//! the record. When it dies in between, the claim lapses and any live instance's sweep
//! (`jobs::delete_sweep`) claims the record and finishes: removing bytes that are already
//! gone is success, so two instances finishing one delete never fail each other.

use crate::error::Error;

/// Who works on an unfinished delete, and until when (ms since the Unix epoch): once that
/// has passed, any instance may take the work over.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Claim<'a> {
    pub instance: &'a str,
    pub until_ms: i64,
}

/// The deleted sessions whose bytes are still to be removed.
pub(crate) trait DeleteStore {
    /// Claims for `claim` at most `limit` unfinished deletes whose claim had passed by
    /// `now_ms`, oldest first; their session ids. Two instances claiming at once get
    /// different ones (`FOR UPDATE SKIP LOCKED`; SQLite has one connection).
    fn claim_unfinished_deletes(
        &self,
        claim: Claim<'_>,
        now_ms: i64,
        limit: u32,
    ) -> Result<Vec<String>, Error>;
    /// The bytes of deleted session `id` are gone: forgets its unfinished delete (none: no
    /// change).
    fn finish_delete(&self, id: &str) -> Result<(), Error>;
    /// Every unfinished delete's session id, by id (the tests' view of what is left).
    #[cfg(test)]
    fn unfinished_deletes(&self) -> Result<Vec<String>, Error>;
}
