-- The tables of the embedded store (storage/sqlite/mod.rs), in Postgres types: times are
-- ms since the Unix epoch (BIGINT), hashes BYTEA; `seq` orders sessions as SQLite's rowid.
CREATE TABLE sessions (
    id TEXT PRIMARY KEY,
    seq BIGSERIAL NOT NULL UNIQUE,
    idempotency_key TEXT UNIQUE,
    created_ms BIGINT NOT NULL,
    trials_total BIGINT NOT NULL,
    setting TEXT NOT NULL,
    playback TEXT NOT NULL,
    state TEXT NOT NULL,
    error TEXT,
    stop_reason TEXT,
    adaptive_min BIGINT,
    adaptive_k BIGINT NOT NULL,
    recording_bytes BIGINT,
    results_trials BIGINT NOT NULL DEFAULT 0,
    legacy BOOLEAN NOT NULL DEFAULT FALSE,
    finished_ms BIGINT,
    window_frames BIGINT NOT NULL DEFAULT 10,
    pose_relation TEXT NOT NULL DEFAULT 'trans_part',
    owner BIGINT
);
CREATE INDEX sessions_state ON sessions (state, created_ms);
CREATE INDEX sessions_owner ON sessions (owner, seq);
CREATE TABLE trials (
    session_id TEXT NOT NULL REFERENCES sessions(id),
    idx BIGINT NOT NULL,
    play_index BIGINT NOT NULL,
    idempotency_key TEXT,
    poses BIGINT NOT NULL,
    source TEXT NOT NULL,
    created_ms BIGINT NOT NULL,
    PRIMARY KEY (session_id, idx),
    UNIQUE (session_id, idempotency_key)
);
CREATE TABLE jobs (
    id BIGSERIAL PRIMARY KEY,
    session_id TEXT NOT NULL REFERENCES sessions(id),
    kind TEXT NOT NULL,
    state TEXT NOT NULL,
    started_ms BIGINT NOT NULL,
    finished_ms BIGINT,
    error TEXT
);
CREATE INDEX jobs_session ON jobs (session_id);
CREATE TABLE devices (
    serial TEXT PRIMARY KEY,
    state TEXT NOT NULL,
    session_id TEXT,
    last_seen_ms BIGINT NOT NULL
);
CREATE TABLE tokens (
    id BIGSERIAL PRIMARY KEY,
    name TEXT NOT NULL UNIQUE,
    role TEXT NOT NULL,
    lookup BYTEA NOT NULL,
    hash BYTEA NOT NULL UNIQUE,
    created_ms BIGINT NOT NULL,
    last_used_ms BIGINT
);
CREATE INDEX tokens_lookup ON tokens (lookup);
CREATE TABLE share_links (
    lookup BYTEA NOT NULL,
    hash BYTEA PRIMARY KEY,
    session_id TEXT NOT NULL,
    created_ms BIGINT NOT NULL
);
CREATE INDEX share_links_lookup ON share_links (lookup);
CREATE TABLE session_creations (
    token_id BIGINT NOT NULL,
    created_ms BIGINT NOT NULL
);
CREATE INDEX session_creations_token ON session_creations (token_id, created_ms);
CREATE TABLE upload_usage (
    token_id BIGINT NOT NULL,
    hour BIGINT NOT NULL,
    bytes BIGINT NOT NULL,
    PRIMARY KEY (token_id, hour)
);
