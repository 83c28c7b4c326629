//! The conformance suites of the two storage seams: what every implementation of
//! [`MetadataStore`] and of [`BlobStore`] must do, written once against the traits. The
//! embedded stores run them (`storage::sqlite`'s and `storage::files`' tests); another
//! implementation calls [`metadata_store`] or [`blob_store`] on a fresh, empty store of its
//! own.

use std::io::Read as _;

use crate::error::Error;
use crate::model::{
    Caller, NewSession, PlaybackKind, Role, SessionState, Step, UsageFull,
    estimate_settings::EstimateSettings,
};
use crate::storage::blobs::{BlobStore, body_stream};
use crate::storage::deletes::Claim;
use crate::storage::keys::SessionObject;
use crate::storage::metadata::{JobEnd, MetadataStore, StepRecord};

/// A claim on a delete's bytes that never lapses: the deletes of these checks are not swept.
pub(crate) const KEEP: Claim<'static> = Claim {
    instance: "conformance",
    until_ms: i64::MAX,
};

/// Runs every check on `store`, which must be empty.
pub(crate) fn metadata_store(store: &dyn MetadataStore) {
    sessions_are_created_once_per_key(store);
    transitions_follow_the_state_table(store);
    trials_are_ordered_idempotent_and_all_or_nothing(store);
    jobs_and_devices_are_recorded(store);
    tokens_keep_only_what_they_must(store);
    share_links_open_one_session(store);
    usage_is_counted_over_its_windows(store);
    deleting_a_session_removes_what_belongs_to_it(store);
    venues_hold_members_and_sessions_of_one_convention(store);
    venue_contributions_are_kept_per_generation(store);
    instances_own_adopt_and_stop_sessions(store);
}

/// A session request with the server's defaults (5 trials), for the suites and unit tests.
pub(crate) fn new_session(
    key: Option<&str>,
    playback: PlaybackKind,
    owner: Option<i64>,
) -> NewSession<'_> {
    NewSession {
        idempotency_key: key,
        trials_total: 5,
        playback,
        settings: EstimateSettings::defaults(sitar_core::DEFAULT_SETTING).unwrap(),
        adaptive_min: None,
        adaptive_k: 3,
        legacy: false,
        owner,
        venue: None,
        convention: sitar_core::Convention::Unity,
        calibration: None,
    }
}

fn sessions_are_created_once_per_key(store: &dyn MetadataStore) {
    let new = new_session(Some("key-1"), PlaybackKind::Sim, Some(7));
    assert_eq!(
        store.insert_session("s1000000000000001", &new).unwrap(),
        ("s1000000000000001".to_string(), true)
    );
    // The same key and request: the first session, not a new one.
    assert_eq!(
        store.insert_session("s1000000000000002", &new).unwrap(),
        ("s1000000000000001".to_string(), false)
    );
    // The same key with another request is refused, naming the key.
    let other = NewSession {
        trials_total: 9,
        ..new_session(Some("key-1"), PlaybackKind::Sim, Some(7))
    };
    let refused = store.insert_session("s1000000000000003", &other);
    assert!(refused.is_err(), "{refused:?}");
    assert!(store.session("s1000000000000003").unwrap().is_none());
    // Another calibration is another request too.
    let calibrated = NewSession {
        calibration: Some("lab-phone"),
        ..new_session(Some("key-1"), PlaybackKind::Sim, Some(7))
    };
    assert!(
        store
            .insert_session("s1000000000000003", &calibrated)
            .is_err()
    );
    let row = store.session("s1000000000000001").unwrap().unwrap();
    assert_eq!(row.state, SessionState::Created);
    assert_eq!((row.trials_total, row.owner), (5, Some(7)));
    assert_eq!(row.calibration, None);
    // A calibrated session keeps its calibration's name, and its key returns it.
    let calibrated = NewSession {
        idempotency_key: Some("key-cal"),
        ..calibrated
    };
    for _ in 0..2 {
        assert_eq!(
            store
                .insert_session("s10000000000000c1", &calibrated)
                .unwrap()
                .0,
            "s10000000000000c1"
        );
    }
    let row = store.session("s10000000000000c1").unwrap().unwrap();
    assert_eq!(row.calibration.as_deref(), Some("lab-phone"));
    assert!(store.delete_session("s10000000000000c1", KEEP).unwrap());
    assert!(store.session("s0000000000000000").unwrap().is_none());
    let created = store
        .session_created_ms("s1000000000000001")
        .unwrap()
        .unwrap();
    assert!(created > 1_600_000_000_000, "{created}");
    // Listing: newest first, by owner.
    let new2 = new_session(None, PlaybackKind::Upload, Some(8));
    store.insert_session("s1000000000000004", &new2).unwrap();
    let all: Vec<String> = store
        .recent_sessions(None, 10)
        .unwrap()
        .into_iter()
        .map(|s| s.id)
        .collect();
    assert_eq!(all, ["s1000000000000004", "s1000000000000001"]);
    let mine = store.recent_rows(Some(8), 10).unwrap();
    assert_eq!(mine.sessions.len(), 1);
    assert!(mine.unreadable.is_empty());
    assert_eq!(store.recent_sessions(None, 1).unwrap().len(), 1);
    let created_ones = store.sessions_in(&[SessionState::Created]).unwrap();
    let ids: Vec<&str> = created_ones
        .sessions
        .iter()
        .map(|s| s.id.as_str())
        .collect();
    assert_eq!(
        ids,
        ["s1000000000000001", "s1000000000000004"],
        "oldest first"
    );
}

