//! The calibrations a server applies (`sitar serve --calibration NAME=FILE`): each read and
//! checked once at start, kept by name, at most [`MAX_CALIBRATIONS`]. A session names one
//! (`"calibration"` in `POST /v1/sessions`); every estimate published for it is then
//! calibrated (`live_sessions.rs`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use sitar_estimator::Calibration;

use crate::error::Error;

/// The most calibrations one server keeps (each is a few hundred bytes of model; the bound
/// keeps the error message that lists them, and the start, short).
pub const MAX_CALIBRATIONS: usize = 64;

/// The longest calibration name.
pub const MAX_NAME_LEN: usize = 64;

/// Whether `name` is a calibration name: 1 to 64 of `A-Z a-z 0-9 _ . -`.
pub fn is_calibration_name(name: &str) -> bool {
    (1..=MAX_NAME_LEN).contains(&name.len())
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"_.-".contains(&b))
}

/// The calibrations a server was started with, by name.
#[derive(Clone, Default)]
pub struct Calibrations {
    by_name: BTreeMap<String, Arc<Calibration>>,
}

impl std::fmt::Debug for Calibrations {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_set().entries(self.by_name.keys()).finish()
    }
}

impl Calibrations {
    /// Splits a `--calibration` argument `NAME=FILE`, checking the name.
    pub fn parse_argument(argument: &str) -> Result<(String, PathBuf), Error> {
        let Some((name, file)) = argument.split_once('=') else {
            return Err(Error::Config(format!(
                "--calibration {argument:?} is not NAME=FILE"
            )));
        };
        if !is_calibration_name(name) {
            return Err(Error::Config(format!(
                "--calibration {argument:?}: the name {name:?} is not 1 to {MAX_NAME_LEN} of \
                 A-Z a-z 0-9 _ . -"
            )));
        }
        if file.is_empty() {
            return Err(Error::Config(format!(
                "--calibration {argument:?}: no file after the ="
            )));
        }
        Ok((name.to_string(), PathBuf::from(file)))
    }

    /// Reads and checks the calibration file `path` and keeps it as `name`; an unreadable or
    /// invalid file, a bad or repeated name, or one past [`MAX_CALIBRATIONS`] is an error
    /// naming them.
    pub fn read(&mut self, name: &str, path: &Path) -> Result<(), Error> {
        self.check_new(name)?;
        let calibration = Calibration::read(path)
            .map_err(|e| Error::Config(format!("calibration {name} ({}): {e}", path.display())))?;
        self.insert(name, calibration)
    }

    /// Keeps `calibration` as `name` (checked as [`Calibrations::read`] does).
    pub fn insert(&mut self, name: &str, calibration: Calibration) -> Result<(), Error> {
        self.check_new(name)?;
        self.by_name.insert(name.to_string(), Arc::new(calibration));
        Ok(())
    }

    fn check_new(&self, name: &str) -> Result<(), Error> {
        if !is_calibration_name(name) {
            return Err(Error::Config(format!(
                "calibration name {name:?} is not 1 to {MAX_NAME_LEN} of A-Z a-z 0-9 _ . -"
            )));
        }
        if self.by_name.contains_key(name) {
            return Err(Error::Config(format!(
                "calibration {name} is given twice: each name once"
            )));
        }
        if self.by_name.len() >= MAX_CALIBRATIONS {
            return Err(Error::Config(format!(
                "calibration {name}: a server keeps at most {MAX_CALIBRATIONS} calibrations"
            )));
        }
        Ok(())
    }

    /// The calibration kept as `name`.
    pub fn get(&self, name: &str) -> Option<&Arc<Calibration>> {
        self.by_name.get(name)
    }

    /// The names, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.by_name.keys().map(String::as_str)
    }

    /// How many are kept.
    pub fn len(&self) -> usize {
        self.by_name.len()
    }

    /// Whether none is kept.
    pub fn is_empty(&self) -> bool {
        self.by_name.is_empty()
    }

    /// What the estimates of a session that asked for `name` (if any) get: the calibration, or,
    /// when this server does not have it (restarted without it), a note that they are not
    /// calibrated.
    pub(crate) fn for_session(&self, name: Option<&str>) -> SessionCalibration {
        match name {
            None => SessionCalibration::None,
            Some(name) => match self.get(name) {
                Some(calibration) => SessionCalibration::Apply {
                    name: name.to_string(),
                    calibration: calibration.clone(),
                },
                None => SessionCalibration::Missing(name.to_string()),
            },
        }
    }
}

