-- Deletes that finish (storage/deletes.rs): a deleted session's row goes at once, and this
-- row, written in the same transaction, stays until its bytes are removed from the bucket.
-- The instance deleting it claims it until claimed_until_ms; past that (the instance died
-- mid-delete), any instance's sweep claims it (FOR UPDATE SKIP LOCKED) and finishes. As
-- storage/sqlite/deletes.rs has it.
CREATE TABLE unfinished_deletes (
    session_id TEXT PRIMARY KEY,
    deleted_ms BIGINT NOT NULL,
    claimed_by TEXT NOT NULL,
    claimed_until_ms BIGINT NOT NULL
);
CREATE INDEX unfinished_deletes_claimed_until ON unfinished_deletes (claimed_until_ms);
