//! The conformance suite of the worker store ([`WorkerStore`]): what every implementation must
//! do, written once against the traits. The embedded store runs it (`storage::sqlite`'s
//! tests); another implementation calls [`worker_store`] on a fresh, empty store of its own,
//! and [`racing_instances`] with two handles on one store (two instances on one database; the
//! embedded store, which one instance owns, passes the same handle twice).

use std::collections::BTreeSet;
use std::sync::Barrier;

use crate::storage::workers::{
    FAILURES_OUT_OF_SERVICE, LeaseCounts, MAX_ATTEMPTS, MAX_TAKEN_PER_CALL, PhoneState, Requeued,
    TrialFailure, WorkerStore,
};

const LEASE_MS: i64 = 60_000;

/// Runs every check on `store`, which must be empty.
pub(crate) fn worker_store(store: &dyn WorkerStore) {
    hosts_register_once_per_token_and_name(store);
    a_trial_is_committed_exactly_once(store);
    leases_expire_without_heartbeats_and_trials_are_replayed(store);
    owners_are_served_in_turn(store);
    phones_failing_twice_in_a_row_leave_service(store);
    withdrawn_trials_are_not_leased_and_their_leases_abort(store);
    failed_trials_are_kept_for_the_status(store);
    committed_trials_reach_the_job_once(store);
}

fn phones(serials: &[&str]) -> Vec<String> {
    serials.iter().map(|s| s.to_string()).collect()
}

fn hosts_register_once_per_token_and_name(store: &dyn WorkerStore) {
    let a = store
        .register_host(1, "lab-a", "sim", &phones(&["sim:0", "sim:1"]), 1_000)
        .unwrap();
    assert!(a.starts_with('h') && a.len() == 17, "{a}");
    // The same worker again (restarted): the same id.
    let again = store
        .register_host(1, "lab-a", "sim", &phones(&["sim:0"]), 2_000)
        .unwrap();
    assert_eq!(again, a);
    // Another token's host of the same name is another host.
    let other = store
        .register_host(2, "lab-a", "sim", &phones(&["sim:0"]), 2_000)
        .unwrap();
    assert_ne!(other, a);
    let row = store.host(&a).unwrap().unwrap();
    assert_eq!(
        (row.name.as_str(), row.token, row.last_seen_ms),
        ("lab-a", 1, 2_000)
    );
    assert!(store.host("h0000000000000000").unwrap().is_none());
    // Registration replaced the phone list: sim:1 is gone.
    let serials: Vec<_> = store
        .phones()
        .unwrap()
        .into_iter()
        .filter(|p| p.host == a)
        .map(|p| p.serial)
        .collect();
    assert_eq!(serials, vec!["sim:0"]);
    // An unknown host's heartbeat is a 404 naming it.
    let err = store
        .heartbeat("h0000000000000000", &[], &[], 3_000, LEASE_MS)
        .unwrap_err();
    assert_eq!(err.status_and_code().1, "not_found", "{err}");
    // A heartbeat lists the phones: new ones join ready, unlisted ones go missing.
    store
        .heartbeat(&a, &phones(&["sim:1"]), &[], 3_000, LEASE_MS)
        .unwrap();
    let states: Vec<_> = store
        .phones()
        .unwrap()
        .into_iter()
        .filter(|p| p.host == a)
        .map(|p| (p.serial, p.state))
        .collect();
    assert_eq!(
        states,
        vec![
            ("sim:0".to_string(), PhoneState::Missing),
            ("sim:1".to_string(), PhoneState::Ready)
        ]
    );
    assert_eq!(store.host(&a).unwrap().unwrap().last_seen_ms, 3_000);
}

