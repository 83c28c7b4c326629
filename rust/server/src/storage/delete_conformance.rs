//! The conformance suite of unfinished deletes ([`DeleteStore`]), for both metadata stores:
//! a delete records its bytes under the deleter's claim; a lapsed claim is taken over by one
//! sweeper only, even when several claim at once; a finished delete is forgotten, twice
//! without harm.

use crate::model::PlaybackKind;
use crate::storage::conformance::new_session;
use crate::storage::deletes::Claim;
use crate::storage::metadata::MetadataStore;

/// Runs the checks on `store` (sessions `s7de1…` and `s7de2…` are its own).
pub(crate) fn unfinished_deletes(store: &dyn MetadataStore) {
    let now = crate::storage::now_ms();
    let new = new_session(None, PlaybackKind::Upload, None);
    for id in ["s7de1000000000001", "s7de1000000000002"] {
        store.insert_session(id, &new).unwrap();
    }
    let deleter = Claim {
        instance: "deleter",
        until_ms: now + 30_000,
    };
    assert!(store.delete_session("s7de1000000000001", deleter).unwrap());
    assert!(store.session("s7de1000000000001").unwrap().is_none());
    assert!(mine(store).contains(&"s7de1000000000001".to_string()));
    // A second delete of a gone session records nothing more (and keeps the claim).
    assert!(!store.delete_session("s7de1000000000001", deleter).unwrap());
    let sweeper = Claim {
        instance: "sweeper",
        until_ms: now + 60_000,
    };
    // While the deleter's claim holds, no sweeper takes the work.
    let taken = store.claim_unfinished_deletes(sweeper, now, 64).unwrap();
    assert!(
        !taken.contains(&"s7de1000000000001".to_string()),
        "{taken:?}"
    );
    // Past it (the deleter died), one sweeper takes it, and then no other.
    let later = now + 30_001;
    let taken = store.claim_unfinished_deletes(sweeper, later, 64).unwrap();
    assert_eq!(taken, ["s7de1000000000001"]);
    let other = Claim {
        instance: "other",
        until_ms: later + 60_000,
    };
    assert!(
        store
            .claim_unfinished_deletes(other, later, 64)
            .unwrap()
            .is_empty()
    );
    // Finished: forgotten; finishing again (the deleter woke up, a second sweeper) is fine.
    store.finish_delete("s7de1000000000001").unwrap();
    store.finish_delete("s7de1000000000001").unwrap();
    assert!(!mine(store).contains(&"s7de1000000000001".to_string()));
    // The limit holds: of three lapsed deletes, two are taken, then the third.
    for id in [
        "s7de1000000000002",
        "s7de1000000000003",
        "s7de1000000000004",
    ] {
        if id != "s7de1000000000002" {
            store.insert_session(id, &new).unwrap();
        }
        let lapsed = Claim {
            instance: "dead",
            until_ms: now - 1,
        };
        assert!(store.delete_session(id, lapsed).unwrap());
    }
    let first = store.claim_unfinished_deletes(sweeper, now, 2).unwrap();
    assert_eq!(first.len(), 2, "{first:?}");
    let rest = store.claim_unfinished_deletes(other, now, 2).unwrap();
    assert_eq!(rest.len(), 1, "{rest:?}");
    assert!(!first.contains(&rest[0]));
    for id in first.iter().chain(&rest) {
        store.finish_delete(id).unwrap();
    }
    assert!(mine(store).is_empty(), "{:?}", mine(store));
}

/// Two instances on one database claim many lapsed deletes at once: each is taken once.
pub(crate) fn racing_sweepers(a: &dyn MetadataStore, b: &dyn MetadataStore) {
    let now = crate::storage::now_ms();
    let new = new_session(None, PlaybackKind::Upload, None);
    let ids: Vec<String> = (0..40).map(|i| format!("s7de200000000{i:04x}")).collect();
    let dead = Claim {
        instance: "dead",
        until_ms: now - 1,
    };
    for id in &ids {
        a.insert_session(id, &new).unwrap();
        assert!(a.delete_session(id, dead).unwrap());
    }
    let claim = |store: &dyn MetadataStore, instance: &'static str| {
        let mut all = Vec::new();
        loop {
            let claim = Claim {
                instance,
                until_ms: now + 60_000,
            };
            let taken = store.claim_unfinished_deletes(claim, now, 3).unwrap();
            if taken.is_empty() {
                return all;
            }
            all.extend(taken);
        }
    };
    let (from_a, from_b) = std::thread::scope(|s| {
        let ta = s.spawn(|| claim(a, "a"));
        let tb = s.spawn(|| claim(b, "b"));
        (ta.join().unwrap(), tb.join().unwrap())
    });
    let mut all: Vec<String> = from_a.iter().chain(&from_b).cloned().collect();
    all.sort();
    assert_eq!(all, ids, "each taken once: a {from_a:?}, b {from_b:?}");
    for id in &ids {
        a.finish_delete(id).unwrap();
    }
}

/// The unfinished deletes of this suite's sessions.
fn mine(store: &dyn MetadataStore) -> Vec<String> {
    store
        .unfinished_deletes()
        .unwrap()
        .into_iter()
        .filter(|id| id.starts_with("s7de1"))
        .collect()
}
