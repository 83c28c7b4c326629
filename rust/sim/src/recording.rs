//! The recording a simulated phone uploads, and its byte format.

use std::sync::Arc;

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use sitar_estimator::{TimeUnit, Trajectory};

use crate::models::{DriftModel, RansacModel};
use crate::observations::Observations;
use crate::{Error, Room, View, Walk};

/// First bytes of every serialised recording.
pub const RECORDING_MAGIC: &[u8; 8] = b"SITARSIM";
/// The format version [`Recording::to_bytes`] writes and [`Recording::from_bytes`] reads.
pub const RECORDING_VERSION: u32 = 1;

/// What the simulated phone records: the room it walked through (the "camera images"), the
/// ground-truth walk and the seed of everything random. Playback ([`crate::play_trial`])
/// turns it into SLAM-like trials, as ARCore's playback turns an mp4 into trajectories.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    seed: u64,
    room: Room,
    walk: Walk,
    drift: DriftModel,
    views: Vec<View>,
    difficulty: Vec<f64>,
    reflectivity: Vec<f64>,
    ransac: Option<(RansacModel, Arc<Observations>)>,
}

/// Which tracker plays a recording's trials.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Tracker {
    /// The fast error model ([`DriftModel`]): drift whose size and spread follow the view's
    /// difficulty by construction.
    #[default]
    Model,
    /// The mechanistic RANSAC visual-inertial tracker ([`RansacModel`]): the spread arises
    /// from its random sampling.
    Ransac,
}

impl std::str::FromStr for Tracker {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        match s {
            "model" => Ok(Self::Model),
            "ransac" => Ok(Self::Ransac),
            other => Err(Error::InvalidArgument(format!(
                "unknown tracker {other:?} (model or ransac)"
            ))),
        }
    }
}

/// The JSON body after the header.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Body {
    seed: u64,
    fps: f64,
    room: Room,
    drift: DriftModel,
    /// Nanoseconds.
    stamps: Vec<i64>,
    /// `[x, y, z, qx, qy, qz, qw]` per frame.
    poses: Vec<[f64; 7]>,
    /// Present when the RANSAC tracker plays the trials.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    ransac: Option<RansacModel>,
}

/// Per-frame facts of a scene description.
#[derive(Serialize)]
struct SceneFrame<'a> {
    t_ns: i64,
    facing: Option<&'a str>,
    view_difficulty: f64,
    tracker_difficulty: f64,
    reflectivity: f64,
}

/// The scene description `sitar simulate` writes.
#[derive(Serialize)]
struct Scene<'a> {
    format: &'static str,
    version: u32,
    convention: &'static str,
    seed: u64,
    fps: f64,
    frames: usize,
    duration_s: f64,
    room: &'a Room,
    hard_surfaces: Vec<&'a str>,
    tracker: Tracker,
    drift: &'a DriftModel,
    #[serde(skip_serializing_if = "Option::is_none")]
    ransac: Option<&'a RansacModel>,
    per_frame: Vec<SceneFrame<'a>>,
}

fn invalid(field: impl Into<String>, message: impl Into<String>) -> Error {
    Error::InvalidRecording {
        field: field.into(),
        message: message.into(),
    }
}

impl Recording {
    /// A recording of `walk` through `room`; `seed` drives every trial's randomness.
    /// Uses the default [`DriftModel`].
    pub fn new(room: Room, walk: Walk, seed: u64) -> Self {
        let gt = &walk.ground_truth;
        let views: Vec<View> = gt
            .positions
            .iter()
            .zip(&gt.orientations)
            .map(|(p, q)| room.view(*p, *q))
            .collect();
        let mut rec = Self {
            seed,
            room,
            walk,
            drift: DriftModel::default(),
            views,
            difficulty: Vec::new(),
            reflectivity: Vec::new(),
            ransac: None,
        };
        rec.smooth();
        rec
    }

    /// The same recording played back by `tracker` with its default settings.
    pub fn with_tracker(self, tracker: Tracker) -> Self {
        match tracker {
            Tracker::Model => Self {
                ransac: None,
                ..self
            },
            Tracker::Ransac => {
                let model = self.ransac_model().copied().unwrap_or_default();
                self.with_ransac_model(model)
                    .expect("the default RANSAC model is valid")
            }
        }
    }

