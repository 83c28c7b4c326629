//! The session configuration (JSON, every key optional).

use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::{Convention, Error, ErrorUnit, PoseRelation, ResultWindow, Thresholds};

/// Which value of a result window colours it (its class) and places markers: the config key
/// `classify_by`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClassifyBy {
    /// The window's error (`"estimate"`, the default): the calibrated value in calibrated
    /// results, else the statistic of the spread.
    #[default]
    Estimate,
    /// The window's upper bound (`"upper"`) where the results give one, else its error: the
    /// cautious choice, which warns wherever the error may be high.
    Upper,
}

impl ClassifyBy {
    /// Every choice, in the order error messages list them.
    pub const ALL: [ClassifyBy; 2] = [ClassifyBy::Estimate, ClassifyBy::Upper];

    /// `"estimate"` or `"upper"`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Estimate => "estimate",
            Self::Upper => "upper",
        }
    }

    /// The inverse of [`ClassifyBy::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }

    /// The value of `window` that classifies it and places markers: its error, or with
    /// [`ClassifyBy::Upper`] its interval's upper bound when it has one.
    pub fn value(&self, window: &ResultWindow) -> f64 {
        match (self, window.interval) {
            (Self::Upper, Some(interval)) => interval.upper,
            _ => window.error,
        }
    }
}

impl std::fmt::Display for ClassifyBy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Settings of one session. Parse with [`SessionConfig::from_json`]; see the field docs for
/// the defaults (those of ARCHITECTURE.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SessionConfig {
    /// Convention of poses in and out (`"unity"`, default, or `"arcore"`).
    pub convention: Convention,
    /// Base URL of the SiTAR backend, if any (default none).
    pub server_url: Option<String>,
    /// Frames per sub-trajectory (default 10); even, ≥ 2. The pose is logged every half of it.
    pub subtrajectory_frames: u32,
    /// Markers are never placed within this distance of each other (default 0.5 m).
    pub dedup_radius_m: f64,
    /// Most markers to place (default 3).
    pub max_regions: usize,
    /// Which error the results measure (default `"trans_part"`, metres; or `"angle_deg"`):
    /// results of another relation are refused, and classes and markers use the thresholds
    /// of its unit.
    pub pose_relation: PoseRelation,
    /// Error thresholds searched in order for markers (default `[0.10, 0.05, 0.02, 0.01]` m).
    pub thresholds_m: Vec<f64>,
    /// Errors at or above this are class high (default 0.10 m).
    pub high_threshold_m: f64,
    /// Errors at or above this (and below high) are class medium (default 0.05 m).
    pub medium_threshold_m: f64,
    /// Marker thresholds for `angle_deg` results (default `[4, 2, 0.8, 0.4]` degrees: the
    /// metric list scaled by the ratio of the class boundaries, 40° per metre).
    pub thresholds_deg: Vec<f64>,
    /// `angle_deg` errors at or above this are class high (default 4°,
    /// [`Thresholds::DEFAULT_DEG`]).
    pub high_threshold_deg: f64,
    /// `angle_deg` errors at or above this (and below high) are class medium (default 2°).
    pub medium_threshold_deg: f64,
    /// A camera frustum is drawn at the first midpoint after every this much path (default 0.5 m).
    pub frustum_spacing_m: f64,
    /// Mean error at or above which results "may be unreliable" (default 0.20 m).
    pub unreliable_mean_error_m: f64,
    /// The same for `angle_deg` results (default 8°: 0.20 m at 40° per metre).
    pub unreliable_mean_error_deg: f64,
    /// Folder where the app keeps session folders, if any (default none).
    pub data_dir: Option<PathBuf>,
    /// Whether the app gives the camera image at midpoints (`Session::image`; default true).
    /// `false` makes the image call a no-op: no properties, no thumbnails.
    #[serde(default = "default_images")]
    pub images: bool,
    /// Longest side of the midpoint thumbnails in pixels (default 160; 8…1024).
    #[serde(default = "default_thumbnail_px")]
    pub thumbnail_px: u32,
    /// The venue the session's recording joins on upload (a venue id, `v` and 16 lowercase
    /// hex digits, as `POST /v1/venues` returns it; default none).
    #[serde(default)]
    pub venue: Option<String>,
    /// Which value of a result window gives its class (the colour of its sub-trajectory) and
    /// places markers (default `"estimate"`: its error; `"upper"`: its interval's upper bound
    /// where calibrated results give one, else its error). Errors reported (`error_at`,
    /// [`crate::Marker::error_m`]) stay the windows' errors either way.
    #[serde(default)]
    pub classify_by: ClassifyBy,
}

