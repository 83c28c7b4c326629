//! Where estimates run: the bounded registry of sessions in flight (`live_sessions`, the only
//! caller of the estimator), the trials each holds with its incremental estimate
//! (`held_trials`), and what an estimate publishes (`publishing`) into the session's results
//! files (`results_files`); the calibrations the server applies to them (`calibrations`).

pub(crate) mod calibrations;
pub(crate) mod held_trials;
pub(crate) mod live_sessions;
pub(crate) mod publishing;
pub(crate) mod results_files;
