-- The progress a session's player publishes (queue position, playback timing as JSON,
-- playback::progress_view) so that every instance's status answer shows it. As
-- storage/sqlite/instance_schema.rs has it (version 2).
ALTER TABLE sessions ADD COLUMN progress_view TEXT;
