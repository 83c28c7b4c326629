//! Playback on remote hosts (`sitar serve --playback-workers 0`): a session's job offers its
//! trials in the worker store, `sitar worker` hosts lease them one per free phone, and each
//! trial a host uploads is committed there exactly once, its text with it. The job takes the
//! committed trials from the worker store every [`CHECK`] (not from memory: with a shared
//! store the host may have uploaded to another instance). The job itself (progressive
//! estimates, adaptive stopping, the final estimate) is the same as for phones on the
//! server's own USB: [`RemotePlayback`] is one more [`Playback`].

use std::collections::{BTreeSet, HashMap};
use std::io::Read;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use crate::error::Error;
use crate::model::PlaybackKind;
use crate::playback::{DeviceInfo, Playback, PlaybackJob, PlaybackPlan, TrialOutput};
use crate::storage::MetadataStore;
use crate::storage::now_ms;
use crate::storage::workers::{MAX_ATTEMPTS, MAX_TAKEN_PER_CALL, PhoneState, WorkerStore};

/// How often a job waiting for its trials takes what was committed (and looks at its cancel
/// flag): a trial reaches its job at most this long after its commit.
const CHECK: Duration = Duration::from_millis(200);

/// Every how many collections a clustered job checks that it still plays its session (once
/// a second).
const PLAYER_CHECK: u64 = 5;

/// Where long-polling hosts wait for trials offered on this instance.
#[derive(Default)]
pub(crate) struct RemoteBoard {
    offered: tokio::sync::Notify,
}

impl RemoteBoard {
    /// Trials may be waiting: wakes the hosts' long polls.
    pub fn wake(&self) {
        self.offered.notify_waiters();
    }

    /// A wait for the next [`RemoteBoard::wake`]: enable it before looking for work, so a
    /// wake between the look and the wait is not missed.
    pub fn next_wake(&self) -> tokio::sync::futures::Notified<'_> {
        self.offered.notified()
    }
}

