//! The names of every object the server keeps for a session, typed: each is built from a
//! server-made session id and server-checked numbers only, so no client-supplied text ever
//! names a stored object. [`SessionObject::relative_path`] is the embedded layout (the folder
//! `DATA/sessions/ID/`, unchanged from earlier versions).

/// One stored object of a session.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SessionObject {
    /// The uploaded recording (mp4, or a sitar-sim recording).
    Recording,
    /// A recording upload as it arrives; kept when it breaks off.
    RecordingPart,
    /// The `Idempotency-Key` of the upload the kept prefix belongs to.
    RecordingPartKey,
    /// The `Content-Range` total the first chunk of the kept prefix declared.
    RecordingPartTotal,
    /// One finished trial (TUM text), by storage index.
    Trial(u32),
    /// The legacy `POST /timestamps` upload.
    Timestamps,
    /// The latest published estimate as CSV (`start,error`).
    ResultsCsv,
    /// The latest published estimate as JSON.
    ResultsJson,
    /// One line per published estimate, for the report's history table.
    History,
    /// The phone's `evidence.csv`, validated and parsed once.
    Evidence,
    /// Start and end of each sub-trajectory (the phone's `subtrajectories.csv`).
    Spans,
    /// Sub-trajectory k's camera thumbnail (k a checked number).
    Thumbnail(usize),
    /// The phone's own log (`trajectory.txt`: start, midpoints, endpoints; TUM, integer ns),
    /// checked whole on arrival.
    PhoneTrajectory,
    /// The phone's anchor observations (`anchors.csv`), checked whole on arrival.
    Anchors,
    /// The phone's walk (`walk.txt`: the start pose and every frame's pose; TUM, integer
    /// ns), checked whole on arrival: the live run its estimates start from.
    Walk,
    /// The phone's whole sub-trajectory table (`subtrajectories.csv` in sitar-core's header),
    /// checked whole on arrival.
    Subtrajectories,
}

impl SessionObject {
    /// The object stored at `relative` inside a session's folder (the inverse of
    /// [`SessionObject::relative_path`]); `None` for anything else there (working folders,
    /// caches).
    #[cfg_attr(not(feature = "cluster"), allow(dead_code))] // the cluster stores use it
    pub(crate) fn from_relative_path(relative: &str) -> Option<SessionObject> {
        let number = |text: &str| -> Option<u32> {
            (!text.is_empty() && text.bytes().all(|b| b.is_ascii_digit()))
                .then(|| text.parse().ok())?
        };
        let object = match relative {
            "recording" => SessionObject::Recording,
            "recording.part" => SessionObject::RecordingPart,
            "recording.part.key" => SessionObject::RecordingPartKey,
            "recording.part.total" => SessionObject::RecordingPartTotal,
            "timestamps.txt" => SessionObject::Timestamps,
            "results.csv" => SessionObject::ResultsCsv,
            "results.json" => SessionObject::ResultsJson,
            "history.jsonl" => SessionObject::History,
            "evidence.json" => SessionObject::Evidence,
            "spans.json" => SessionObject::Spans,
            "phone_log/trajectory.txt" => SessionObject::PhoneTrajectory,
            "phone_log/anchors.csv" => SessionObject::Anchors,
            "phone_log/walk.txt" => SessionObject::Walk,
            "phone_log/subtrajectories.csv" => SessionObject::Subtrajectories,
            other => {
                if let Some(name) = other.strip_prefix("trials/trial_") {
                    SessionObject::Trial(number(name.strip_suffix(".txt")?)?)
                } else {
                    let k = other.strip_prefix("thumbnails/")?.strip_suffix(".jpg")?;
                    SessionObject::Thumbnail(number(k)? as usize)
                }
            }
        };
        // Only the spelling this version writes (`trial_7.txt` is not `trial_007.txt`).
        (object.relative_path() == relative).then_some(object)
    }

    /// Where the object lives inside the session's folder.
    pub(crate) fn relative_path(self) -> String {
        match self {
            SessionObject::Recording => "recording".into(),
            SessionObject::RecordingPart => "recording.part".into(),
            SessionObject::RecordingPartKey => "recording.part.key".into(),
            SessionObject::RecordingPartTotal => "recording.part.total".into(),
            SessionObject::Trial(index) => format!("trials/trial_{index:03}.txt"),
            SessionObject::Timestamps => "timestamps.txt".into(),
            SessionObject::ResultsCsv => "results.csv".into(),
            SessionObject::ResultsJson => "results.json".into(),
            SessionObject::History => "history.jsonl".into(),
            SessionObject::Evidence => "evidence.json".into(),
            SessionObject::Spans => "spans.json".into(),
            SessionObject::Thumbnail(k) => format!("thumbnails/{k}.jpg"),
            SessionObject::PhoneTrajectory => "phone_log/trajectory.txt".into(),
            SessionObject::Anchors => "phone_log/anchors.csv".into(),
            SessionObject::Walk => "phone_log/walk.txt".into(),
            SessionObject::Subtrajectories => "phone_log/subtrajectories.csv".into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_object_has_its_own_path_inside_the_folder() {
        let objects = [
            SessionObject::Recording,
            SessionObject::RecordingPart,
            SessionObject::RecordingPartKey,
            SessionObject::RecordingPartTotal,
            SessionObject::Trial(0),
            SessionObject::Trial(7),
            SessionObject::Timestamps,
            SessionObject::ResultsCsv,
            SessionObject::ResultsJson,
            SessionObject::History,
            SessionObject::Evidence,
            SessionObject::Spans,
            SessionObject::Thumbnail(0),
            SessionObject::Thumbnail(12),
            SessionObject::PhoneTrajectory,
            SessionObject::Anchors,
            SessionObject::Walk,
            SessionObject::Subtrajectories,
        ];
        for object in objects {
            let path = object.relative_path();
            assert_eq!(
                SessionObject::from_relative_path(&path),
                Some(object),
                "{path}"
            );
        }
        for other in [
            "trials/trial_7.txt",
            "trials/trial_.txt",
            "thumbnails/x.jpg",
            "thumbnails/+1.jpg",
            "phone/session.json",
            "adb-pull/trajectory_0.txt",
            "recording.tmp",
        ] {
            assert_eq!(SessionObject::from_relative_path(other), None, "{other}");
        }
        let paths: std::collections::BTreeSet<String> =
            objects.iter().map(|o| o.relative_path()).collect();
        assert_eq!(paths.len(), objects.len(), "{paths:?}");
        for path in &paths {
            assert!(!path.starts_with('/') && !path.contains(".."), "{path}");
        }
        // The layout earlier versions wrote, so an existing data directory keeps working.
        assert_eq!(
            SessionObject::Trial(7).relative_path(),
            "trials/trial_007.txt"
        );
        assert_eq!(
            SessionObject::Thumbnail(12).relative_path(),
            "thumbnails/12.jpg"
        );
    }
}