fn a_trial_is_committed_exactly_once(store: &dyn WorkerStore) {
    let host = store
        .register_host(10, "once", "sim", &phones(&["p0", "p1"]), 0)
        .unwrap();
    store
        .offer("s2000000000000001", Some(5), "sim", &[0], "abc", 0)
        .unwrap();
    // adb hosts see nothing of a sim session.
    assert!(
        store
            .claim(&host, "p0", "adb", 0, LEASE_MS)
            .unwrap()
            .is_none()
    );
    let lease = store
        .claim(&host, "p0", "sim", 0, LEASE_MS)
        .unwrap()
        .unwrap();
    assert_eq!(
        (lease.session.as_str(), lease.index),
        ("s2000000000000001", 0)
    );
    assert_eq!((lease.phone.as_str(), lease.expires_ms), ("p0", LEASE_MS));
    assert_eq!(lease.recording_sha256, "abc");
    // Nothing else waits.
    assert!(
        store
            .claim(&host, "p1", "sim", 0, LEASE_MS)
            .unwrap()
            .is_none()
    );
    assert!(store.live_lease(&lease.id, &host, 10).unwrap().is_some());
    // Another host cannot commit it; its own host can, once.
    let other = store
        .register_host(10, "once-b", "sim", &phones(&["p0"]), 0)
        .unwrap();
    assert!(
        store
            .commit(&lease.id, &other, 10, "", "")
            .unwrap()
            .is_err()
    );
    let committed = store.commit(&lease.id, &host, 10, "", "").unwrap().unwrap();
    assert_eq!(committed.index, 0);
    let again = store
        .commit(&lease.id, &host, 11, "", "")
        .unwrap()
        .unwrap_err();
    assert!(again.contains(&lease.id), "{again}");
    assert_eq!(
        store.counts("s2000000000000001").unwrap(),
        LeaseCounts {
            done: 1,
            ..LeaseCounts::default()
        }
    );
    assert!(store.give_back(&lease.id, &host).unwrap().is_none());
}

fn leases_expire_without_heartbeats_and_trials_are_replayed(store: &dyn WorkerStore) {
    let a = store
        .register_host(20, "dies", "sim", &phones(&["p0"]), 0)
        .unwrap();
    let b = store
        .register_host(20, "lives", "sim", &phones(&["p0"]), 0)
        .unwrap();
    store
        .offer("s2000000000000002", None, "sim", &[3], "abc", 0)
        .unwrap();
    let first = store.claim(&a, "p0", "sim", 0, LEASE_MS).unwrap().unwrap();
    // A heartbeat renews it.
    let abort = store
        .heartbeat(
            &a,
            &phones(&["p0"]),
            std::slice::from_ref(&first.id),
            50_000,
            LEASE_MS,
        )
        .unwrap();
    assert!(abort.is_empty(), "{abort:?}");
    assert!(store.expire(100_000).unwrap().is_empty());
    // Then host a goes silent: past 50 s + 60 s the lease expires and the trial waits again.
    let expired = store.expire(110_001).unwrap();
    assert_eq!(expired.len(), 1);
    assert_eq!(
        (
            expired[0].lease.as_str(),
            expired[0].index,
            expired[0].requeued
        ),
        (first.id.as_str(), 3, Requeued::Again)
    );
    // A heartbeat now does not bring it back: host a is told to abort it.
    let abort = store
        .heartbeat(
            &a,
            &phones(&["p0"]),
            std::slice::from_ref(&first.id),
            110_002,
            LEASE_MS,
        )
        .unwrap();
    assert_eq!(abort, vec![first.id.clone()]);
    let second = store
        .claim(&b, "p0", "sim", 110_003, LEASE_MS)
        .unwrap()
        .unwrap();
    assert_eq!(second.index, 3);
    assert_ne!(second.id, first.id);
    // The presumed-dead host's late upload is refused; the live one commits, once.
    assert!(
        store
            .commit(&first.id, &a, 110_004, "", "")
            .unwrap()
            .is_err()
    );
    assert!(
        store
            .commit(&second.id, &b, 110_005, "", "")
            .unwrap()
            .is_ok()
    );
    assert!(
        store
            .commit(&first.id, &a, 110_006, "", "")
            .unwrap()
            .is_err()
    );
    assert_eq!(store.counts("s2000000000000002").unwrap().done, 1);
    // A lease past its time is not live, even before the reaper ran.
    store
        .offer("s2000000000000003", None, "sim", &[0], "abc", 0)
        .unwrap();
    let late = store.claim(&b, "p0", "sim", 0, 1_000).unwrap().unwrap();
    assert!(store.live_lease(&late.id, &b, 1_001).unwrap().is_none());
    assert!(store.commit(&late.id, &b, 1_001, "", "").unwrap().is_err());
    // Expiring over and over gives the trial up after MAX_ATTEMPTS.
    let mut now = 2_000;
    let mut last = None;
    for _ in 0..MAX_ATTEMPTS {
        let expired = store.expire(now).unwrap();
        last = expired.last().map(|e| e.requeued);
        now += 10;
        if let Some(lease) = store.claim(&b, "p0", "sim", now, 1).unwrap() {
            assert_eq!(lease.session, "s2000000000000003");
        }
        now += 10;
    }
    assert_eq!(last, Some(Requeued::GivenUp));
    let counts = store.counts("s2000000000000003").unwrap();
    assert_eq!((counts.failed, counts.open()), (1, 0));
    store.forget("s2000000000000003").unwrap();
    assert_eq!(
        store.counts("s2000000000000003").unwrap(),
        LeaseCounts::default()
    );
}

