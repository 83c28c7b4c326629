-- Several API instances on one database: each instance's heartbeat, the instance playing a
-- session in flight and the stop a client asked through another instance, the instance
-- running each job. As storage/sqlite/instance_schema.rs has them.
CREATE TABLE instances (
    id TEXT PRIMARY KEY,
    started_ms BIGINT NOT NULL,
    heartbeat_ms BIGINT NOT NULL
);
ALTER TABLE sessions ADD COLUMN played_by TEXT;
ALTER TABLE sessions ADD COLUMN stop_request TEXT;
CREATE INDEX sessions_played_by ON sessions (played_by) WHERE played_by IS NOT NULL;
ALTER TABLE jobs ADD COLUMN instance TEXT;