    /// The same recording played back by the RANSAC tracker with `model`: records the
    /// front end's observations once (landmarks, matches, IMU) for every trial to share.
    pub fn with_ransac_model(mut self, model: RansacModel) -> Result<Self, Error> {
        model.validate().map_err(|(field, message)| {
            Error::InvalidArgument(format!("ransac.{field}: {message}"))
        })?;
        let observations =
            Observations::record(&self.room, &self.walk.ground_truth, &model, self.seed);
        self.ransac = Some((model, Arc::new(observations)));
        Ok(self)
    }

    /// The tracker that plays the trials.
    pub fn tracker(&self) -> Tracker {
        if self.ransac.is_some() {
            Tracker::Ransac
        } else {
            Tracker::Model
        }
    }

    /// The RANSAC tracker's settings, when it plays the trials.
    pub fn ransac_model(&self) -> Option<&RansacModel> {
        self.ransac.as_ref().map(|(model, _)| model)
    }

    pub(crate) fn ransac_parts(&self) -> Option<(&RansacModel, &Observations)> {
        self.ransac.as_ref().map(|(m, o)| (m, o.as_ref()))
    }

    /// The demo room, a handheld walk of `seconds` at `fps`, all from `seed`.
    pub fn demo(seconds: f64, fps: f64, seed: u64) -> Result<Self, Error> {
        let room = Room::demo();
        let walk = Walk::handheld(&room, seconds, fps, seed)?;
        Ok(Self::new(room, walk, seed))
    }

    /// The same recording played back with another drift model.
    pub fn with_drift(mut self, drift: DriftModel) -> Result<Self, Error> {
        drift.validate().map_err(|(field, message)| {
            Error::InvalidArgument(format!("drift.{field}: {message}"))
        })?;
        self.drift = drift;
        self.smooth();
        Ok(self)
    }

    /// Exponentially smoothed difficulty and reflectivity, as the tracker experiences them.
    fn smooth(&mut self) {
        let stamps = &self.walk.ground_truth.stamps;
        let tau = self.drift.difficulty_time_constant_s;
        let (mut d, mut r) = match self.views.first() {
            Some(v) => (v.difficulty, v.reflectivity),
            None => (0.0, 0.0),
        };
        self.difficulty.clear();
        self.reflectivity.clear();
        for (i, view) in self.views.iter().enumerate() {
            if i > 0 {
                let dt = (stamps[i] - stamps[i - 1]) as f64 * 1e-9;
                let alpha = 1.0 - (-dt / tau).exp();
                d += alpha * (view.difficulty - d);
                r += alpha * (view.reflectivity - r);
            }
            self.difficulty.push(d);
            self.reflectivity.push(r);
        }
    }

    /// The seed of the trials.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The room.
    pub fn room(&self) -> &Room {
        &self.room
    }

    /// The ground-truth walk.
    pub fn walk(&self) -> &Walk {
        &self.walk
    }

    /// The drift model of playback.
    pub fn drift(&self) -> &DriftModel {
        &self.drift
    }

    /// What the camera saw at each frame.
    pub fn views(&self) -> &[View] {
        &self.views
    }

    /// Per-frame tracking difficulty, 0 … 1, smoothed over the drift model's time constant.
    pub fn difficulty(&self) -> &[f64] {
        &self.difficulty
    }

    /// Per-frame share of reflective surface in view, smoothed like [`Self::difficulty`].
    pub fn reflectivity(&self) -> &[f64] {
        &self.reflectivity
    }

    /// Number of camera frames.
    pub fn frames(&self) -> usize {
        self.walk.ground_truth.len()
    }

    /// Duration in seconds, `frames / fps` (an mp4 of 450 frames at 30 fps lasts 15 s).
    pub fn duration_s(&self) -> f64 {
        self.frames() as f64 / self.walk.fps
    }