fn owners_are_served_in_turn(store: &dyn WorkerStore) {
    let host = store
        .register_host(30, "fair", "adb", &phones(&["p0"]), 0)
        .unwrap();
    // Token 1 offers 3 trials first, token 2 two trials after.
    store
        .offer("s3000000000000001", Some(1), "adb", &[0, 1, 2], "x", 0)
        .unwrap();
    store
        .offer("s3000000000000002", Some(2), "adb", &[0, 1], "y", 0)
        .unwrap();
    let mut order = Vec::new();
    while let Some(lease) = store.claim(&host, "p0", "adb", 0, LEASE_MS).unwrap() {
        order.push((lease.session.clone(), lease.index));
        assert!(store.commit(&lease.id, &host, 0, "", "").unwrap().is_ok());
    }
    // Alternating between the tokens while both wait, each in its own order.
    let expected = [
        ("s3000000000000001", 0),
        ("s3000000000000002", 0),
        ("s3000000000000001", 1),
        ("s3000000000000002", 1),
        ("s3000000000000001", 2),
    ];
    let expected: Vec<_> = expected.iter().map(|(s, i)| (s.to_string(), *i)).collect();
    assert_eq!(order, expected);
}

fn phones_failing_twice_in_a_row_leave_service(store: &dyn WorkerStore) {
    let host = store
        .register_host(40, "flaky", "sim", &phones(&["p0"]), 0)
        .unwrap();
    store
        .offer("s4000000000000001", None, "sim", &[0, 1], "x", 0)
        .unwrap();
    let lease = store
        .claim(&host, "p0", "sim", 0, LEASE_MS)
        .unwrap()
        .unwrap();
    assert_eq!(
        store.give_back(&lease.id, &host).unwrap(),
        Some(Requeued::Again)
    );
    assert_eq!(
        store
            .phone_result(&host, "p0", Some("no trajectory"))
            .unwrap(),
        PhoneState::Ready
    );
    // A success in between resets the count.
    assert_eq!(
        store.phone_result(&host, "p0", None).unwrap(),
        PhoneState::Ready
    );
    let mut state = PhoneState::Ready;
    for _ in 0..FAILURES_OUT_OF_SERVICE {
        state = store
            .phone_result(&host, "p0", Some("app crashed"))
            .unwrap();
    }
    assert_eq!(state, PhoneState::OutOfService);
    let phone = store
        .phones()
        .unwrap()
        .into_iter()
        .find(|p| p.host == host)
        .unwrap();
    assert_eq!(phone.state, PhoneState::OutOfService);
    assert_eq!(phone.last_error.as_deref(), Some("app crashed"));
    // It takes no lease, also after a heartbeat that lists it; a registration brings it back.
    store
        .heartbeat(&host, &phones(&["p0"]), &[], 1, LEASE_MS)
        .unwrap();
    assert!(
        store
            .claim(&host, "p0", "sim", 1, LEASE_MS)
            .unwrap()
            .is_none()
    );
    store
        .register_host(40, "flaky", "sim", &phones(&["p0"]), 2)
        .unwrap();
    assert!(
        store
            .claim(&host, "p0", "sim", 2, LEASE_MS)
            .unwrap()
            .is_some()
    );
    store.withdraw("s4000000000000001").unwrap();
}

