//! What runs for a session beyond one request, over the shared [`App`](crate::app_state::App):
//! its playback job (queued, run on the backends, its estimates published: `playback`,
//! `playback_run`), a recording's arrival that starts one (`recordings`), this instance's
//! heartbeat and adoption of dead instances' sessions (`instances`), the progress other
//! instances read (`progress_view`), failed workers' leases taken back (`reaper`), stop
//! requests passed between instances (`stop_requests`), and deletions with the sweeps that
//! finish them or apply retention (`deletion`, `delete_sweep`).

pub(crate) mod delete_sweep;
pub(crate) mod deletion;
pub(crate) mod instances;
pub(crate) mod live_session;
pub(crate) mod playback;
pub(crate) mod playback_run;
pub(crate) mod progress_view;
pub(crate) mod reaper;
pub(crate) mod recordings;
pub(crate) mod stop_requests;