fn transitions_follow_the_state_table(store: &dyn MetadataStore) {
    let id = "s1000000000000001";
    let before = store
        .transition(id, Step::AcceptRecording, StepRecord::RecordingBytes(42))
        .unwrap();
    assert_eq!(before, SessionState::Created);
    // A step the state does not allow is a transition error naming the state; nothing changes.
    let refused = store.transition(id, Step::Finish, StepRecord::Nothing);
    assert!(
        matches!(refused, Err(Error::Transition { state, .. })
            if state == SessionState::Uploaded.as_str()),
        "{refused:?}"
    );
    store
        .transition(id, Step::StartPlaying, StepRecord::Nothing)
        .unwrap();
    store
        .transition(id, Step::Publish, StepRecord::ResultsTrials(2))
        .unwrap();
    store
        .transition(id, Step::Stop, StepRecord::StopReason("adaptive stop"))
        .unwrap();
    let row = store.session(id).unwrap().unwrap();
    assert_eq!(row.state, SessionState::Playing);
    assert_eq!(row.recording_bytes, Some(42));
    assert_eq!(row.results_trials, 2);
    assert_eq!(row.stop_reason.as_deref(), Some("adaptive stop"));
    let missing = store.transition("s0000000000000000", Step::Finish, StepRecord::Nothing);
    assert!(matches!(missing, Err(Error::NotFound(_))), "{missing:?}");
    // A failure records why and finishes the session, whatever the step table says.
    store.fail_unreadable(id, "bad row").unwrap();
    let row = store.session(id).unwrap().unwrap();
    assert_eq!(row.state, SessionState::Failed);
    assert_eq!(row.error.as_deref(), Some("bad row"));
    // Finished sessions expire after their finish; idle ones after their creation.
    let expired = store.expired(i64::MAX).unwrap();
    assert!(expired.contains(&id.to_string()), "{expired:?}");
    assert!(store.expired(0).unwrap().is_empty());
    assert_eq!(
        store.latest_session(true, false, None).unwrap(),
        None,
        "no session is done"
    );
    assert_eq!(
        store
            .latest_session(false, false, Some(8))
            .unwrap()
            .as_deref(),
        Some("s1000000000000004")
    );
}

fn trials_are_ordered_idempotent_and_all_or_nothing(store: &dyn MetadataStore) {
    let id = "s1000000000000004";
    let mut stored = Vec::new();
    let mut add = |key: Option<&str>, play: Option<u32>, source: &str| {
        store.add_trial(id, key, play, 10, source, &mut |index| {
            stored.push(index);
            Ok(())
        })
    };
    assert_eq!(add(Some("t1"), Some(1), "sim:0").unwrap(), (0, true));
    assert_eq!(add(Some("t2"), Some(0), "sim:1").unwrap(), (1, true));
    assert_eq!(add(Some("t1"), Some(1), "sim:0").unwrap(), (0, false));
    assert_eq!(add(None, Some(2), "sim:0").unwrap(), (2, true));
    assert_eq!(stored, [0, 1, 2], "the key seen before stores nothing");
    // A store that fails leaves no row behind.
    let failed = store.add_trial(id, None, Some(3), 10, "sim:1", &mut |_| {
        Err(Error::Internal("disk".into()))
    });
    assert!(failed.is_err());
    assert_eq!(store.trial_count(id).unwrap(), 3);
    assert_eq!(
        store.trials_in_order(id).unwrap(),
        vec![(1, 0), (0, 1), (2, 2)]
    );
    assert_eq!(
        store.trial_sources(id).unwrap(),
        vec![
            ("sim:0".to_string(), vec![0, 2]),
            ("sim:1".to_string(), vec![1])
        ]
    );
    assert_eq!(store.trial_count("s0000000000000000").unwrap(), 0);
}

fn jobs_and_devices_are_recorded(store: &dyn MetadataStore) {
    let id = "s1000000000000004";
    let first = store.start_job(id, "playback", "instance-j").unwrap();
    let second = store.start_job(id, "estimate", "instance-j").unwrap();
    assert_ne!(first, second);
    store.finish_job(first, JobEnd::Done, None).unwrap();
    store
        .finish_job(second, JobEnd::Failed, Some("no trials"))
        .unwrap();
    let third = store.start_job(id, "estimate", "instance-j").unwrap();
    // Its instance restarts: its own running jobs are interrupted, once.
    let now = crate::storage::now_ms();
    store.heartbeat("instance-j", now).unwrap();
    assert_eq!(store.interrupt_jobs(Some("instance-j"), now).unwrap(), 1);
    assert_eq!(store.interrupt_jobs(Some("instance-j"), now).unwrap(), 0);
    let jobs = store.jobs_of(id).unwrap();
    let (done, failed) = (JobEnd::Done.as_str(), JobEnd::Failed.as_str());
    assert_eq!(
        jobs,
        [
            ("playback", done),
            ("estimate", failed),
            ("estimate", "interrupted")
        ]
        .map(|(k, s)| (k.to_string(), s.to_string()))
    );
    let _ = third;
    store
        .upsert_device("emulator-5554", "busy", Some(id))
        .unwrap();
    store.upsert_device("emulator-5556", "idle", None).unwrap();
    store.upsert_device("emulator-5554", "idle", None).unwrap();
    let devices = store.devices().unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(devices[0].0, "emulator-5554");
    assert_eq!(
        (devices[0].1.as_str(), devices[0].2.as_deref()),
        ("idle", None)
    );
}