fn withdrawn_trials_are_not_leased_and_their_leases_abort(store: &dyn WorkerStore) {
    let host = store
        .register_host(50, "cancel", "sim", &phones(&["p0", "p1"]), 0)
        .unwrap();
    store
        .offer("s5000000000000001", None, "sim", &[0, 1, 2], "x", 0)
        .unwrap();
    let lease = store
        .claim(&host, "p0", "sim", 0, LEASE_MS)
        .unwrap()
        .unwrap();
    store.withdraw("s5000000000000001").unwrap();
    assert!(
        store
            .claim(&host, "p1", "sim", 0, LEASE_MS)
            .unwrap()
            .is_none()
    );
    let abort = store
        .heartbeat(
            &host,
            &phones(&["p0", "p1"]),
            std::slice::from_ref(&lease.id),
            1,
            LEASE_MS,
        )
        .unwrap();
    assert_eq!(abort, vec![lease.id.clone()]);
    assert!(store.commit(&lease.id, &host, 1, "", "").unwrap().is_err());
    assert_eq!(store.counts("s5000000000000001").unwrap().open(), 0);
    // Offered again (a resumed session): the named trials only, committed ones included
    // (their files were lost with the crash that interrupted them).
    store
        .offer("s5000000000000001", None, "sim", &[2], "x", 5)
        .unwrap();
    let again = store
        .claim(&host, "p1", "sim", 5, LEASE_MS)
        .unwrap()
        .unwrap();
    assert_eq!(again.index, 2);
    assert!(
        store
            .claim(&host, "p0", "sim", 5, LEASE_MS)
            .unwrap()
            .is_none()
    );
    store.forget("s5000000000000001").unwrap();
}

fn failed_trials_are_kept_for_the_status(store: &dyn WorkerStore) {
    let session = "s6000000000000001";
    assert!(store.failures(session).unwrap().is_empty());
    for k in 0..(crate::storage::workers::MAX_FAILURES_KEPT as u32 + 5) {
        store
            .record_failure(
                session,
                &TrialFailure {
                    index: k,
                    source: "lab-a/sim:0".into(),
                    error: format!("trial:{k}: not a number"),
                    at_ms: i64::from(k),
                },
            )
            .unwrap();
    }
    let kept = store.failures(session).unwrap();
    assert_eq!(kept.len(), crate::storage::workers::MAX_FAILURES_KEPT);
    assert_eq!(kept[0].index, 0);
    assert_eq!(kept[1].error, "trial:1: not a number");
    store.forget(session).unwrap();
    assert!(store.failures(session).unwrap().is_empty());
}

