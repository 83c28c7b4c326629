-- The worker store (storage/workers.rs) in Postgres, shared by every instance: playback hosts,
-- their phones, offered trials and their leases, owners' turns, failed trials. Times are ms
-- since the Unix epoch. A committed trial's text stays with its lease until its session's job
-- takes it (`taken`), then it is dropped.
CREATE TABLE worker_hosts (
    id TEXT PRIMARY KEY,
    token_id BIGINT NOT NULL,
    name TEXT NOT NULL,
    playback TEXT NOT NULL,
    registered_ms BIGINT NOT NULL,
    last_seen_ms BIGINT NOT NULL,
    UNIQUE (token_id, name)
);
CREATE TABLE worker_phones (
    host_id TEXT NOT NULL REFERENCES worker_hosts(id),
    serial TEXT NOT NULL,
    state TEXT NOT NULL,
    failures BIGINT NOT NULL DEFAULT 0,
    last_error TEXT,
    PRIMARY KEY (host_id, serial)
);
-- Offer and turn order across instances (SQLite takes MAX + 1 under its single writer).
CREATE SEQUENCE trial_offer_seq;
CREATE SEQUENCE lease_turn_seq;
CREATE TABLE trial_leases (
    session_id TEXT NOT NULL,
    play_index BIGINT NOT NULL,
    owner_key TEXT NOT NULL,
    playback TEXT NOT NULL,
    recording_sha256 TEXT NOT NULL,
    offered_seq BIGINT NOT NULL,
    state TEXT NOT NULL,
    attempts BIGINT NOT NULL DEFAULT 0,
    lease_id TEXT UNIQUE,
    host_id TEXT,
    phone TEXT,
    expires_ms BIGINT,
    trial_text TEXT,
    trial_source TEXT,
    taken BOOLEAN NOT NULL DEFAULT FALSE,
    PRIMARY KEY (session_id, play_index)
);
CREATE INDEX trial_leases_pending ON trial_leases (state, playback, owner_key, offered_seq);
CREATE INDEX trial_leases_host ON trial_leases (host_id, state);
CREATE TABLE lease_turns (
    owner_key TEXT PRIMARY KEY,
    served_seq BIGINT NOT NULL
);
CREATE TABLE trial_failures (
    id BIGSERIAL PRIMARY KEY,
    session_id TEXT NOT NULL,
    play_index BIGINT NOT NULL,
    source TEXT NOT NULL,
    error TEXT NOT NULL,
    at_ms BIGINT NOT NULL
);
CREATE INDEX trial_failures_session ON trial_failures (session_id, id);