fn tokens_keep_only_what_they_must(store: &dyn MetadataStore) {
    let token = "sitar_conformanceAAAAAAAAAAAAAAAAAAAAAAAAAA";
    store.insert_token("phone-1", Role::App, token).unwrap();
    assert!(
        store
            .insert_token("phone-1", Role::App, "sitar_other")
            .is_err()
    );
    assert!(store.has_token("phone-1").unwrap());
    assert!(!store.has_token("phone-2").unwrap());
    let caller = store.caller(token).unwrap();
    assert!(
        matches!(&caller, Some(Caller::Token { role: Role::App, name, .. }) if name == "phone-1"),
        "{caller:?}"
    );
    assert_eq!(store.caller("sitar_nope").unwrap(), None);
    assert_eq!(store.caller("").unwrap(), None);
    // A preset replaces the hash of its name.
    let preset = "sitar_presetBBBBBBBBBBBBBBBBBBBBBBBBBBBBBB";
    store.set_token("phone-1", Role::Admin, preset).unwrap();
    assert_eq!(store.caller(token).unwrap(), None);
    assert!(store.caller(preset).unwrap().unwrap().is_admin());
    let listed = store.tokens().unwrap();
    assert_eq!(listed.len(), 1);
    assert_eq!(
        (listed[0].name.as_str(), listed[0].role),
        ("phone-1", Role::Admin)
    );
    assert!(store.revoke_token("phone-1").unwrap());
    assert!(!store.revoke_token("phone-1").unwrap());
    assert_eq!(store.caller(preset).unwrap(), None);
    assert_eq!(store.token_count().unwrap(), 0);
}

fn share_links_open_one_session(store: &dyn MetadataStore) {
    let id = "s1000000000000004";
    let link = "share_CCCCCCCCCCCCCCCCCCCCCCCCCCCCCCCCCCCC";
    store.insert_share(id, link).unwrap();
    assert_eq!(store.shared_session(link).unwrap().as_deref(), Some(id));
    assert_eq!(store.shared_session("share_nope").unwrap(), None);
    assert_eq!(store.revoke_shares(id).unwrap(), 1);
    assert_eq!(store.shared_session(link).unwrap(), None);
}

fn usage_is_counted_over_its_windows(store: &dyn MetadataStore) {
    const HOUR: i64 = 3_600_000;
    let t0 = 1_700_000_000_000;
    assert_eq!(store.count_session_creation(1, 2, t0).unwrap(), Ok(()));
    assert_eq!(store.count_session_creation(1, 2, t0 + 10).unwrap(), Ok(()));
    assert_eq!(
        store.count_session_creation(1, 2, t0 + 20).unwrap(),
        Err(UsageFull {
            used: 2,
            frees_at_ms: t0 + HOUR
        })
    );
    // Another token has its own count; an hour later the first may create again.
    assert_eq!(store.count_session_creation(2, 2, t0 + 20).unwrap(), Ok(()));
    assert_eq!(
        store.count_session_creation(1, 2, t0 + HOUR + 1).unwrap(),
        Ok(())
    );
    store.add_uploaded(1, 1000, t0).unwrap();
    store.add_uploaded(1, 500, t0 + 2 * HOUR).unwrap();
    store.add_uploaded(2, 7, t0).unwrap();
    let day = store.uploaded_in_day(1, t0 + 3 * HOUR).unwrap();
    assert_eq!(day.used, 1500);
    // A day after the first upload, only the later one counts.
    let later = store.uploaded_in_day(1, t0 + 24 * HOUR + HOUR).unwrap();
    assert_eq!(later.used, 500);
}

fn deleting_a_session_removes_what_belongs_to_it(store: &dyn MetadataStore) {
    let id = "s1000000000000004";
    store
        .insert_share(id, "share_DDDDDDDDDDDDDDDDDDDDDDDDDDDDDDDDDDDD")
        .unwrap();
    store
        .upsert_device("emulator-5554", "busy", Some(id))
        .unwrap();
    assert!(store.delete_session(id, KEEP).unwrap());
    assert!(!store.delete_session(id, KEEP).unwrap());
    assert!(store.session(id).unwrap().is_none());
    assert_eq!(store.trial_count(id).unwrap(), 0);
    assert!(store.jobs_of(id).unwrap().is_empty());
    let device = store
        .devices()
        .unwrap()
        .into_iter()
        .find(|d| d.0 == "emulator-5554");
    assert_eq!(device.unwrap().2, None, "the device forgets the session");
    // The same server-made id may not come back, but a new one works as before.
    let new = new_session(None, PlaybackKind::Upload, None);
    assert!(store.insert_session("s1000000000000005", &new).unwrap().1);
}

/// Runs every check on `store`, which must be empty and without quotas.
pub(crate) async fn blob_store(store: &dyn BlobStore) {
    whole_objects_are_replaced_and_removed(store);
    uploads_are_staged_checked_and_published_whole(store).await;
    resumable_parts_keep_exactly_what_arrived(store).await;
    a_recording_of_declared_size_is_published_whole(store).await;
    deleted_sessions_are_removed_whole_and_again(store);
    scenes_are_kept_whole_with_their_tag(store);
}

const A: &str = "s2000000000000001";
const B: &str = "s2000000000000002";
const C: &str = "s2000000000000003";

