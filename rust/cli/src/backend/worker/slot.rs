//! One phone's loop: lease a trial (long poll), fetch its recording unless cached, play it,
//! upload it — or report the phone's failure. A trial whose lease the server withdrew (the
//! session was cancelled or deleted, or the lease expired while this host was silent) is
//! stopped and dropped; an upload the server refuses (409) is dropped too.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::{Context, Result, anyhow};
use sitar_client::WorkerLease;
use sitar_server::{AdbPlayback, Playback, PlaybackJob, SimConfig, SimPlayback, TrialOutput};

use super::Host;

/// How one trial is played on this host.
#[derive(Clone)]
pub(crate) struct Player {
    /// Simulated phones (else adb).
    pub playback: bool,
    pub sim_speed: f64,
    pub adb: AdbPlayback,
    /// Working folders of adb's pulled trials.
    pub work: PathBuf,
}

/// Seconds a lease request waits on the server for work.
const LEASE_WAIT_S: f64 = 20.0;

/// Runs phone `phone`'s loop until the process ends.
pub(crate) fn run(host: &Host, player: &Player, phone: &str) {
    loop {
        if let Err(e) = one(host, player, phone) {
            log::warn!("{phone}: {e:#}");
            // The server is away or refused: try again shortly.
            std::thread::sleep(Duration::from_secs(1));
        }
    }
}

/// One lease, from asking to uploading.
fn one(host: &Host, player: &Player, phone: &str) -> Result<()> {
    let Some(lease) = host
        .client
        .worker_lease(&host.id(), phone, LEASE_WAIT_S)
        .context("lease")?
    else {
        return Ok(());
    };
    let cancel = Arc::new(AtomicBool::new(false));
    host.held()
        .insert(phone.to_string(), (lease.lease.clone(), cancel.clone()));
    let outcome = play_and_send(host, player, phone, &lease, &cancel);
    host.held().remove(phone);
    outcome
}

fn play_and_send(
    host: &Host,
    player: &Player,
    phone: &str,
    lease: &WorkerLease,
    cancel: &Arc<AtomicBool>,
) -> Result<()> {
    let id = host.id();
    let recording = host.cache.get(&lease.recording_sha256, |part| {
        host.client
            .worker_recording(&id, &lease.lease, part)
            .map(|_| ())
            .context("fetching the recording")
    });
    let recording = match recording {
        Ok((path, fetched)) => {
            if fetched {
                log::info!("recording {} fetched", lease.recording_sha256);
            }
            path
        }
        Err(e) => {
            report(host, &id, lease, &format!("{e:#}"));
            return Ok(());
        }
    };
    log::info!(
        "{phone}: playing trial {} of session {}",
        lease.index,
        lease.session
    );
    let played = play(player, phone, lease, recording, cancel);
    if cancel.load(Ordering::SeqCst) {
        log::info!(
            "{phone}: trial {} of {} stopped",
            lease.index,
            lease.session
        );
        return Ok(());
    }
    match played {
        Ok(tum) => match host.client.worker_upload_trial(&id, &lease.lease, &tum) {
            Ok(()) => log::info!("{phone}: trial {} of {} sent", lease.index, lease.session),
            Err(e) if e.status() == Some(409) => log::warn!(
                "{phone}: trial {} of {} refused, the lease was no longer ours: {e}",
                lease.index,
                lease.session
            ),
            Err(e) => return Err(anyhow!(e).context("uploading the trial")),
        },
        Err(e) => report(host, &id, lease, &format!("{e:#}")),
    }
    Ok(())
}

/// Tells the server the phone could not play the trial.
fn report(host: &Host, id: &str, lease: &WorkerLease, error: &str) {
    log::warn!("{}: trial {} failed: {error}", lease.phone, lease.index);
    if let Err(e) = host.client.worker_failure(id, &lease.lease, error) {
        log::warn!("{}: reporting the failure: {e}", lease.phone);
    }
}

/// Plays the leased trial on `phone` and returns its TUM text.
fn play(
    player: &Player,
    phone: &str,
    lease: &WorkerLease,
    recording: PathBuf,
    cancel: &Arc<AtomicBool>,
) -> Result<String> {
    let work_dir = player.work.join(phone.replace(['/', ':'], "_"));
    std::fs::create_dir_all(&work_dir)
        .with_context(|| format!("cannot create {}", work_dir.display()))?;
    let job = PlaybackJob {
        session: lease.session.clone(),
        recording,
        work_dir,
        indices: vec![lease.index],
        cancel: cancel.clone(),
    };
    let got: Mutex<Option<TrialOutput>> = Mutex::new(None);
    let sink = |trial: TrialOutput| {
        *got.lock().unwrap_or_else(|e| e.into_inner()) = Some(trial);
    };
    if player.playback {
        let sim = SimPlayback::new(SimConfig {
            speed: player.sim_speed,
            devices: 1,
        });
        sim.play(&job, &sink)?;
    } else {
        player.adb.on_phone(phone).play(&job, &sink)?;
    }
    let trial = got
        .into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .ok_or_else(|| anyhow!("the phone finished without a trajectory"))?;
    Ok(trial.tum)
}