/// The SHA-256 of a file, hex: the name hosts cache a recording under.
pub(crate) fn sha256_file(path: &Path) -> Result<String, Error> {
    let mut file = std::fs::File::open(path).map_err(|e| Error::io("cannot read", path, e))?;
    let mut digest = ring::digest::Context::new(&ring::digest::SHA256);
    let mut buf = vec![0u8; 1 << 20];
    loop {
        let n = file
            .read(&mut buf)
            .map_err(|e| Error::io("cannot read", path, e))?;
        if n == 0 {
            break;
        }
        digest.update(&buf[..n]);
    }
    Ok(digest
        .finish()
        .as_ref()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
}

/// A [`Playback`] whose phones are on `sitar worker` hosts (see the module docs).
pub(crate) struct RemotePlayback {
    kind: PlaybackKind,
    /// The server's own backend of this kind: only for how long a trial lasts.
    local: Arc<dyn Playback>,
    workers: Arc<dyn WorkerStore>,
    db: Arc<dyn MetadataStore>,
    board: Arc<RemoteBoard>,
    /// A host not heard from for this long is silent (its leases expire).
    lease: Duration,
    /// Fallback trial duration of a recording without a readable MP4 header (adb).
    fallback_duration_s: f64,
    /// This instance, when others share the database: a job stops collecting once another
    /// instance plays its session (adopted while this one was silent).
    instance: Option<String>,
}

impl RemotePlayback {
    pub fn new(
        kind: PlaybackKind,
        local: Arc<dyn Playback>,
        workers: Arc<dyn WorkerStore>,
        db: Arc<dyn MetadataStore>,
        board: Arc<RemoteBoard>,
        lease: Duration,
        fallback_duration_s: f64,
    ) -> RemotePlayback {
        RemotePlayback {
            kind,
            local,
            workers,
            db,
            board,
            lease,
            fallback_duration_s,
            instance: None,
        }
    }

    /// Plays for `instance` among others on one database: see [`RemotePlayback::collect`].
    pub fn for_instance(mut self, instance: Option<String>) -> RemotePlayback {
        self.instance = instance;
        self
    }

    /// Whether another instance plays the session now (never without other instances).
    fn adopted_elsewhere(&self, session: &str) -> Result<bool, Error> {
        let Some(me) = &self.instance else {
            return Ok(false);
        };
        Ok(self.db.session_player(session)?.as_deref() != Some(me.as_str()))
    }

    /// Ready phones of live hosts of this kind.
    fn ready_phones(&self) -> Result<u32, Error> {
        let now = now_ms();
        let live: BTreeSet<String> = self
            .workers
            .hosts()?
            .into_iter()
            .filter(|h| h.playback == self.kind.as_str() && self.alive(h.last_seen_ms, now))
            .map(|h| h.id)
            .collect();
        Ok(self
            .workers
            .phones()?
            .iter()
            .filter(|p| p.state == PhoneState::Ready && live.contains(&p.host))
            .count() as u32)
    }

    fn alive(&self, last_seen_ms: i64, now_ms: i64) -> bool {
        now_ms - last_seen_ms <= self.lease.as_millis() as i64
    }

    /// Hands every trial committed for the job's session to `sink` until none is open (or
    /// the job is cancelled, or another instance plays the session now: checked every
    /// [`PLAYER_CHECK`] collections; the job's end sees it and leaves the session alone).
    fn collect(&self, job: &PlaybackJob, sink: &(dyn Fn(TrialOutput) + Sync)) -> Result<(), Error> {
        for round in 0u64.. {
            if job.cancelled() {
                return Ok(());
            }
            if round % PLAYER_CHECK == PLAYER_CHECK - 1 && self.adopted_elsewhere(&job.session)? {
                return Ok(());
            }
            // Counted before taking: a trial done by then is committed, so this take (or an
            // earlier one) has it when nothing is open any more.
            let counts = self.workers.counts(&job.session)?;
            loop {
                let taken = self
                    .workers
                    .take_committed(&job.session, self.instance.as_deref())?;
                let full = taken.len() >= MAX_TAKEN_PER_CALL;
                for trial in taken {
                    sink(TrialOutput {
                        index: trial.index,
                        tum: trial.tum,
                        source: trial.source,
                    });
                }
                if !full {
                    break;
                }
            }
            if counts.open() == 0 {
                if counts.failed > 0 {
                    return Err(Error::Playback(format!(
                        "{} trial(s) failed on the playback hosts {MAX_ATTEMPTS} times each and \
                         were given up (see failed_trials)",
                        counts.failed
                    )));
                }
                return Ok(());
            }
            std::thread::sleep(CHECK);
        }
        Ok(())
    }
}

impl Playback for RemotePlayback {
    fn name(&self) -> &'static str {
        self.kind.as_str()
    }

    fn plan(&self, recording: &Path, trials: u32) -> Result<PlaybackPlan, Error> {
        let trial_seconds = match self.kind {
            PlaybackKind::Adb => match crate::playback::adb::mp4_duration_s(recording) {
                Ok(d) if d > 0.0 => d,
                _ => self.fallback_duration_s,
            },
            _ => self.local.plan(recording, trials)?.trial_seconds,
        };
        Ok(PlaybackPlan {
            trial_seconds,
            devices: self.ready_phones()?.max(1),
        })
    }

    fn play(&self, job: &PlaybackJob, sink: &(dyn Fn(TrialOutput) + Sync)) -> Result<(), Error> {
        let session = self
            .db
            .session(&job.session)?
            .ok_or_else(|| Error::NotFound(format!("no session {:?}", job.session)))?;
        let sha256 = sha256_file(&job.recording)?;
        let outcome = (|| {
            self.workers.offer(
                &job.session,
                session.owner,
                self.kind.as_str(),
                &job.indices,
                &sha256,
                now_ms(),
            )?;
            self.board.wake();
            self.collect(job, sink)
        })();
        // Whatever ended the job (done, cancel, delete, shutdown): nothing stays offered, and
        // hosts playing a withdrawn trial are told to abort at their next heartbeat.
        if let Err(e) = self.workers.withdraw(&job.session) {
            log::warn!("session {}: cannot withdraw its trials: {e}", job.session);
        }
        outcome
    }

    fn devices(&self) -> Vec<DeviceInfo> {
        let now = now_ms();
        let (Ok(hosts), Ok(phones)) = (self.workers.hosts(), self.workers.phones()) else {
            return Vec::new();
        };
        let hosts: HashMap<_, _> = hosts
            .into_iter()
            .filter(|h| h.playback == self.kind.as_str())
            .map(|h| (h.id.clone(), h))
            .collect();
        phones
            .into_iter()
            .filter_map(|p| {
                let host = hosts.get(&p.host)?;
                let state = if !self.alive(host.last_seen_ms, now) {
                    "host_silent"
                } else {
                    p.state.as_str()
                };
                Some(DeviceInfo {
                    serial: format!("{}/{}", host.name, p.serial),
                    state: state.to_string(),
                    backend: "remote",
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_recording_hash_is_sha256() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rec");
        std::fs::write(&path, b"abc").unwrap();
        assert_eq!(
            sha256_file(&path).unwrap(),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
