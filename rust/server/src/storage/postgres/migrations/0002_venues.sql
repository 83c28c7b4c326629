-- Venues (several users' sessions in one place) and the sessions that joined them, as
-- storage/sqlite/mod.rs has them.
ALTER TABLE sessions ADD COLUMN venue TEXT;
ALTER TABLE sessions ADD COLUMN convention TEXT NOT NULL DEFAULT 'unity';
CREATE INDEX sessions_venue ON sessions (venue) WHERE venue IS NOT NULL;
CREATE TABLE venues (
    id TEXT PRIMARY KEY,
    seq BIGSERIAL NOT NULL UNIQUE,
    name TEXT NOT NULL,
    anchor TEXT NOT NULL,
    cell_m DOUBLE PRECISION NOT NULL,
    owner BIGINT,
    created_ms BIGINT NOT NULL
);
CREATE TABLE venue_members (
    venue_id TEXT NOT NULL REFERENCES venues(id),
    token_id BIGINT NOT NULL,
    PRIMARY KEY (venue_id, token_id)
);