fn committed_trials_reach_the_job_once(store: &dyn WorkerStore) {
    let session = "s7000000000000001";
    let host = store
        .register_host(70, "hands", "sim", &phones(&["p0"]), 0)
        .unwrap();
    let count = MAX_TAKEN_PER_CALL as u32 + 3;
    let all: Vec<u32> = (0..count).collect();
    store.offer(session, Some(7), "sim", &all, "x", 0).unwrap();
    assert!(store.take_committed(session, None).unwrap().is_empty());
    // Committed in reverse order, each with its own text.
    let mut leases = Vec::new();
    while let Some(lease) = store.claim(&host, "p0", "sim", 0, LEASE_MS).unwrap() {
        let tum = format!("{}.0 0 0 0 0 0 0 1\n", lease.index);
        assert!(
            store
                .commit(&lease.id, &host, 1, &tum, "hands/p0")
                .unwrap()
                .is_ok()
        );
        leases.push(lease);
    }
    assert_eq!(leases.len(), count as usize);
    // A refused commit stores nothing: the trial stays taken as it was.
    assert!(
        store
            .commit(&leases[0].id, &host, 2, "garbage", "hands/p0")
            .unwrap()
            .is_err()
    );
    // Bounded per call, by index, each once; then nothing more.
    let first = store.take_committed(session, None).unwrap();
    assert_eq!(first.len(), MAX_TAKEN_PER_CALL);
    assert_eq!(
        (
            first[0].index,
            first[0].tum.as_str(),
            first[0].source.as_str()
        ),
        (0, "0.0 0 0 0 0 0 0 1\n", "hands/p0")
    );
    let rest = store.take_committed(session, None).unwrap();
    let indices: Vec<u32> = first.iter().chain(&rest).map(|t| t.index).collect();
    assert_eq!(indices, all);
    assert!(store.take_committed(session, None).unwrap().is_empty());
    assert_eq!(store.counts(session).unwrap().done, count);
    // A trial committed after a withdraw (a job that ended) is dropped by the next offer,
    // which plays it again: a resumed job takes only what its own offer brought.
    store.offer(session, Some(7), "sim", &[0], "x", 5).unwrap();
    let lease = store
        .claim(&host, "p0", "sim", 5, LEASE_MS)
        .unwrap()
        .unwrap();
    store
        .commit(&lease.id, &host, 6, "late", "hands/p0")
        .unwrap()
        .unwrap();
    store.withdraw(session).unwrap();
    assert!(store.take_committed(session, None).unwrap().is_empty());
    store.offer(session, Some(7), "sim", &[0], "x", 7).unwrap();
    let lease = store
        .claim(&host, "p0", "sim", 7, LEASE_MS)
        .unwrap()
        .unwrap();
    store
        .commit(&lease.id, &host, 8, "again", "hands/p0")
        .unwrap()
        .unwrap();
    store.offer(session, Some(7), "sim", &[0], "x", 9).unwrap();
    assert!(store.take_committed(session, None).unwrap().is_empty());
    store.forget(session).unwrap();
}

/// Two instances at once on one store, through `a` and `b` (the same handle twice for a store
/// one instance owns): every trial is leased once and committed once, a commit raced from both
/// sides succeeds once, and every committed trial is taken once. `a` and `b` must be empty.
pub(crate) fn racing_instances(a: &dyn WorkerStore, b: &dyn WorkerStore) {
    let stores = [a, b];
    let session = "s8000000000000001";
    let serials: Vec<String> = (0..6).map(|n| format!("p{n}")).collect();
    let host = a.register_host(80, "race", "sim", &serials, 0).unwrap();
    let trials: Vec<u32> = (0..24).collect();
    b.offer(session, Some(8), "sim", &trials, "x", 0).unwrap();
    // Six phones claim and commit at once, alternating between the handles.
    let played: Vec<(u32, String)> = std::thread::scope(|s| {
        let runs: Vec<_> = serials
            .iter()
            .enumerate()
            .map(|(n, phone)| {
                let (mine, other) = (stores[n % 2], stores[(n + 1) % 2]);
                let host = host.clone();
                s.spawn(move || {
                    let mut got = Vec::new();
                    while let Some(lease) = mine.claim(&host, phone, "sim", 0, LEASE_MS).unwrap() {
                        let tum = format!("trial {}", lease.index);
                        other
                            .commit(&lease.id, &host, 1, &tum, phone)
                            .unwrap()
                            .unwrap();
                        got.push((lease.index, lease.id));
                    }
                    got
                })
            })
            .collect();
        runs.into_iter().flat_map(|r| r.join().unwrap()).collect()
    });
    let indices: BTreeSet<u32> = played.iter().map(|(i, _)| *i).collect();
    assert_eq!(
        played.len(),
        trials.len(),
        "each trial leased once: {played:?}"
    );
    assert_eq!(indices.into_iter().collect::<Vec<_>>(), trials);
    assert_eq!(a.counts(session).unwrap().done, trials.len() as u32);
    // Both handles take at once: together they take every trial, none twice.
    let barrier = Barrier::new(2);
    let taken: Vec<u32> = std::thread::scope(|s| {
        let runs: Vec<_> = stores
            .iter()
            .map(|store| {
                let barrier = &barrier;
                s.spawn(move || {
                    barrier.wait();
                    let mut got = Vec::new();
                    loop {
                        let batch = store.take_committed(session, None).unwrap();
                        if batch.is_empty() {
                            return got;
                        }
                        got.extend(batch.iter().map(|t| t.index));
                    }
                })
            })
            .collect();
        runs.into_iter().flat_map(|r| r.join().unwrap()).collect()
    });
    let mut sorted = taken.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, trials, "each committed trial taken once: {taken:?}");
    // One lease, committed from both sides at the same moment: exactly one succeeds.
    for round in 0..10u32 {
        let one = format!("s80000000000001{round:02}");
        a.offer(&one, None, "sim", &[0], "x", 0).unwrap();
        let lease = b.claim(&host, "p0", "sim", 0, LEASE_MS).unwrap().unwrap();
        let wins = std::thread::scope(|s| {
            let runs: Vec<_> = stores
                .iter()
                .map(|store| {
                    let (barrier, lease, host) = (&barrier, &lease, &host);
                    s.spawn(move || {
                        barrier.wait();
                        store
                            .commit(&lease.id, host, 1, "t", "race/p0")
                            .unwrap()
                            .is_ok()
                    })
                })
                .collect();
            runs.into_iter()
                .map(|r| r.join().unwrap())
                .filter(|won| *won)
                .count()
        });
        assert_eq!(wins, 1, "round {round}");
        assert_eq!(b.take_committed(&one, None).unwrap().len(), 1);
        assert!(a.take_committed(&one, None).unwrap().is_empty());
    }
}

