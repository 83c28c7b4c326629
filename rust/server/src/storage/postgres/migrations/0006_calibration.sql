-- The calibration a session's estimates are calibrated with, by name (`sitar serve
-- --calibration NAME=FILE`); NULL for uncalibrated sessions and every older row. As
-- storage/sqlite/mod.rs's ADDED_COLUMNS has it.
ALTER TABLE sessions ADD COLUMN calibration TEXT;