    /// The upload format: [`RECORDING_MAGIC`], [`RECORDING_VERSION`] as u32 little-endian,
    /// then a JSON body (seed, fps, room, drift model, stamps, poses, and the RANSAC tracker's
    /// settings under `ransac` when it plays the trials).
    pub fn to_bytes(&self) -> Vec<u8> {
        let gt = &self.walk.ground_truth;
        let body = Body {
            seed: self.seed,
            fps: self.walk.fps,
            room: self.room.clone(),
            drift: self.drift,
            stamps: gt.stamps.clone(),
            poses: gt
                .positions
                .iter()
                .zip(&gt.orientations)
                .map(|(p, q)| [p.x, p.y, p.z, q.x, q.y, q.z, q.w])
                .collect(),
            ransac: self.ransac_model().copied(),
        };
        let mut bytes = Vec::with_capacity(12 + 160 * gt.len() + 4096);
        bytes.extend_from_slice(RECORDING_MAGIC);
        bytes.extend_from_slice(&RECORDING_VERSION.to_le_bytes());
        // Serialising plain numbers, strings and vectors cannot fail.
        serde_json::to_writer(&mut bytes, &body).expect("recording body serialises");
        bytes
    }

    /// Reads bytes written by [`Self::to_bytes`], checking the header and every field.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, Error> {
        if bytes.len() < 12 || &bytes[..8] != RECORDING_MAGIC {
            return Err(Error::NotARecording(format!(
                "missing the {:?} header ({} bytes given)",
                String::from_utf8_lossy(RECORDING_MAGIC),
                bytes.len()
            )));
        }
        let version = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
        if version != RECORDING_VERSION {
            return Err(Error::UnsupportedVersion {
                found: version,
                supported: RECORDING_VERSION,
            });
        }
        let body: Body = serde_json::from_slice(&bytes[12..])
            .map_err(|e| invalid("body", format!("bad JSON: {e}")))?;
        body.room.validate()?;
        body.drift
            .validate()
            .map_err(|(field, message)| invalid(format!("drift.{field}"), message))?;
        if !(body.fps.is_finite() && body.fps > 0.0 && body.fps <= 1000.0) {
            return Err(invalid(
                "fps",
                format!("must be in (0, 1000], got {}", body.fps),
            ));
        }
        if body.stamps.len() != body.poses.len() {
            return Err(invalid(
                "poses",
                format!(
                    "{} poses for {} stamps",
                    body.poses.len(),
                    body.stamps.len()
                ),
            ));
        }
        if body.stamps.len() < 2 {
            return Err(invalid("stamps", "a recording needs at least 2 frames"));
        }
        if let Some(i) = body.stamps.windows(2).position(|w| w[1] <= w[0]) {
            return Err(invalid(
                format!("stamps[{}]", i + 1),
                "timestamps must increase",
            ));
        }
        let mut positions = Vec::with_capacity(body.poses.len());
        let mut orientations = Vec::with_capacity(body.poses.len());
        for (i, p) in body.poses.iter().enumerate() {
            if p.iter().any(|v| !v.is_finite()) {
                return Err(invalid(format!("poses[{i}]"), "not finite"));
            }
            let q = DQuat::from_xyzw(p[3], p[4], p[5], p[6]);
            if (q.length() - 1.0).abs() > 1e-6 {
                return Err(invalid(
                    format!("poses[{i}]"),
                    "quaternion is not unit length",
                ));
            }
            positions.push(DVec3::new(p[0], p[1], p[2]));
            orientations.push(q);
        }
        let walk = Walk {
            fps: body.fps,
            ground_truth: Trajectory {
                stamps: body.stamps,
                positions,
                orientations,
                time_unit: TimeUnit::Nanoseconds,
            },
        };
        if let Some(model) = &body.ransac {
            model
                .validate()
                .map_err(|(field, message)| invalid(format!("ransac.{field}"), message))?;
        }
        let rec = Self::new(body.room, walk, body.seed)
            .with_drift(body.drift)
            .map_err(|e| invalid("drift", e.to_string()))?;
        match body.ransac {
            Some(model) => rec
                .with_ransac_model(model)
                .map_err(|e| invalid("ransac", e.to_string())),
            None => Ok(rec),
        }
    }

    /// A JSON description of the scene: room, hard surfaces, drift model and, per frame, the
    /// surface at the image centre and the tracking difficulty (the simulator's ground truth).
    pub fn scene_json(&self) -> String {
        let gt = &self.walk.ground_truth;
        let scene = Scene {
            format: "sitar-sim-scene",
            version: 1,
            convention: "arcore",
            seed: self.seed,
            fps: self.walk.fps,
            frames: self.frames(),
            duration_s: self.duration_s(),
            room: &self.room,
            hard_surfaces: self
                .room
                .hard_surfaces()
                .iter()
                .map(|s| s.name.as_str())
                .collect(),
            tracker: self.tracker(),
            drift: &self.drift,
            ransac: self.ransac_model(),
            per_frame: (0..self.frames())
                .map(|i| SceneFrame {
                    t_ns: gt.stamps[i],
                    facing: self.views[i].facing.as_deref(),
                    view_difficulty: self.views[i].difficulty,
                    tracker_difficulty: self.difficulty[i],
                    reflectivity: self.reflectivity[i],
                })
                .collect(),
        };
        serde_json::to_string_pretty(&scene).expect("scene serialises")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::play_trial;

    #[test]
    fn bytes_round_trip_exactly() {
        let rec = Recording::demo(15.0, 30.0, 11).unwrap();
        assert_eq!(rec.frames(), 450);
        assert!((rec.duration_s() - 15.0).abs() < 1e-12);
        let bytes = rec.to_bytes();
        assert_eq!(&bytes[..8], b"SITARSIM");
        let back = Recording::from_bytes(&bytes).unwrap();
        assert_eq!(back, rec);
        assert_eq!(play_trial(&back, 4), play_trial(&rec, 4));
    }

    #[test]
    fn from_bytes_rejects_bad_input_clearly() {
        let rec = Recording::demo(2.0, 30.0, 1).unwrap();
        let bytes = rec.to_bytes();
        let err = |b: &[u8]| Recording::from_bytes(b).unwrap_err().to_string();
        assert!(err(b"").contains("header"));
        assert!(err(b"\x00\x00\x00\x20ftypisom-an-mp4-file").contains("not a sitar-sim recording"));
        let mut v2 = bytes.clone();
        v2[8] = 2;
        assert_eq!(
            err(&v2),
            "unsupported sitar-sim recording version 2 (this build reads version 1)"
        );
        assert!(err(&bytes[..bytes.len() - 5]).contains("bad JSON"));
        let text = String::from_utf8(bytes[12..].to_vec()).unwrap();
        let with = |t: String| {
            let mut b = bytes[..12].to_vec();
            b.extend_from_slice(t.as_bytes());
            err(&b)
        };
        assert!(with(text.replace("\"fps\":30.0", "\"fps\":-1.0")).contains("fps"));
        assert!(
            with(text.replace("\"correlation\":0.8", "\"correlation\":7.0"))
                .contains("drift.correlation")
        );
        assert!(
            with(text.replace("\"seed\":1", "\"seed\":1,\"extra\":2")).contains("unknown field")
        );
        let swapped = text.replacen(
            "[1000000000000,1000033333333",
            "[1000033333333,1000000000000",
            1,
        );
        assert!(with(swapped).contains("stamps[1]: timestamps must increase"));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        /// Corrupted or truncated uploads are errors, never panics.
        #[test]
        fn corrupted_bytes_never_panic(
            keep in 0.0f64..1.5, flips in proptest::collection::vec((0.0f64..1.0, 0u8..=255), 0..4),
        ) {
            let bytes = Recording::demo(1.0, 30.0, 3).unwrap().to_bytes();
            let cut = ((keep * bytes.len() as f64) as usize).min(bytes.len());
            let mut bad = bytes[..cut].to_vec();
            for (at, value) in flips {
                let at = (at * bad.len() as f64) as usize;
                if let Some(b) = bad.get_mut(at) {
                    *b = value;
                }
            }
            if let Ok(rec) = Recording::from_bytes(&bad) {
                // Whatever parses is a valid recording that plays.
                proptest::prop_assert!(play_trial(&rec, 0).len() == rec.frames());
            }
        }
    }

    #[test]
    fn scene_json_names_the_hard_surfaces_and_the_facing_surface() {
        let rec = Recording::demo(15.0, 30.0, 2).unwrap();
        let scene: serde_json::Value = serde_json::from_str(&rec.scene_json()).unwrap();
        assert_eq!(
            scene["hard_surfaces"],
            serde_json::json!(["blank wall", "glass pane"])
        );
        assert_eq!(scene["per_frame"].as_array().unwrap().len(), 450);
        assert_eq!(scene["per_frame"][0]["t_ns"], 1_000_000_000_000i64);
        assert_eq!(scene["room"]["surfaces"].as_array().unwrap().len(), 9);
    }
}