fn default_images() -> bool {
    true
}

fn default_thumbnail_px() -> u32 {
    160
}

impl Default for SessionConfig {
    fn default() -> Self {
        Self {
            convention: Convention::Unity,
            server_url: None,
            subtrajectory_frames: 10,
            dedup_radius_m: 0.5,
            max_regions: 3,
            pose_relation: PoseRelation::TransPart,
            thresholds_m: vec![0.10, 0.05, 0.02, 0.01],
            high_threshold_m: Thresholds::DEFAULT_M.high,
            medium_threshold_m: Thresholds::DEFAULT_M.medium,
            thresholds_deg: DEFAULT_MARKER_THRESHOLDS_DEG.to_vec(),
            high_threshold_deg: Thresholds::DEFAULT_DEG.high,
            medium_threshold_deg: Thresholds::DEFAULT_DEG.medium,
            frustum_spacing_m: 0.5,
            unreliable_mean_error_m: 0.20,
            unreliable_mean_error_deg: 0.20 * DEG_PER_M,
            data_dir: None,
            images: true,
            thumbnail_px: 160,
            venue: None,
            classify_by: ClassifyBy::Estimate,
        }
    }
}

/// Degrees per metre between the two class rules: [`Thresholds::DEFAULT_DEG`] over
/// [`Thresholds::DEFAULT_M`] (4° / 0.10 m, and 2° / 0.05 m). The degree defaults of the marker
/// search and of the unreliable mean are the metric ones at this ratio, so the phone behaves
/// the same for either relation (a rotation error θ moves a surface 1.5 m away by about
/// θ · 1.5 m, i.e. 38° per metre; see [`Thresholds::DEFAULT_DEG`]).
const DEG_PER_M: f64 = 40.0;

/// `[0.10, 0.05, 0.02, 0.01]` m at [`DEG_PER_M`].
const DEFAULT_MARKER_THRESHOLDS_DEG: [f64; 4] = [4.0, 2.0, 0.8, 0.4];

const KEYS: &[&str] = &[
    "convention",
    "server_url",
    "subtrajectory_frames",
    "pose_relation",
    "dedup_radius_m",
    "max_regions",
    "thresholds_m",
    "high_threshold_m",
    "medium_threshold_m",
    "thresholds_deg",
    "high_threshold_deg",
    "medium_threshold_deg",
    "frustum_spacing_m",
    "unreliable_mean_error_m",
    "unreliable_mean_error_deg",
    "data_dir",
    "images",
    "thumbnail_px",
    "venue",
    "classify_by",
];

fn config_err(key: &str, message: impl Into<String>) -> Error {
    Error::Config {
        key: key.to_owned(),
        message: message.into(),
    }
}

/// Deserialises one key's value, naming the key on failure.
fn field<T: serde::de::DeserializeOwned>(key: &str, value: Value) -> Result<T, Error> {
    serde_json::from_value(value).map_err(|e| config_err(key, e.to_string()))
}

/// The `classify_by` value: one of [`ClassifyBy::ALL`]'s names.
fn classify_by(value: Value) -> Result<ClassifyBy, Error> {
    let allowed = || {
        ClassifyBy::ALL
            .iter()
            .map(|c| format!("\"{c}\""))
            .collect::<Vec<_>>()
            .join(" or ")
    };
    match &value {
        Value::String(name) => ClassifyBy::from_name(name).ok_or_else(|| {
            config_err(
                "classify_by",
                format!("`{name}` is not allowed; use {}", allowed()),
            )
        }),
        other => Err(config_err(
            "classify_by",
            format!("expected {}, found {other}", allowed()),
        )),
    }
}