/// How a session's estimates are calibrated on this server.
#[derive(Debug, Clone, Default)]
pub(crate) enum SessionCalibration {
    /// The session asked for none: the estimate is the spread, as in the paper.
    #[default]
    None,
    /// Every estimate is calibrated with this one.
    Apply {
        name: String,
        calibration: Arc<Calibration>,
    },
    /// The session asked for a calibration this server does not have: estimates are published
    /// uncalibrated, and the results say so (`"calibration_missing": NAME`).
    Missing(String),
}

impl SessionCalibration {
    /// The calibration to apply and its name, if any.
    pub(crate) fn applied(&self) -> Option<(&Calibration, &str)> {
        match self {
            SessionCalibration::Apply { name, calibration } => Some((calibration, name)),
            _ => None,
        }
    }

    /// Marks a results JSON document (one object, as the estimator writes it) of a session
    /// whose calibration is missing: `"calibration_missing": NAME` first; other documents
    /// are returned as they are.
    pub(crate) fn mark(&self, json: String) -> String {
        match self {
            SessionCalibration::Missing(name) if json.starts_with('{') => {
                let name = serde_json::to_string(name).expect("a string serializes");
                let rest = &json[1..];
                let comma = if rest.trim_start().starts_with('}') {
                    ""
                } else {
                    ","
                };
                format!("{{\"calibration_missing\":{name}{comma}{rest}")
            }
            _ => json,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A small valid calibration for `setting`, `window_frames` and `pose_relation`: the
    /// calibrated value is twice the statistic (plus its offset), the interval ×0.5 … ×2.
    pub(crate) fn calibration(setting: &str, window_frames: usize, relation: &str) -> String {
        serde_json::json!({
            "format": "sitar-calibration",
            "version": 1,
            "fitted_on": {
                "sequences": [{"name": "a", "runs": 10, "set_a": 5, "set_b": 5, "windows": 100}],
                "setting": setting,
                "window_frames": window_frames,
                "pose_relation": relation,
                "unit": if relation == "angle_deg" { "deg" } else { "m" },
                "coverage": 0.8,
                "t_max_diff_s": 0.01,
            },
            "model": {
                "kind": "log_linear",
                "features": ["ln_statistic", "ln_path_m", "ln_rotation_deg"],
                "offsets": [1e-3, 1e-3, 0.1],
                "smoothing_windows": 1,
                "coefficients": [std::f64::consts::LN_2, 1.0, 0.0, 0.0],
                "spread_match": 0.0,
                "center": -3.0,
                "stretch": 1.0,
            },
            "interval": {
                "method": "in_sample",
                "log_lower": -std::f64::consts::LN_2,
                "log_upper": std::f64::consts::LN_2,
                "residuals": 100,
            },
        })
        .to_string()
    }

    /// A version-2 calibration for `setting`, `window_frames` and `relation` with every
    /// model: one run's error is half its path over the window; with replays (or several
    /// runs), twice their spread; intervals ×0.5 … ×2; `informative` as given.
    pub(crate) fn calibration_v2(
        setting: &str,
        window_frames: usize,
        relation: &str,
        informative: bool,
    ) -> Calibration {
        use sitar_core::calibration::{
            CALIBRATION_FORMAT, CalibrationModel, Feature, FittedOn, IntervalModel, RunCount,
            Target,
        };
        let model = |target, runs, feature: Feature, factor: f64| CalibrationModel {
            target,
            runs,
            kind: "log_linear".into(),
            features: vec![feature],
            offsets: vec![feature.offset()],
            smoothing_windows: 0,
            coefficients: vec![factor.ln(), 1.0],
            spread_match: 0.0,
            center: 0.0,
            stretch: 1.0,
            interval: IntervalModel {
                method: "in_sample".into(),
                log_lower: 0.5f64.ln(),
                log_upper: 2.0f64.ln(),
                residuals: 100,
            },
            informative,
            scores: None,
        };
        Calibration {
            format: CALIBRATION_FORMAT.into(),
            version: 2,
            fitted_on: FittedOn {
                sequences: Vec::new(),
                setting: setting.into(),
                window_frames,
                pose_relation: relation.into(),
                unit: if relation == "angle_deg" { "deg" } else { "m" }.into(),
                coverage: 0.8,
                t_max_diff_s: 0.01,
            },
            informative,
            models: vec![
                model(Target::Live, RunCount::One, Feature::PathM, 0.5),
                model(Target::Live, RunCount::Several, Feature::Spread, 2.0),
                model(Target::Expected, RunCount::Several, Feature::Spread, 2.0),
            ],
        }
    }

    #[test]
    fn arguments_and_names_are_checked() {
        let (name, file) = Calibrations::parse_argument("pixel7_arcore=cal/p7.json").unwrap();
        assert_eq!(
            (name.as_str(), file),
            ("pixel7_arcore", "cal/p7.json".into())
        );
        // The file may hold `=`; the name ends at the first.
        let (name, file) = Calibrations::parse_argument("a=b=c.json").unwrap();
        assert_eq!((name.as_str(), file), ("a", "b=c.json".into()));
        for bad in [
            "nofile",
            "=x.json",
            "a b=x.json",
            "a/b=x.json",
            "a=",
            &format!("{}=x", "n".repeat(65)),
        ] {
            let err = Calibrations::parse_argument(bad).unwrap_err().to_string();
            assert!(err.contains("--calibration"), "{bad}: {err}");
        }
        assert!(is_calibration_name(&"n".repeat(64)));
        assert!(is_calibration_name("A-z_0.9"));
        assert!(!is_calibration_name("é"));
    }

    #[test]
    fn files_are_read_once_named_once_and_bounded() {
        // Files written through `tempfile` (only `storage` names the file system's calls).
        let file = |text: &str| {
            use std::io::Write;
            let mut file = tempfile::Builder::new().suffix(".json").tempfile().unwrap();
            file.write_all(text.as_bytes()).unwrap();
            file
        };
        let good = file(&calibration("trim_mean_30", 10, "trans_part"));
        let bad = file("{\"format\":\"sitar-calibration\"}");
        let bad_name = bad
            .path()
            .file_name()
            .unwrap()
            .to_str()
            .unwrap()
            .to_string();
        let mut all = Calibrations::default();
        let good = good.path();
        all.read("lab", good).unwrap();
        assert_eq!(all.names().collect::<Vec<_>>(), ["lab"]);
        let err = all.read("lab", good).unwrap_err().to_string();
        assert!(err.contains("lab") && err.contains("twice"), "{err}");
        let err = all.read("other", bad.path()).unwrap_err().to_string();
        assert!(err.contains("other") && err.contains(&bad_name), "{err}");
        let missing = good.with_file_name("missing-calibration.json");
        let err = all.read("gone", &missing).unwrap_err().to_string();
        assert!(
            err.contains("gone") && err.contains("missing-calibration.json"),
            "{err}"
        );
        assert_eq!(all.len(), 1);
        let model = all.get("lab").unwrap().as_ref().clone();
        for i in 1..MAX_CALIBRATIONS {
            all.insert(&format!("c{i}"), model.clone()).unwrap();
        }
        let err = all.insert("one_more", model).unwrap_err().to_string();
        assert!(err.contains(&MAX_CALIBRATIONS.to_string()), "{err}");
        assert_eq!(
            format!("{all:?}").matches('"').count(),
            2 * MAX_CALIBRATIONS
        );
    }

    #[test]
    fn a_missing_calibration_is_named_in_the_results() {
        let mut all = Calibrations::default();
        let model =
            Calibration::from_json(&calibration("median", 10, "trans_part"), "test").unwrap();
        all.insert("here", model).unwrap();
        assert!(matches!(all.for_session(None), SessionCalibration::None));
        assert!(matches!(
            all.for_session(Some("here")),
            SessionCalibration::Apply { ref name, .. } if name == "here"
        ));
        let missing = all.for_session(Some("gone"));
        let json = missing.mark(r#"{"version":1,"windows":[]}"#.to_string());
        assert_eq!(
            json,
            r#"{"calibration_missing":"gone","version":1,"windows":[]}"#
        );
        assert_eq!(
            missing.mark("{}".into()),
            r#"{"calibration_missing":"gone"}"#
        );
        assert_eq!(
            all.for_session(Some("here")).mark("{}".into()),
            "{}",
            "applied: as written"
        );
    }
}
