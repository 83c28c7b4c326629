-- Each venue session's contribution to its venue's map, kept beside its row (as
-- storage/sqlite/mod.rs has it): a generation raised whenever what it was computed from
-- changes (a phone file, the session finishing), and the body (venue/kept.rs), NULL until
-- computed again. A cache: `sitar migrate` does not copy it, and a session without one gets
-- it computed on first use.
CREATE TABLE venue_contributions (
    session_id TEXT PRIMARY KEY,
    generation BIGINT NOT NULL,
    body BYTEA
);