/// With several instances on one database a job takes committed trials only while its
/// instance plays the session: one that woke from a pause to find its session adopted takes
/// none of the adopter's. `store` holds both the sessions and the leases (one database).
pub(crate) fn only_the_player_takes<S>(store: &S)
where
    S: crate::storage::MetadataStore + WorkerStore,
{
    use crate::model::PlaybackKind;
    use crate::model::Step;
    use crate::storage::instances::InstanceStore;
    use crate::storage::metadata::StepRecord;
    let session = "s9000000000000001";
    store
        .insert_session(
            session,
            &crate::storage::conformance::new_session(None, PlaybackKind::Sim, None),
        )
        .unwrap();
    store
        .transition(
            session,
            Step::AcceptRecording,
            StepRecord::RecordingBytes(9),
        )
        .unwrap();
    let now = crate::storage::now_ms();
    let (a, b) = ("instance-pa", "instance-pb");
    InstanceStore::heartbeat(store, a, now).unwrap();
    assert!(store.claim_session(session, a, now - 30_000).unwrap());
    let host = store
        .register_host(90, "paused", "sim", &phones(&["p0"]), 0)
        .unwrap();
    store
        .offer(session, Some(9), "sim", &[0, 1], "x", 0)
        .unwrap();
    let commit_next = || {
        let lease = store
            .claim(&host, "p0", "sim", 0, LEASE_MS)
            .unwrap()
            .unwrap();
        let tum = format!("{}.0 0 0 0 0 0 0 1\n", lease.index);
        assert!(
            store
                .commit(&lease.id, &host, 1, &tum, "paused/p0")
                .unwrap()
                .is_ok()
        );
    };
    commit_next();
    // B is no player: it takes nothing; A, the player, takes the trial.
    assert!(store.take_committed(session, Some(b)).unwrap().is_empty());
    let taken = store.take_committed(session, Some(a)).unwrap();
    assert_eq!(taken.iter().map(|t| t.index).collect::<Vec<_>>(), [0]);
    // A falls silent; B adopts the session. A, awake again, takes nothing more: the next
    // trial is B's.
    commit_next();
    InstanceStore::heartbeat(store, b, now + 60_000).unwrap();
    assert!(store.claim_session(session, b, now + 30_000).unwrap());
    assert!(store.take_committed(session, Some(a)).unwrap().is_empty());
    let taken = store.take_committed(session, Some(b)).unwrap();
    assert_eq!(taken.iter().map(|t| t.index).collect::<Vec<_>>(), [1]);
    // Alone on its database (no player named), a job takes as before.
    assert!(store.take_committed(session, None).unwrap().is_empty());
    assert!(
        store
            .delete_session(session, crate::storage::conformance::KEEP)
            .unwrap()
    );
}