impl SessionConfig {
    /// Parses the config JSON. An empty text or `{}` gives the defaults; an unknown key, a
    /// wrong type or an invalid value is an [`Error::Config`] naming the key.
    pub fn from_json(text: &str) -> Result<Self, Error> {
        let mut config = SessionConfig::default();
        if text.trim().is_empty() {
            return Ok(config);
        }
        let value: Value =
            serde_json::from_str(text).map_err(|e| config_err("(document)", e.to_string()))?;
        let Value::Object(map) = value else {
            return Err(config_err("(document)", "expected a JSON object"));
        };
        for (key, value) in map {
            let k = key.as_str();
            match k {
                "convention" => config.convention = field(k, value)?,
                "server_url" => config.server_url = field(k, value)?,
                "subtrajectory_frames" => config.subtrajectory_frames = field(k, value)?,
                "pose_relation" => config.pose_relation = field(k, value)?,
                "dedup_radius_m" => config.dedup_radius_m = field(k, value)?,
                "max_regions" => config.max_regions = field(k, value)?,
                "thresholds_m" => config.thresholds_m = field(k, value)?,
                "high_threshold_m" => config.high_threshold_m = field(k, value)?,
                "medium_threshold_m" => config.medium_threshold_m = field(k, value)?,
                "thresholds_deg" => config.thresholds_deg = field(k, value)?,
                "high_threshold_deg" => config.high_threshold_deg = field(k, value)?,
                "medium_threshold_deg" => config.medium_threshold_deg = field(k, value)?,
                "frustum_spacing_m" => config.frustum_spacing_m = field(k, value)?,
                "unreliable_mean_error_m" => config.unreliable_mean_error_m = field(k, value)?,
                "unreliable_mean_error_deg" => config.unreliable_mean_error_deg = field(k, value)?,
                "data_dir" => config.data_dir = field(k, value)?,
                "images" => config.images = field(k, value)?,
                "thumbnail_px" => config.thumbnail_px = field(k, value)?,
                "venue" => config.venue = field(k, value)?,
                "classify_by" => config.classify_by = classify_by(value)?,
                _ => {
                    return Err(config_err(
                        k,
                        format!("unknown key; known keys are {}", KEYS.join(", ")),
                    ));
                }
            }
        }
        config.validate()?;
        Ok(config)
    }

    /// The class boundaries of the configured `pose_relation`'s unit.
    pub fn class_thresholds(&self) -> Thresholds {
        self.thresholds_for(self.pose_relation.unit())
    }

    /// The class boundaries for errors in `unit`: `medium_threshold_m`/`high_threshold_m`
    /// or `medium_threshold_deg`/`high_threshold_deg`.
    pub fn thresholds_for(&self, unit: ErrorUnit) -> Thresholds {
        match unit {
            ErrorUnit::Metres => Thresholds::new(self.medium_threshold_m, self.high_threshold_m),
            ErrorUnit::Degrees => {
                Thresholds::new(self.medium_threshold_deg, self.high_threshold_deg)
            }
        }
    }

    /// The marker search thresholds of the configured `pose_relation`'s unit
    /// (`thresholds_m` or `thresholds_deg`).
    pub fn marker_thresholds(&self) -> &[f64] {
        match self.pose_relation.unit() {
            ErrorUnit::Metres => &self.thresholds_m,
            ErrorUnit::Degrees => &self.thresholds_deg,
        }
    }

    /// The mean error from which results "may be unreliable", for errors in `unit`.
    pub fn unreliable_mean_error(&self, unit: ErrorUnit) -> f64 {
        match unit {
            ErrorUnit::Metres => self.unreliable_mean_error_m,
            ErrorUnit::Degrees => self.unreliable_mean_error_deg,
        }
    }