fn chunks(parts: &[&'static [u8]], broken: bool) -> crate::storage::blobs::BodyStream<'static> {
    let mut items: Vec<Result<axum::body::Bytes, String>> = parts
        .iter()
        .map(|p| Ok(axum::body::Bytes::from_static(p)))
        .collect();
    if broken {
        items.push(Err("connection reset".into()));
    }
    body_stream(futures_util::stream::iter(items))
}

fn read_all(opened: crate::storage::blobs::ObjectReader) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut reader = opened.bytes;
    reader.read_to_end(&mut bytes).unwrap();
    bytes
}

fn whole_objects_are_replaced_and_removed(store: &dyn BlobStore) {
    store.create_session(A).unwrap();
    store.create_session(B).unwrap();
    for object in [
        SessionObject::Trial(0),
        SessionObject::Trial(3),
        SessionObject::ResultsCsv,
        SessionObject::ResultsJson,
        SessionObject::Evidence,
        SessionObject::Spans,
        SessionObject::Thumbnail(5),
        SessionObject::Timestamps,
    ] {
        assert!(!store.exists(A, object));
        assert_eq!(store.get(A, object).unwrap(), None, "{object:?}");
        assert_eq!(store.len(A, object).unwrap(), None);
        store.put(A, object, b"first").unwrap();
        store.put(A, object, b"second, longer").unwrap();
        assert!(store.exists(A, object));
        assert_eq!(store.get(A, object).unwrap().unwrap(), b"second, longer");
        assert_eq!(store.len(A, object).unwrap(), Some(14));
        assert_eq!(store.peek(A, object, 6).unwrap().unwrap(), b"second");
        assert_eq!(
            store.peek(A, object, 99).unwrap().unwrap(),
            b"second, longer"
        );
        let opened = store.open(A, object).unwrap().unwrap();
        assert_eq!(opened.len, 14);
        assert_eq!(read_all(opened), b"second, longer");
        // Another session's object of the same name is its own.
        assert_eq!(store.get(B, object).unwrap(), None, "{object:?}");
        store.remove(A, object).unwrap();
        store.remove(A, object).unwrap();
        assert_eq!(store.get(A, object).unwrap(), None);
        assert_eq!(store.peek(A, object, 6).unwrap(), None);
        assert!(store.open(A, object).unwrap().is_none());
    }
    // An object of many chunks reads back whole through a reader; an empty one peeks empty.
    let long: Vec<u8> = (0..(3 << 20) + 5).map(|i: u32| (i % 251) as u8).collect();
    store.put(A, SessionObject::Trial(7), &long).unwrap();
    assert!(read_all(store.open(A, SessionObject::Trial(7)).unwrap().unwrap()) == long);
    assert_eq!(
        store.peek(A, SessionObject::Trial(7), 3).unwrap().unwrap(),
        &long[..3]
    );
    store.put(A, SessionObject::Trial(8), b"").unwrap();
    assert_eq!(
        store.peek(A, SessionObject::Trial(8), 3).unwrap().unwrap(),
        b""
    );
    store.remove(A, SessionObject::Trial(7)).unwrap();
    store.remove(A, SessionObject::Trial(8)).unwrap();
    store
        .append_line(A, SessionObject::History, "{\"trials\":2}")
        .unwrap();
    store
        .append_line(A, SessionObject::History, "{\"trials\":3}")
        .unwrap();
    assert_eq!(
        store.get(A, SessionObject::History).unwrap().unwrap(),
        b"{\"trials\":2}\n{\"trials\":3}\n"
    );
    store
        .put(A, SessionObject::Trial(1), b"1 0 0 0 0 0 0 1\n")
        .unwrap();
    let local = std::fs::read(store.local_file(A, SessionObject::Trial(1))).unwrap();
    assert_eq!(
        local, b"1 0 0 0 0 0 0 1\n",
        "a local file holds the object's bytes"
    );
}

async fn uploads_are_staged_checked_and_published_whole(store: &dyn BlobStore) {
    let refused = store
        .receive(chunks(&[b"0123", b"4567"], false), 7, "recording")
        .await;
    assert!(
        matches!(refused, Err(Error::TooLarge { limit: 7, .. })),
        "{refused:?}"
    );
    let broken = store
        .receive(chunks(&[b"0123"], true), 100, "recording")
        .await;
    assert!(broken.unwrap_err().to_string().contains("broke off"));
    assert!(!store.exists(A, SessionObject::Recording));
    let staged = store
        .receive(chunks(&[b"0123", b"4567"], false), 8, "recording")
        .await
        .unwrap();
    assert_eq!(staged.bytes, 8);
    store.publish(staged, A, SessionObject::Recording).unwrap();
    assert_eq!(
        store.get(A, SessionObject::Recording).unwrap().unwrap(),
        b"01234567"
    );
    let same = store
        .receive(chunks(&[b"01234567"], false), 8, "recording")
        .await
        .unwrap();
    assert!(
        store
            .same_content(&same, A, SessionObject::Recording)
            .unwrap()
    );
    let other = store
        .receive(chunks(&[b"01234568"], false), 8, "recording")
        .await
        .unwrap();
    assert!(
        !store
            .same_content(&other, A, SessionObject::Recording)
            .unwrap()
    );
    let bytes = store
        .receive_bytes(chunks(&[b"ab", b"cd"], false), 4, "trajectory")
        .await
        .unwrap();
    assert_eq!(bytes, b"abcd");
    let room = store.reserve(Some(A), Some(4)).unwrap();
    let over = store
        .receive_bytes_into(chunks(&[b"ab", b"cde"], false), 4, "trajectory", room)
        .await;
    assert!(matches!(over, Err(Error::TooLarge { .. })), "{over:?}");
}

async fn resumable_parts_keep_exactly_what_arrived(store: &dyn BlobStore) {
    let part = SessionObject::RecordingPart;
    // Appends `parts` (breaking off after them when `broken`) at `offset` of a 12-byte upload.
    let append = async |parts: &[&'static [u8]], broken: bool, offset: u64| {
        let room = store.reserve(Some(B), None).unwrap();
        let body = chunks(parts, broken);
        store
            .append_to(body, B, part, offset, 12, "recording", room)
            .await
    };
    // A body that breaks off keeps what arrived.
    let first = append(&[b"abc", b"def"], true, 0).await.unwrap();
    assert_eq!(first.len, 6);
    assert!(first.broken.is_some());
    assert_eq!(store.len(B, part).unwrap(), Some(6));
    // Resuming from another offset is refused; nothing changes.
    assert!(append(&[b"xyz"], false, 3).await.is_err());
    // A body longer than its range is refused and cut back to where it started.
    assert!(append(&[b"ghijklmn"], false, 6).await.is_err());
    assert_eq!(store.len(B, part).unwrap(), Some(6));
    let rest = append(&[b"ghi", b"jkl"], false, 6).await.unwrap();
    assert_eq!((rest.len, rest.broken.is_none()), (12, true));
    // The kept upload reads back in order, whatever parts it is kept as.
    assert_eq!(store.peek(B, part, 8).unwrap().unwrap(), b"abcdefgh");
    assert_eq!(
        read_all(store.open(B, part).unwrap().unwrap()),
        b"abcdefghijkl"
    );
    assert_eq!(store.get(B, part).unwrap().unwrap(), b"abcdefghijkl");
    let staged = store.staged_part(B, 12);
    store.publish(staged, B, SessionObject::Recording).unwrap();
    assert_eq!(
        store.get(B, SessionObject::Recording).unwrap().unwrap(),
        b"abcdefghijkl"
    );
    assert_eq!(
        store.peek(B, SessionObject::Recording, 3).unwrap().unwrap(),
        b"abc"
    );
    assert!(!store.exists(B, part), "the part became the recording");
    // A kept prefix published whole (`sitar migrate`) replaces what was kept.
    append(&[b"old"], true, 0).await.unwrap();
    let staged = store
        .receive(chunks(&[b"abcd", b"efg"], false), 100, "recording")
        .await
        .unwrap();
    store.publish(staged, B, part).unwrap();
    assert_eq!(store.get(B, part).unwrap().unwrap(), b"abcdefg");
    assert_eq!(store.len(B, part).unwrap(), Some(7));
    store.remove(B, part).unwrap();
}

/// A body from byte 0 that carries a whole recording of declared size (a plain `PUT`):
/// nothing of it is visible until it is published; broken off, its prefix is kept for a
/// resume; staged and dropped unpublished, it leaves the stored recording as it was.
async fn a_recording_of_declared_size_is_published_whole(store: &dyn BlobStore) {
    let part = SessionObject::RecordingPart;
    store.create_session(C).unwrap();
    store
        .put(C, SessionObject::RecordingPartTotal, b"9")
        .unwrap();
    let append = async |parts: &[&'static [u8]], broken: bool| {
        let room = store.reserve(Some(C), Some(9)).unwrap();
        store
            .append_to(
                chunks(parts, broken),
                C,
                part,
                0,
                1 << 20,
                "recording",
                room,
            )
            .await
            .unwrap()
    };
    let cut = append(&[b"abc", b"de"], true).await;
    assert_eq!((cut.len, cut.broken.is_some()), (5, true));
    assert_eq!(store.len(C, part).unwrap(), Some(5), "kept for a resume");
    assert!(!store.exists(C, SessionObject::Recording));
    store.remove(C, part).unwrap();
    let whole = append(&[b"abcd", b"efghi"], false).await;
    assert_eq!((whole.len, whole.broken.is_none()), (9, true));
    assert!(
        !store.exists(C, SessionObject::Recording),
        "visible before it was published"
    );
    let staged = store.staged_part(C, 9);
    assert_eq!(std::fs::read(&staged.path).unwrap(), b"abcdefghi");
    store.publish(staged, C, SessionObject::Recording).unwrap();
    store.remove(C, part).unwrap();
    assert_eq!(
        store.get(C, SessionObject::Recording).unwrap().unwrap(),
        b"abcdefghi"
    );
    // Another whole upload, staged and dropped (its check refused it): nothing changes.
    append(&[b"zzzzzzzzz"], false).await;
    drop(store.staged_part(C, 9));
    store.remove(C, part).unwrap();
    assert_eq!(
        store.get(C, SessionObject::Recording).unwrap().unwrap(),
        b"abcdefghi"
    );
    assert!(!store.exists(C, part));
    store.remove(C, SessionObject::RecordingPartTotal).unwrap();
}

fn deleted_sessions_are_removed_whole_and_again(store: &dyn BlobStore) {
    store.put(B, SessionObject::Trial(0), b"trial").unwrap();
    store.put(B, SessionObject::Trial(1), b"trial").unwrap();
    store.remove_session(B).unwrap();
    assert!(!store.exists(B, SessionObject::Trial(0)));
    assert!(!store.exists(B, SessionObject::Trial(1)));
    assert!(!store.exists(B, SessionObject::Recording));
    assert_eq!(store.get(B, SessionObject::Trial(0)).unwrap(), None);
    // Removing what is gone is success (a repeated delete, two instances' sweeps).
    store.remove_session(B).unwrap();
    store.remove_session(B).unwrap();
    // The other session is untouched.
    assert!(store.exists(A, SessionObject::Recording));
}

fn scenes_are_kept_whole_with_their_tag(store: &dyn BlobStore) {
    assert!(store.kept_scene(A).is_none());
    let failed = store.keep_scene(A, "sim", &mut |_| false);
    assert!(!failed);
    assert!(store.kept_scene(A).is_none(), "a failed save keeps nothing");
    let kept = store.keep_scene(A, "trial", &mut |dir| {
        std::fs::create_dir_all(dir).is_ok() && std::fs::write(dir.join("plan.csv"), "x").is_ok()
    });
    assert!(kept);
    let (dir, tag) = store.kept_scene(A).unwrap();
    assert_eq!(tag, "trial");
    assert!(dir.join("plan.csv").is_file());
    assert_eq!(dir, store.scene_folder(A));
    assert_ne!(store.playback_folder(A), store.playback_folder(B));
    store.discard_scene(A);
    assert!(store.kept_scene(A).is_none());
}

fn venues_hold_members_and_sessions_of_one_convention(store: &dyn MetadataStore) {
    use crate::model::NewVenue;
    use sitar_core::Convention;
    let (owner, member, stranger) = ("venue-owner", "venue-member", "venue-stranger");
    for (name, token) in [
        (owner, "sitar_vownerAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA"),
        (member, "sitar_vmemberAAAAAAAAAAAAAAAAAAAAAAAAAAAAA"),
        (stranger, "sitar_vstrangerAAAAAAAAAAAAAAAAAAAAAAAAAAA"),
    ] {
        store.insert_token(name, Role::App, token).unwrap();
    }
    let id_of = |token: &str| store.caller(token).unwrap().unwrap().owner().unwrap();
    let owner_id = id_of("sitar_vownerAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA");
    let member_id = id_of("sitar_vmemberAAAAAAAAAAAAAAAAAAAAAAAAAAAAA");
    let stranger_id = id_of("sitar_vstrangerAAAAAAAAAAAAAAAAAAAAAAAAAAA");
    let venue = "v2000000000000001";
    let new = NewVenue {
        name: "Lobby",
        anchor: "poster-1",
        cell_m: 0.5,
        owner: Some(owner_id),
    };
    store.insert_venue(venue, &new).unwrap();
    store
        .insert_venue(
            "v2000000000000002",
            &NewVenue {
                owner: Some(stranger_id),
                ..new.clone()
            },
        )
        .unwrap();
    let row = store.venue(venue).unwrap().unwrap();
    assert_eq!(
        (
            row.name.as_str(),
            row.anchor.as_str(),
            row.cell_m,
            row.owner
        ),
        ("Lobby", "poster-1", 0.5, Some(owner_id))
    );
    assert!(store.venue("v2000000000000009").unwrap().is_none());
    // Membership by token name; an unknown name changes nothing.
    assert!(store.add_member(venue, member).unwrap());
    assert!(store.add_member(venue, member).unwrap(), "again: no change");
    assert!(!store.add_member(venue, "nobody").unwrap());
    assert_eq!(store.members(venue).unwrap(), [member]);
    assert!(store.is_member(venue, member_id).unwrap());
    assert!(!store.is_member(venue, stranger_id).unwrap());
    let ids = |viewer| -> Vec<String> {
        store
            .venues_for(viewer, 10)
            .unwrap()
            .into_iter()
            .map(|v| v.id)
            .collect()
    };
    assert_eq!(ids(Some(owner_id)), [venue]);
    assert_eq!(ids(Some(member_id)), [venue]);
    assert_eq!(ids(Some(stranger_id)), ["v2000000000000002"]);
    assert_eq!(ids(None), ["v2000000000000002", venue], "all, newest first");
    assert_eq!(store.venues_for(None, 1).unwrap().len(), 1);
    // Sessions join with one convention; another is refused naming both, and not stored.
    let joining = |id: &str, owner, convention| {
        let new = NewSession {
            venue: Some(venue),
            convention,
            ..new_session(None, PlaybackKind::Upload, Some(owner))
        };
        store.insert_session(id, &new)
    };
    joining("s2000000000000001", owner_id, Convention::Arcore).unwrap();
    joining("s2000000000000002", member_id, Convention::Arcore).unwrap();
    let refused = joining("s2000000000000003", member_id, Convention::Unity).unwrap_err();
    assert_eq!(refused.status_and_code().0.as_u16(), 409, "{refused}");
    let message = refused.to_string();
    assert!(
        message.contains("arcore") && message.contains("unity"),
        "{message}"
    );
    assert!(store.session("s2000000000000003").unwrap().is_none());
    let row = store.session("s2000000000000002").unwrap().unwrap();
    assert_eq!(
        (row.venue.as_deref(), row.convention),
        (Some(venue), Convention::Arcore)
    );
    let in_venue: Vec<String> = store
        .venue_sessions(venue)
        .unwrap()
        .into_iter()
        .map(|s| s.id)
        .collect();
    assert_eq!(in_venue, ["s2000000000000001", "s2000000000000002"]);
    // A deleted session leaves its venue.
    assert!(store.delete_session("s2000000000000002", KEEP).unwrap());
    assert_eq!(store.venue_sessions(venue).unwrap().len(), 1);
    // Joining a venue that does not exist is refused naming the key.
    let gone = NewSession {
        venue: Some("v2000000000000009"),
        ..new_session(None, PlaybackKind::Upload, Some(owner_id))
    };
    let e = store
        .insert_session("s2000000000000004", &gone)
        .unwrap_err();
    assert!(e.to_string().contains("venue"), "{e}");
    // Ending a membership; an unknown token name is told apart.
    assert_eq!(store.remove_member(venue, member).unwrap(), Some(true));
    assert_eq!(store.remove_member(venue, member).unwrap(), Some(false));
    assert_eq!(store.remove_member(venue, "nobody").unwrap(), None);
    assert!(ids(Some(member_id)).is_empty());
    // Deleting a venue keeps its sessions, in no venue.
    store.add_member(venue, member).unwrap();
    assert!(store.delete_venue(venue).unwrap());
    assert!(!store.delete_venue(venue).unwrap());
    assert!(store.venue(venue).unwrap().is_none());
    assert!(!store.is_member(venue, member_id).unwrap());
    let kept = store.session("s2000000000000001").unwrap().unwrap();
    assert_eq!((kept.venue, kept.convention), (None, Convention::Arcore));
}

/// A venue session's kept map contribution: kept only at the generation read before its
/// files, forgotten (generation raised) on request and when the session becomes `done`,
/// removed with the session and with its venue; never kept for a session in no venue.
fn venue_contributions_are_kept_per_generation(store: &dyn MetadataStore) {
    use crate::model::NewVenue;
    let venue = "v3000000000000001";
    let new = NewVenue {
        name: "Atrium",
        anchor: "poster-3",
        cell_m: 0.25,
        owner: None,
    };
    store.insert_venue(venue, &new).unwrap();
    let (a, b, outside) = (
        "s3000000000000001",
        "s3000000000000002",
        "s3000000000000003",
    );
    for id in [a, b] {
        let joining = NewSession {
            venue: Some(venue),
            ..new_session(None, PlaybackKind::Upload, None)
        };
        store.insert_session(id, &joining).unwrap();
    }
    store
        .insert_session(outside, &new_session(None, PlaybackKind::Upload, None))
        .unwrap();
    let kept = |session: &str| {
        let rows = store.kept_contributions(venue).unwrap();
        rows.into_iter()
            .find(|k| k.session == session)
            .map(|k| (k.generation, k.body))
    };
    assert_eq!(store.kept_contributions(venue).unwrap().len(), 2);
    assert_eq!(kept(a), Some((0, None)), "nothing kept yet");
    assert!(store.keep_contribution(a, 0, b"first").unwrap());
    assert_eq!(kept(a), Some((0, Some(b"first".to_vec()))));
    assert!(
        store.keep_contribution(a, 0, b"again").unwrap(),
        "the same generation"
    );
    assert_eq!(kept(a), Some((0, Some(b"again".to_vec()))));
    // A session in no venue keeps nothing, and forgetting it is no error.
    assert!(!store.keep_contribution(outside, 0, b"x").unwrap());
    store.forget_contribution(outside).unwrap();
    assert!(
        store
            .kept_contributions("v3000000000000009")
            .unwrap()
            .is_empty()
    );
    // Forgotten: the body goes, the generation rises, a body computed before is refused.
    store.forget_contribution(a).unwrap();
    assert_eq!(kept(a), Some((1, None)));
    assert!(!store.keep_contribution(a, 0, b"stale").unwrap());
    assert_eq!(kept(a), Some((1, None)));
    assert!(store.keep_contribution(a, 1, b"fresh").unwrap());
    assert_eq!(kept(a), Some((1, Some(b"fresh".to_vec()))));
    // Forgetting one never kept; and a computation racing it (read generation 0) is refused.
    store.forget_contribution(b).unwrap();
    assert!(!store.keep_contribution(b, 0, b"raced").unwrap());
    assert!(store.keep_contribution(b, 1, b"b1").unwrap());
    // Becoming done forgets it in the transition's own transaction; other steps do not.
    store
        .transition(b, Step::StartEstimating, StepRecord::Nothing)
        .unwrap();
    assert_eq!(kept(b), Some((1, Some(b"b1".to_vec()))));
    store
        .transition(b, Step::Finish, StepRecord::Nothing)
        .unwrap();
    assert_eq!(kept(b), Some((2, None)));
    assert!(store.keep_contribution(b, 2, b"b2").unwrap());
    // Deleting a session removes its contribution; deleting the venue removes the rest.
    assert!(store.delete_session(a, KEEP).unwrap());
    assert_eq!(kept(a), None);
    assert_eq!(store.kept_contributions(venue).unwrap().len(), 1);
    assert!(store.delete_venue(venue).unwrap());
    assert!(store.kept_contributions(venue).unwrap().is_empty());
    assert!(
        !store.keep_contribution(b, 2, b"gone").unwrap(),
        "in no venue now"
    );
    store.forget_contribution(b).unwrap();
}

/// Several instances on one store: one player per session in flight, adoption of a dead
/// instance's sessions by exactly one other, stop requests reaching the player, and each
/// instance's restart interrupting only its own and dead instances' jobs.
fn instances_own_adopt_and_stop_sessions(store: &dyn MetadataStore) {
    use crate::storage::instances::StopRequest;
    let now = crate::storage::now_ms();
    let alive_since = now - 30_000;
    let (a, b, c) = ("instance-a", "instance-b", "instance-c");
    store.heartbeat(a, now).unwrap();
    store.heartbeat(b, now).unwrap();
    let id = "s1000000000000060";
    store
        .insert_session(id, &new_session(None, PlaybackKind::Sim, None))
        .unwrap();
    // Not in flight yet: nobody can claim it.
    assert!(!store.claim_session(id, a, alive_since).unwrap());
    store
        .transition(id, Step::AcceptRecording, StepRecord::RecordingBytes(9))
        .unwrap();
    // Sessions the suite left in flight may be listed too: only this one is looked at.
    let unplayed = |alive: i64| -> Vec<Option<String>> {
        let rows = store.unplayed_sessions(alive).unwrap();
        rows.into_iter()
            .filter(|r| r.0 == id)
            .map(|r| r.1)
            .collect()
    };
    assert_eq!(unplayed(alive_since), [None]);
    assert!(store.claim_session(id, a, alive_since).unwrap());
    // Again by its player: still its own; by another while the player lives: refused.
    assert!(store.claim_session(id, a, alive_since).unwrap());
    assert!(!store.claim_session(id, b, alive_since).unwrap());
    assert_eq!(store.session_player(id).unwrap().as_deref(), Some(a));
    assert!(unplayed(alive_since).is_empty());
    store
        .transition(id, Step::StartPlaying, StepRecord::Nothing)
        .unwrap();
    let job = store.start_job(id, "playback", a).unwrap();
    let _ = job;

    // A publishes its progress for the others' status answers; B, not the player, cannot.
    assert_eq!(store.published_progress(id).unwrap(), None);
    store
        .publish_progress(id, a, Some(r#"{"queue_position":2}"#))
        .unwrap();
    store
        .publish_progress(id, b, Some(r#"{"queue_position":9}"#))
        .unwrap();
    assert_eq!(
        store.published_progress(id).unwrap(),
        Some((a.to_string(), r#"{"queue_position":2}"#.to_string()))
    );

    // An estimate, a cancel and then a delete sent through B reach A; the stronger request
    // stays (delete, cancel, estimate).
    assert!(store.stop_requests(a).unwrap().is_empty());
    store.request_stop(id, StopRequest::Estimate).unwrap();
    assert_eq!(
        store.stop_requests(a).unwrap(),
        [(id.to_string(), StopRequest::Estimate)]
    );
    store.request_stop(id, StopRequest::Cancel).unwrap();
    store.request_stop(id, StopRequest::Estimate).unwrap();
    assert_eq!(
        store.stop_requests(a).unwrap(),
        [(id.to_string(), StopRequest::Cancel)]
    );
    assert!(store.stop_requests(b).unwrap().is_empty());
    store.request_stop(id, StopRequest::Delete).unwrap();
    store.request_stop(id, StopRequest::Cancel).unwrap();
    assert_eq!(
        store.stop_requests(a).unwrap(),
        [(id.to_string(), StopRequest::Delete)]
    );

    // A falls silent past the bound while B lives on: the session is A's no more.
    let later = now + 60_000;
    let alive_later = later - 30_000;
    store.heartbeat(b, later).unwrap();
    store.heartbeat(c, later).unwrap();
    assert!(!store.is_alive(a, alive_later).unwrap());
    assert!(store.is_alive(b, alive_later).unwrap());
    // An earlier heartbeat never moves one back.
    store.heartbeat(b, now).unwrap();
    assert!(store.is_alive(b, alive_later).unwrap());
    assert_eq!(unplayed(alive_later), [Some(a.to_string())]);
    // B and C adopt it at once: exactly one wins.
    let (by_b, by_c) = std::thread::scope(|scope| {
        let b_claims = scope.spawn(|| store.claim_session(id, b, alive_later).unwrap());
        let c_claims = scope.spawn(|| store.claim_session(id, c, alive_later).unwrap());
        (b_claims.join().unwrap(), c_claims.join().unwrap())
    });
    assert!(by_b ^ by_c, "B adopted: {by_b}, C adopted: {by_c}");
    let (adopter, other) = if by_b { (b, c) } else { (c, b) };
    assert_eq!(store.session_player(id).unwrap().as_deref(), Some(adopter));
    assert!(!store.claim_session(id, other, alive_later).unwrap());
    // What A published went with the adoption; the adopter publishes its own, and A, back
    // late, cannot overwrite it.
    assert_eq!(store.published_progress(id).unwrap(), None);
    store.publish_progress(id, adopter, Some("{}")).unwrap();
    store
        .publish_progress(id, a, Some(r#"{"queue_position":1}"#))
        .unwrap();
    assert_eq!(
        store.published_progress(id).unwrap(),
        Some((adopter.to_string(), "{}".to_string()))
    );
    // The request made while A played is the adopter's to carry out now.
    assert_eq!(
        store.stop_requests(adopter).unwrap(),
        [(id.to_string(), StopRequest::Delete)]
    );
    // The adopter interrupts the dead instance's running job, never a live one's.
    let live_job = store.start_job(id, "estimate", adopter).unwrap();
    assert_eq!(store.interrupt_jobs(None, alive_later).unwrap(), 1);
    let states: Vec<String> = store
        .jobs_of(id)
        .unwrap()
        .into_iter()
        .map(|j| j.1)
        .collect();
    assert_eq!(states, ["interrupted", "running"]);
    store.finish_job(live_job, JobEnd::Done, None).unwrap();
    // A, back, claims nothing the adopter plays.
    store.heartbeat(a, later).unwrap();
    assert!(!store.claim_session(id, a, alive_later).unwrap());

    // Released by someone else than the player: nothing changes; by the player: nobody
    // plays it and its stop request is gone.
    store.release_session(id, other).unwrap();
    assert_eq!(store.session_player(id).unwrap().as_deref(), Some(adopter));
    store.release_session(id, adopter).unwrap();
    assert_eq!(store.session_player(id).unwrap(), None);
    assert!(store.stop_requests(adopter).unwrap().is_empty());
    assert_eq!(store.published_progress(id).unwrap(), None);
    // Finished, it is in flight no more: nobody claims it, no adopter sees it.
    store
        .transition(id, Step::Fail, StepRecord::Error("test"))
        .unwrap();
    assert!(!store.claim_session(id, a, alive_later).unwrap());
    assert!(unplayed(alive_later).is_empty());
    // An upload session is never played by an instance; its final estimate runs on one,
    // claimed as a playback is (and adopted from a dead one).
    let upload = "s1000000000000061";
    store
        .insert_session(upload, &new_session(None, PlaybackKind::Upload, None))
        .unwrap();
    store
        .transition(upload, Step::AcceptRecording, StepRecord::RecordingBytes(9))
        .unwrap();
    assert!(!store.claim_session(upload, b, alive_later).unwrap());
    store
        .transition(upload, Step::StartEstimating, StepRecord::Nothing)
        .unwrap();
    let unplayed_upload = |alive: i64| -> Vec<Option<String>> {
        let rows = store.unplayed_sessions(alive).unwrap();
        rows.into_iter()
            .filter(|r| r.0 == upload)
            .map(|r| r.1)
            .collect()
    };
    assert_eq!(unplayed_upload(alive_later), [None]);
    assert!(store.claim_session(upload, b, alive_later).unwrap());
    assert!(!store.claim_session(upload, c, alive_later).unwrap());
    assert!(unplayed_upload(alive_later).is_empty());
    assert!(store.delete_session(upload, KEEP).unwrap() && store.delete_session(id, KEEP).unwrap());
}