    /// The config as pretty JSON (every key, `null` for absent options); parses back equal.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Checks value ranges; the error names the offending key.
    pub fn validate(&self) -> Result<(), Error> {
        let n = self.subtrajectory_frames;
        if n < 2 || !n.is_multiple_of(2) {
            return Err(config_err(
                "subtrajectory_frames",
                format!("{n} is not an even number ≥ 2"),
            ));
        }
        let non_negative = |key: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(config_err(key, format!("{v} is not a finite number ≥ 0")))
            }
        };
        non_negative("dedup_radius_m", self.dedup_radius_m)?;
        non_negative("high_threshold_m", self.high_threshold_m)?;
        non_negative("medium_threshold_m", self.medium_threshold_m)?;
        non_negative("high_threshold_deg", self.high_threshold_deg)?;
        non_negative("medium_threshold_deg", self.medium_threshold_deg)?;
        non_negative("unreliable_mean_error_m", self.unreliable_mean_error_m)?;
        non_negative("unreliable_mean_error_deg", self.unreliable_mean_error_deg)?;
        if let Some(v) = &self.venue
            && !(v.len() == 17
                && v.starts_with('v')
                && v[1..]
                    .bytes()
                    .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b)))
        {
            return Err(config_err(
                "venue",
                format!("`{v}` is not a venue id (`v` and 16 lowercase hex digits)"),
            ));
        }
        if !(8..=1024).contains(&self.thumbnail_px) {
            return Err(config_err(
                "thumbnail_px",
                format!("{} is not between 8 and 1024", self.thumbnail_px),
            ));
        }
        if !(self.frustum_spacing_m.is_finite() && self.frustum_spacing_m > 0.0) {
            return Err(config_err(
                "frustum_spacing_m",
                format!("{} is not a finite number > 0", self.frustum_spacing_m),
            ));
        }
        for (key, list) in [
            ("thresholds_m", &self.thresholds_m),
            ("thresholds_deg", &self.thresholds_deg),
        ] {
            for (i, t) in list.iter().enumerate() {
                if !(t.is_finite() && *t >= 0.0) {
                    return Err(config_err(
                        key,
                        format!("element {i} ({t}) is not a finite number ≥ 0"),
                    ));
                }
            }
        }
        for (medium_key, medium, high_key, high) in [
            (
                "medium_threshold_m",
                self.medium_threshold_m,
                "high_threshold_m",
                self.high_threshold_m,
            ),
            (
                "medium_threshold_deg",
                self.medium_threshold_deg,
                "high_threshold_deg",
                self.high_threshold_deg,
            ),
        ] {
            if medium > high {
                return Err(config_err(
                    medium_key,
                    format!("{medium} is above {high_key} ({high})"),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key_of(err: Error) -> String {
        match err {
            Error::Config { key, .. } => key,
            other => panic!("expected a config error, got {other}"),
        }
    }

    #[test]
    fn venue_is_a_venue_id() {
        let c = SessionConfig::from_json(r#"{"venue":"v0123456789abcdef"}"#).unwrap();
        assert_eq!(c.venue.as_deref(), Some("v0123456789abcdef"));
        assert_eq!(SessionConfig::from_json(&c.to_json()).unwrap(), c);
        for bad in [r#""lobby""#, r#""v0123456789ABCDEF""#, r#""v0123""#, "3"] {
            let e = SessionConfig::from_json(&format!(r#"{{"venue":{bad}}}"#)).unwrap_err();
            assert_eq!(key_of(e), "venue");
        }
    }

    #[test]
    fn classify_by_is_estimate_or_upper() {
        assert_eq!(SessionConfig::default().classify_by, ClassifyBy::Estimate);
        for (text, want) in [
            (r#"{"classify_by":"estimate"}"#, ClassifyBy::Estimate),
            (r#"{"classify_by":"upper"}"#, ClassifyBy::Upper),
        ] {
            let c = SessionConfig::from_json(text).unwrap();
            assert_eq!(c.classify_by, want);
            assert_eq!(SessionConfig::from_json(&c.to_json()).unwrap(), c);
        }
        for bad in [r#""Upper""#, r#""lower""#, "1", "null", r#"["upper"]"#] {
            let e = SessionConfig::from_json(&format!(r#"{{"classify_by":{bad}}}"#)).unwrap_err();
            let message = e.to_string();
            assert_eq!(key_of(e), "classify_by");
            assert!(
                message.contains(r#""estimate" or "upper""#),
                "{bad}: {message}"
            );
        }
        // A config.json written before the key existed reads as the default.
        let mut old: serde_json::Value =
            serde_json::from_str(&SessionConfig::default().to_json()).unwrap();
        old.as_object_mut().unwrap().remove("classify_by");
        assert_eq!(
            SessionConfig::from_json(&old.to_string()).unwrap(),
            SessionConfig::default()
        );
        // The value it picks: the upper bound only where a window has one.
        let mut w = ResultWindow {
            start: 0,
            end: None,
            error: 0.04,
            pairs: None,
            raw: None,
            interval: None,
        };
        assert_eq!(ClassifyBy::Upper.value(&w), 0.04);
        w.interval = Some(crate::ErrorInterval {
            lower: 0.01,
            upper: 0.12,
        });
        assert_eq!(ClassifyBy::Upper.value(&w), 0.12);
        assert_eq!(ClassifyBy::Estimate.value(&w), 0.04);
    }

    #[test]
    fn empty_and_braces_give_defaults() {
        assert_eq!(
            SessionConfig::from_json("").unwrap(),
            SessionConfig::default()
        );
        assert_eq!(
            SessionConfig::from_json(" {} ").unwrap(),
            SessionConfig::default()
        );
        let d = SessionConfig::default();
        assert_eq!(d.subtrajectory_frames, 10);
        assert_eq!(d.thresholds_m, vec![0.10, 0.05, 0.02, 0.01]);
        assert_eq!(
            (d.dedup_radius_m, d.max_regions, d.frustum_spacing_m),
            (0.5, 3, 0.5)
        );
        assert_eq!(
            (
                d.high_threshold_m,
                d.medium_threshold_m,
                d.unreliable_mean_error_m
            ),
            (0.10, 0.05, 0.20)
        );
        assert_eq!(d.pose_relation, PoseRelation::TransPart);
        assert_eq!(d.thresholds_deg, vec![4.0, 2.0, 0.8, 0.4]);
        assert_eq!(
            (
                d.high_threshold_deg,
                d.medium_threshold_deg,
                d.unreliable_mean_error_deg
            ),
            (4.0, 2.0, 8.0)
        );
        assert_eq!(d.class_thresholds(), Thresholds::DEFAULT_M);
        assert_eq!(
            d.thresholds_for(ErrorUnit::Degrees),
            Thresholds::DEFAULT_DEG
        );
    }

    #[test]
    fn degree_defaults_are_the_metric_ones_at_the_class_ratio() {
        let d = SessionConfig::default();
        let ratio = Thresholds::DEFAULT_DEG.high / Thresholds::DEFAULT_M.high;
        assert_eq!(ratio, DEG_PER_M);
        assert_eq!(
            Thresholds::DEFAULT_DEG.medium / Thresholds::DEFAULT_M.medium,
            ratio
        );
        for (deg, m) in d.thresholds_deg.iter().zip(&d.thresholds_m) {
            assert!((deg - m * ratio).abs() < 1e-12, "{deg} vs {m}");
        }
        assert!((d.unreliable_mean_error_deg - d.unreliable_mean_error_m * ratio).abs() < 1e-12);
    }

    #[test]
    fn the_relation_chooses_thresholds() {
        let c = SessionConfig::from_json(
            r#"{"pose_relation":"angle_deg","thresholds_deg":[3,1],"medium_threshold_deg":1,
            "high_threshold_deg":3,"unreliable_mean_error_deg":5}"#,
        )
        .unwrap();
        assert_eq!(c.pose_relation, PoseRelation::AngleDeg);
        assert_eq!(c.class_thresholds(), Thresholds::new(1.0, 3.0));
        assert_eq!(c.marker_thresholds(), &[3.0, 1.0]);
        assert_eq!(c.unreliable_mean_error(ErrorUnit::Degrees), 5.0);
        assert_eq!(c.unreliable_mean_error(ErrorUnit::Metres), 0.20);
        assert_eq!(c.thresholds_for(ErrorUnit::Metres), Thresholds::DEFAULT_M);
        assert_eq!(SessionConfig::from_json(&c.to_json()).unwrap(), c);
        assert_eq!(
            SessionConfig::default().marker_thresholds(),
            &[0.10, 0.05, 0.02, 0.01]
        );
    }

    #[test]
    fn every_key_parses() {
        let c = SessionConfig::from_json(
            r#"{"convention":"arcore","server_url":"http://127.0.0.1:8000","subtrajectory_frames":20,
            "dedup_radius_m":1.0,"max_regions":5,"thresholds_m":[0.2,0.1],"high_threshold_m":0.2,
            "medium_threshold_m":0.1,"frustum_spacing_m":0.25,"unreliable_mean_error_m":0.3,"data_dir":"/tmp/x"}"#,
        )
        .unwrap();
        assert_eq!(c.convention, Convention::Arcore);
        assert_eq!(c.server_url.as_deref(), Some("http://127.0.0.1:8000"));
        assert_eq!(c.subtrajectory_frames, 20);
        assert_eq!(c.max_regions, 5);
        assert_eq!(c.thresholds_m, vec![0.2, 0.1]);
        assert_eq!(c.data_dir, Some(PathBuf::from("/tmp/x")));
        assert_eq!(SessionConfig::from_json(&c.to_json()).unwrap(), c);
    }

    #[test]
    fn errors_name_the_key() {
        assert_eq!(
            key_of(SessionConfig::from_json(r#"{"convention":"opengl"}"#).unwrap_err()),
            "convention"
        );
        assert_eq!(
            key_of(SessionConfig::from_json(r#"{"max_regions":"3"}"#).unwrap_err()),
            "max_regions"
        );
        assert_eq!(
            key_of(SessionConfig::from_json(r#"{"thresholds_m":[0.1,"x"]}"#).unwrap_err()),
            "thresholds_m"
        );
        assert_eq!(
            key_of(SessionConfig::from_json(r#"{"dedup_radius":0.5}"#).unwrap_err()),
            "dedup_radius"
        );
        assert_eq!(
            key_of(SessionConfig::from_json(r#"{"subtrajectory_frames":7}"#).unwrap_err()),
            "subtrajectory_frames"
        );
        assert_eq!(
            key_of(SessionConfig::from_json(r#"{"frustum_spacing_m":0}"#).unwrap_err()),
            "frustum_spacing_m"
        );
        assert_eq!(
            key_of(SessionConfig::from_json(r#"{"dedup_radius_m":null}"#).unwrap_err()),
            "dedup_radius_m"
        );
        for (text, key) in [
            (r#"{"pose_relation":"angle_rad"}"#, "pose_relation"),
            (r#"{"pose_relation":1}"#, "pose_relation"),
            (r#"{"thresholds_deg":[1,"x"]}"#, "thresholds_deg"),
            (r#"{"thresholds_deg":[-1]}"#, "thresholds_deg"),
            (r#"{"high_threshold_deg":"4"}"#, "high_threshold_deg"),
            (r#"{"medium_threshold_deg":5}"#, "medium_threshold_deg"),
            (
                r#"{"unreliable_mean_error_deg":-1}"#,
                "unreliable_mean_error_deg",
            ),
        ] {
            assert_eq!(
                key_of(SessionConfig::from_json(text).unwrap_err()),
                key,
                "{text}"
            );
        }
        let msg = SessionConfig::from_json(r#"{"max_regions":-1}"#)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("max_regions"), "{msg}");
        assert!(SessionConfig::from_json("[1]").is_err());
        assert!(SessionConfig::from_json("{").is_err());
    }
}
