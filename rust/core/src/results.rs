//! Error-estimation results: parsing (legacy CSV or JSON), lookup and classes.

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::{Error, ErrorUnit, PoseRelation, Thresholds};

/// One RPE window: the estimated error of the frames starting at `start`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ResultWindow {
    /// Start timestamp (ns).
    pub start: i64,
    /// End timestamp (ns), when known (JSON form only).
    pub end: Option<i64>,
    /// Estimated error in the results' unit ([`Results::unit`]: metres, or degrees for
    /// `angle_deg`), finite and ≥ 0. In calibrated results (`calibration` named) the
    /// calibrated value.
    pub error: f64,
    /// Number of trial pairs that had this window, when known (JSON form only).
    pub pairs: Option<u32>,
    /// The uncalibrated estimate (`raw_m`, or `raw_deg` for `angle_deg`) of a calibrated
    /// window, finite and ≥ 0; `None` in uncalibrated results, legacy CSV, and where the
    /// key is `null` (the estimator writes `null` for a value it could not compute).
    #[serde(default)]
    pub raw: Option<f64>,
    /// The interval that holds the window's true error with the calibration's coverage
    /// (`lower_m`/`upper_m`, or `lower_deg`/`upper_deg`); `None` in uncalibrated results
    /// and legacy CSV.
    #[serde(default)]
    pub interval: Option<ErrorInterval>,
}

/// The interval a calibrated window's true error lies in with the calibration's stated
/// coverage (e.g. 80 %), in the results' unit. A calibration is fitted for one SLAM system
/// and playback device (and one setting, window length and pose relation): the interval
/// means what it says only for results of that system and device.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ErrorInterval {
    /// Lower bound, finite and ≥ 0.
    pub lower: f64,
    /// Upper bound, finite and ≥ `lower`.
    pub upper: f64,
}

/// Parsed results, windows sorted by start timestamp.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Results {
    /// The windows, sorted by `start`.
    pub windows: Vec<ResultWindow>,
    /// The statistic used (`"trim_mean_30"` …), when the JSON form names it.
    pub setting: Option<String>,
    /// Number of trials, when the JSON form gives it.
    pub trials: Option<u32>,
    /// Frames per window (the RPE's delta), when the JSON form gives it (`"window_frames"`);
    /// legacy CSV never does.
    pub window_frames: Option<u32>,
    /// What the errors measure (`"pose_relation"`; legacy CSV is always `trans_part`).
    pub relation: PoseRelation,
    /// The name of the calibration applied (`"calibration"`), when the results are
    /// calibrated; `None` for uncalibrated results and legacy CSV.
    pub calibration: Option<String>,
    /// Which error the windows estimate (`"target"`): `live` (the error of one run, the
    /// user's own walk) or `expected` (the mean error at each place); `None` when the
    /// results do not say (uncalibrated results, legacy CSV).
    pub target: Option<String>,
    /// Where they come from (`"source"`): `walk` (the walk alone, estimated on the phone or
    /// at upload) or `replays`.
    pub source: Option<String>,
    /// How many runs they come from (`"runs"`: the walk and its replays).
    pub runs: Option<u32>,
    /// Whether the calibration's runs predict the error at all (`"informative"`); `false`
    /// means the colours are a guess.
    pub informative: Option<bool>,
}

/// The optional count under `key` of a results document: absent or `null` is `None`,
/// otherwise an integer from `min` up that fits in `u32` (`expected` says what in the error).
fn optional_count(
    obj: &serde_json::Map<String, Value>,
    key: &'static str,
    min: u32,
    expected: &str,
) -> Result<Option<u32>, Error> {
    match obj.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(v) => v
            .as_u64()
            .and_then(|n| u32::try_from(n).ok())
            .filter(|&n| n >= min)
            .map(Some)
            .ok_or_else(|| {
                Error::parse(
                    "results.json",
                    0,
                    key,
                    format!("expected {expected}, found {v}"),
                )
            }),
    }
}

/// What results say of where they come from: `target`, `source`, `runs`, `informative`,
/// each optional.
struct Provenance {
    target: Option<String>,
    source: Option<String>,
    runs: Option<u32>,
    informative: Option<bool>,
}

impl Provenance {
    fn parse(obj: &serde_json::Map<String, Value>) -> Result<Self, Error> {
        const SRC: &str = "results.json";
        let word = |key: &'static str, allowed: [&str; 2]| -> Result<Option<String>, Error> {
            match obj.get(key) {
                None | Some(Value::Null) => Ok(None),
                Some(Value::String(s)) if allowed.contains(&s.as_str()) => Ok(Some(s.clone())),
                Some(other) => Err(Error::parse(
                    SRC,
                    0,
                    key,
                    format!(
                        "expected \"{}\" or \"{}\", found {other}",
                        allowed[0], allowed[1]
                    ),
                )),
            }
        };
        let runs = optional_count(obj, "runs", 1, "a count of runs")?;
        let informative = match obj.get("informative") {
            None | Some(Value::Null) => None,
            Some(Value::Bool(b)) => Some(*b),
            Some(other) => {
                return Err(Error::parse(
                    SRC,
                    0,
                    "informative",
                    format!("expected true or false, found {other}"),
                ));
            }
        };
        Ok(Self {
            target: word("target", ["live", "expected"])?,
            source: word("source", ["walk", "replays"])?,
            runs,
            informative,
        })
    }

    fn set(self, results: &mut Results) {
        results.target = self.target;
        results.source = self.source;
        results.runs = self.runs;
        results.informative = self.informative;
    }
}

/// Parses a decimal-seconds token exactly into nanoseconds (no f64 rounding of large stamps).
fn seconds_to_ns(token: &str) -> Option<i64> {
    let (neg, body) = match token.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, token.strip_prefix('+').unwrap_or(token)),
    };
    if body.contains(['e', 'E']) {
        let s: f64 = token.parse().ok()?;
        let ns = (s * 1e9).round();
        return (ns.is_finite() && ns.abs() < 9.2e18).then_some(ns as i64);
    }
    let (int, frac) = body.split_once('.').unwrap_or((body, ""));
    if (int.is_empty() && frac.is_empty())
        || !int.bytes().all(|b| b.is_ascii_digit())
        || !frac.bytes().all(|b| b.is_ascii_digit())
    {
        return None;
    }
    let whole: i64 = if int.is_empty() { 0 } else { int.parse().ok()? };
    let mut nanos: i64 = 0;
    for b in frac.bytes().chain(std::iter::repeat(b'0')).take(9) {
        nanos = nanos * 10 + i64::from(b - b'0');
    }
    // Round half up on the tenth digit onwards.
    if frac.len() > 9 && frac.as_bytes()[9] >= b'5' {
        nanos += 1;
    }
    let total = whole.checked_mul(1_000_000_000)?.checked_add(nanos)?;
    Some(if neg { -total } else { total })
}

fn is_integer_token(token: &str) -> bool {
    let body = token.strip_prefix(['-', '+']).unwrap_or(token);
    !body.is_empty() && body.bytes().all(|b| b.is_ascii_digit())
}

/// An optional number of a JSON window (`raw_…`, `lower_…`, `upper_…`): absent is `None`;
/// `null` is `None` when `null_is_absent`, else an error; otherwise a finite number ≥ 0.
fn window_number(
    window: &Value,
    key: &str,
    path: &str,
    start: i64,
    null_is_absent: bool,
) -> Result<Option<f64>, Error> {
    const SRC: &str = "results.json";
    let bad = |message: String| {
        Err(Error::parse(
            SRC,
            0,
            path,
            format!("{message} (window starting at {start} ns)"),
        ))
    };
    match window.get(key) {
        None => Ok(None),
        Some(Value::Null) if null_is_absent => Ok(None),
        Some(Value::Null) => bad(format!("{key} is null, not a finite number")),
        Some(Value::Number(n)) => match n.as_f64() {
            Some(v) if v.is_finite() && v >= 0.0 => Ok(Some(v)),
            Some(v) if v.is_finite() => bad(format!("{key} {v} is negative")),
            _ => bad(format!("{key} {n} is not a finite number")),
        },
        Some(other) => bad(format!("{key}: expected a number, found {other}")),
    }
}

fn check_error(source: &str, line: usize, field: &str, e: f64) -> Result<f64, Error> {
    if e.is_nan() {
        Err(Error::parse(source, line, field, "error is NaN"))
    } else if !e.is_finite() {
        Err(Error::parse(source, line, field, "error is not finite"))
    } else if e < 0.0 {
        Err(Error::parse(
            source,
            line,
            field,
            format!("error {e} is negative"),
        ))
    } else {
        Ok(e)
    }
}

impl Results {
    /// Parses the legacy CSV (`start,error`) or the JSON form, whichever `text` is
    /// (JSON when it starts with `{`).
    pub fn parse(text: &str) -> Result<Self, Error> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        if text.trim_start().starts_with('{') {
            Self::parse_json(text)
        } else {
            Self::parse_csv(text)
        }
    }

    /// Parses the legacy CSV: an optional header `start,error`, then `start,error` rows.
    /// Starts that are all integers are nanoseconds; otherwise all are decimal seconds.
    pub fn parse_csv(text: &str) -> Result<Self, Error> {
        const SRC: &str = "results.csv";
        let mut rows: Vec<(usize, &str, f64)> = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line_no = i + 1;
            let line = raw.trim();
            if line.is_empty() {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            if rows.is_empty() && fields.len() == 2 && fields[0].eq_ignore_ascii_case("start") {
                if !fields[1].eq_ignore_ascii_case("error") {
                    return Err(Error::parse(
                        SRC,
                        line_no,
                        fields[1],
                        "header must be `start,error`",
                    ));
                }
                continue;
            }
            if fields.len() != 2 {
                return Err(Error::parse(
                    SRC,
                    line_no,
                    "row",
                    format!("expected 2 fields (start,error), found {}", fields.len()),
                ));
            }
            let error = fields[1].parse::<f64>().map_err(|_| {
                Error::parse(
                    SRC,
                    line_no,
                    "error",
                    format!("`{}` is not a number", fields[1]),
                )
            })?;
            let error = check_error(SRC, line_no, "error", error)?;
            rows.push((line_no, fields[0], error));
        }
        let all_integer = rows.iter().all(|(_, s, _)| is_integer_token(s));
        let mut windows = Vec::with_capacity(rows.len());
        for (line_no, start, error_m) in rows {
            let start_ns = if all_integer {
                start.parse::<i64>().ok()
            } else {
                seconds_to_ns(start)
            };
            let start_ns = start_ns.ok_or_else(|| {
                Error::parse(
                    SRC,
                    line_no,
                    "start",
                    format!("`{start}` is not a timestamp"),
                )
            })?;
            windows.push(ResultWindow {
                start: start_ns,
                end: None,
                error: error_m,
                pairs: None,
                raw: None,
                interval: None,
            });
        }
        Ok(Self::sorted(
            windows,
            None,
            None,
            None,
            PoseRelation::TransPart,
        ))
    }

    /// Parses the JSON form `{"version":1,"setting":…,"trials":n,"window_frames":n,
    /// "pose_relation":"trans_part"|"angle_deg","unit":"m"|"deg","windows":[{"start":…,
    /// "end":…,"error_m":…,"pairs":…,"class":…}]}`. `start`/`end` integers are nanoseconds;
    /// numbers with a fraction (or strings) are decimal seconds. `window_frames`,
    /// `pose_relation` and `unit` are optional (`trans_part` and `m` when both are absent;
    /// either implies the other, and they must agree); with `deg` the windows carry
    /// `error_deg` instead of `error_m`. `class` is ignored (recomputed from the session's
    /// thresholds), as are keys this parser does not know.
    ///
    /// Calibrated results (what the backend writes once a calibration is applied) name it
    /// (`"calibration":"<name>"`, a string) and give per window `raw_m`, `lower_m` and
    /// `upper_m` (`raw_deg`, `lower_deg`, `upper_deg` for degrees); `error_m` is then the
    /// calibrated value. Each key is optional. `lower_m` and `upper_m` come together, each a
    /// finite number ≥ 0 (not `null`), lower ≤ upper; `raw_m` is a finite number ≥ 0 or
    /// `null` (kept as `None`). A bad value is an [`Error::Parse`] whose field is the key's
    /// path (`windows[3].lower_m`) and whose message names the window's start.
    pub fn parse_json(text: &str) -> Result<Self, Error> {
        const SRC: &str = "results.json";
        let value: Value = serde_json::from_str(text)
            .map_err(|e| Error::parse(SRC, e.line(), "(document)", e.to_string()))?;
        let obj = value
            .as_object()
            .ok_or_else(|| Error::parse(SRC, 1, "(document)", "expected an object"))?;
        if let Some(v) = obj.get("version")
            && v.as_u64() != Some(1)
        {
            return Err(Error::parse(
                SRC,
                0,
                "version",
                format!("unsupported version {v}"),
            ));
        }
        let setting = match obj.get("setting") {
            None | Some(Value::Null) => None,
            Some(Value::String(s)) => Some(s.clone()),
            Some(other) => {
                return Err(Error::parse(
                    SRC,
                    0,
                    "setting",
                    format!("expected a string, found {other}"),
                ));
            }
        };
        let trials = optional_count(obj, "trials", 0, "a count")?;
        let window_frames = optional_count(obj, "window_frames", 1, "a positive frame count")?;
        let calibration = match obj.get("calibration") {
            None | Some(Value::Null) => None,
            Some(Value::String(s)) => Some(s.clone()),
            Some(other) => {
                return Err(Error::parse(
                    SRC,
                    0,
                    "calibration",
                    format!("expected the calibration's name (a string), found {other}"),
                ));
            }
        };
        let provenance = Provenance::parse(obj)?;
        let relation = relation_and_unit(obj)?;
        let error_key = relation.unit().error_key();
        let [raw_key, lower_key, upper_key] = relation.unit().interval_keys();
        let list = obj
            .get("windows")
            .and_then(Value::as_array)
            .ok_or_else(|| Error::parse(SRC, 0, "windows", "missing or not an array"))?;
        // The stamps' number text, read a second time without going through f64: decimal
        // seconds keep all nine digits (1403636579.763555527 is not an f64).
        #[derive(Deserialize)]
        struct RawStamps {
            start: Option<Box<serde_json::value::RawValue>>,
            end: Option<Box<serde_json::value::RawValue>>,
        }
        #[derive(Deserialize)]
        struct RawDocument {
            windows: Vec<RawStamps>,
        }
        let raw = serde_json::from_str::<RawDocument>(text)
            .ok()
            .filter(|d| d.windows.len() == list.len());
        let mut windows = Vec::with_capacity(list.len());
        for (i, w) in list.iter().enumerate() {
            let raw_text = |f: &str| {
                let stamps = &raw.as_ref()?.windows[i];
                let value = if f == "start" {
                    &stamps.start
                } else {
                    &stamps.end
                };
                value.as_ref().map(|v| v.get().to_owned())
            };
            let path = |f: &str| format!("windows[{i}].{f}");
            let stamp = |f: &str, required: bool| -> Result<Option<i64>, Error> {
                match w.get(f) {
                    None | Some(Value::Null) if !required => Ok(None),
                    None | Some(Value::Null) => Err(Error::parse(SRC, 0, path(f), "missing")),
                    Some(Value::Number(n)) => {
                        let parsed = match n.as_i64() {
                            Some(ns) => Some(ns),
                            None => seconds_to_ns(&raw_text(f).unwrap_or_else(|| n.to_string())),
                        };
                        parsed.map(Some).ok_or_else(|| {
                            Error::parse(SRC, 0, path(f), format!("`{n}` is not a timestamp"))
                        })
                    }
                    Some(Value::String(s)) => seconds_to_ns(s).map(Some).ok_or_else(|| {
                        Error::parse(SRC, 0, path(f), format!("`{s}` is not a timestamp"))
                    }),
                    Some(other) => Err(Error::parse(
                        SRC,
                        0,
                        path(f),
                        format!("expected a number, found {other}"),
                    )),
                }
            };
            let start = stamp("start", true)?.unwrap_or_default();
            let end = stamp("end", false)?;
            let error = w
                .get(error_key)
                .and_then(Value::as_f64)
                .ok_or_else(|| Error::parse(SRC, 0, path(error_key), "missing or not a number"))?;
            let error = check_error(SRC, 0, &path(error_key), error)?;
            let pairs = match w.get("pairs") {
                None | Some(Value::Null) => None,
                Some(v) => Some(v.as_u64().and_then(|p| u32::try_from(p).ok()).ok_or_else(
                    || {
                        Error::parse(
                            SRC,
                            0,
                            path("pairs"),
                            format!("expected a count, found {v}"),
                        )
                    },
                )?),
            };
            let raw = window_number(w, raw_key, &path(raw_key), start, true)?;
            let lower = window_number(w, lower_key, &path(lower_key), start, false)?;
            let upper = window_number(w, upper_key, &path(upper_key), start, false)?;
            let interval = match (lower, upper) {
                (None, None) => None,
                (Some(lower), Some(upper)) if lower <= upper => {
                    Some(ErrorInterval { lower, upper })
                }
                (Some(lower), Some(upper)) => {
                    return Err(Error::parse(
                        SRC,
                        0,
                        path(lower_key),
                        format!(
                            "{lower_key} {lower} is above {upper_key} {upper} (window \
                             starting at {start} ns)"
                        ),
                    ));
                }
                (given, _) => {
                    let (present, missing) = if given.is_some() {
                        (lower_key, upper_key)
                    } else {
                        (upper_key, lower_key)
                    };
                    return Err(Error::parse(
                        SRC,
                        0,
                        path(missing),
                        format!(
                            "missing while {present} is given: an interval needs both bounds \
                             (window starting at {start} ns)"
                        ),
                    ));
                }
            };
            windows.push(ResultWindow {
                start,
                end,
                error,
                pairs,
                raw,
                interval,
            });
        }
        let mut results = Self::sorted(windows, setting, trials, window_frames, relation);
        results.calibration = calibration;
        provenance.set(&mut results);
        Ok(results)
    }

    fn sorted(
        mut windows: Vec<ResultWindow>,
        setting: Option<String>,
        trials: Option<u32>,
        window_frames: Option<u32>,
        relation: PoseRelation,
    ) -> Self {
        // Stable: among equal starts the first row wins the lookup.
        windows.sort_by_key(|w| w.start);
        Self {
            windows,
            setting,
            trials,
            window_frames,
            relation,
            calibration: None,
            target: None,
            source: None,
            runs: None,
            informative: None,
        }
    }

    /// The unit of the errors: metres for `trans_part`, degrees for `angle_deg`.
    pub fn unit(&self) -> ErrorUnit {
        self.relation.unit()
    }

    /// Writes the JSON form (starts and ends in integer nanoseconds, the error under the
    /// key of its unit), classes from the thresholds (which must be in that unit). A
    /// calibration's name and the windows' raw values and intervals are written where
    /// present, under the keys of the unit.
    pub fn to_json(&self, thresholds: Thresholds) -> String {
        let error_key = self.unit().error_key();
        let [raw_key, lower_key, upper_key] = self.unit().interval_keys();
        let windows: Vec<Value> = self
            .windows
            .iter()
            .map(|w| {
                let mut o = serde_json::Map::new();
                o.insert("start".into(), w.start.into());
                o.insert("end".into(), w.end.into());
                o.insert(error_key.into(), w.error.into());
                o.insert("pairs".into(), w.pairs.into());
                o.insert("class".into(), thresholds.classify(w.error).name().into());
                if let Some(raw) = w.raw {
                    o.insert(raw_key.into(), raw.into());
                }
                if let Some(interval) = w.interval {
                    o.insert(lower_key.into(), interval.lower.into());
                    o.insert(upper_key.into(), interval.upper.into());
                }
                Value::Object(o)
            })
            .collect();
        let mut doc = serde_json::json!({
            "version": 1,
            "setting": self.setting,
            "trials": self.trials,
            "window_frames": self.window_frames,
            "pose_relation": self.relation.name(),
            "unit": self.unit().name(),
            "windows": windows,
        });
        if let Value::Object(o) = &mut doc {
            if let Some(name) = &self.calibration {
                o.insert("calibration".into(), name.as_str().into());
            }
            if let Some(target) = &self.target {
                o.insert("target".into(), target.as_str().into());
            }
            if let Some(source) = &self.source {
                o.insert("source".into(), source.as_str().into());
            }
            if let Some(runs) = self.runs {
                o.insert("runs".into(), runs.into());
            }
            if let Some(informative) = self.informative {
                o.insert("informative".into(), informative.into());
            }
        }
        serde_json::to_string_pretty(&doc).unwrap_or_default()
    }

    /// The window whose start is nearest to `t_ns`, if within `tolerance_ns` (inclusive).
    /// Ties go to the earlier start. O(log n).
    pub fn lookup(&self, t_ns: i64, tolerance_ns: i64) -> Option<&ResultWindow> {
        let i = self.windows.partition_point(|w| w.start < t_ns);
        let after = self.windows.get(i);
        let before = i.checked_sub(1).and_then(|j| self.windows.get(j));
        let best = match (before, after) {
            (Some(b), Some(a)) => {
                if t_ns.abs_diff(b.start) <= a.start.abs_diff(t_ns) {
                    b
                } else {
                    a
                }
            }
            (Some(b), None) => b,
            (None, Some(a)) => a,
            (None, None) => return None,
        };
        (best.start.abs_diff(t_ns) <= tolerance_ns.max(0) as u64).then_some(best)
    }

    /// [`Results::lookup`] for many timestamps at once: O(n + m) when `times` ascend
    /// (a merge walk), falling back to binary search for any that do not.
    pub fn lookup_many(&self, times: &[i64], tolerance_ns: i64) -> Vec<Option<&ResultWindow>> {
        let tol = tolerance_ns.max(0) as u64;
        let w = &self.windows;
        let mut out = Vec::with_capacity(times.len());
        let mut i = 0; // first window with start >= t, for ascending t
        let mut last = i64::MIN;
        for &t in times {
            if t < last {
                out.push(self.lookup(t, tolerance_ns));
                continue;
            }
            last = t;
            while i < w.len() && w[i].start < t {
                i += 1;
            }
            let before = i.checked_sub(1).map(|j| &w[j]);
            let best = match (before, w.get(i)) {
                (Some(b), Some(a)) => {
                    if t.abs_diff(b.start) <= a.start.abs_diff(t) {
                        Some(b)
                    } else {
                        Some(a)
                    }
                }
                (b, a) => b.or(a),
            };
            out.push(best.filter(|x| x.start.abs_diff(t) <= tol));
        }
        out
    }

    /// Mean error over all windows (in [`Results::unit`]), `None` without windows.
    pub fn mean_error(&self) -> Option<f64> {
        (!self.windows.is_empty())
            .then(|| self.windows.iter().map(|w| w.error).sum::<f64>() / self.windows.len() as f64)
    }
}

/// The document's `pose_relation` and `unit`: either implies the other; both absent is
/// `trans_part` in metres (what results had before they named it); they must agree.
fn relation_and_unit(obj: &serde_json::Map<String, Value>) -> Result<PoseRelation, Error> {
    const SRC: &str = "results.json";
    let text = |key: &str| -> Result<Option<&str>, Error> {
        match obj.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::String(s)) => Ok(Some(s)),
            Some(other) => Err(Error::parse(
                SRC,
                0,
                key,
                format!("expected a string, found {other}"),
            )),
        }
    };
    let relation = text("pose_relation")?
        .map(|name| {
            PoseRelation::from_name(name).ok_or_else(|| {
                Error::parse(
                    SRC,
                    0,
                    "pose_relation",
                    format!("`{name}` is not a relation the phone shows (trans_part or angle_deg)"),
                )
            })
        })
        .transpose()?;
    let unit = text("unit")?
        .map(|name| {
            ErrorUnit::from_name(name).ok_or_else(|| {
                Error::parse(SRC, 0, "unit", format!("`{name}` is not a unit (m or deg)"))
            })
        })
        .transpose()?;
    match (relation, unit) {
        (Some(r), Some(u)) if r.unit() != u => Err(Error::parse(
            SRC,
            0,
            "unit",
            format!(
                "`{}` does not fit pose_relation `{r}` (its unit is `{}`)",
                u.name(),
                r.unit().name()
            ),
        )),
        (Some(r), _) => Ok(r),
        (None, Some(ErrorUnit::Degrees)) => Ok(PoseRelation::AngleDeg),
        (None, _) => Ok(PoseRelation::TransPart),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn legacy_csv_in_nanoseconds() {
        let r = Results::parse(
            "\u{feff}start,error\r\n1700000000200000000,0.12\r\n1700000000100000000,0.03\r\n",
        )
        .unwrap();
        assert_eq!(r.windows.len(), 2);
        assert_eq!(r.windows[0].start, 1_700_000_000_100_000_000);
        assert_eq!(r.windows[0].error, 0.03);
        assert_eq!(r.windows[1].error, 0.12);
        assert_eq!(
            (r.relation, r.window_frames),
            (PoseRelation::TransPart, None)
        );
    }

    #[test]
    fn legacy_csv_in_seconds_is_exact() {
        let r = Results::parse("start,error\n1700000000.123456789,0.5\n1700000001,0.25\n").unwrap();
        assert_eq!(r.windows[0].start, 1_700_000_000_123_456_789);
        assert_eq!(r.windows[1].start, 1_700_000_001_000_000_000);
        assert_eq!(seconds_to_ns("0.5"), Some(500_000_000));
        assert_eq!(seconds_to_ns("-1.25"), Some(-1_250_000_000));
        assert_eq!(seconds_to_ns("1.0000000005"), Some(1_000_000_001));
        assert_eq!(seconds_to_ns("1.5e0"), Some(1_500_000_000));
        assert_eq!(seconds_to_ns("abc"), None);
        assert_eq!(seconds_to_ns("."), None);
    }

    #[test]
    fn malformed_csv_names_line_and_field() {
        let cases = [
            ("start,error\n1,0.1\n2,abc\n", 3, "error"),
            ("start,error\n1,0.1\n2,NaN\n", 3, "error"),
            ("start,error\n1,-0.1\n", 2, "error"),
            ("start,error\n1,0.1,7\n", 2, "row"),
            ("start,error\n1.5,0.1\nx,0.2\n", 3, "start"),
            ("start,err\n", 1, "err"),
        ];
        for (text, want_line, want_field) in cases {
            match Results::parse(text) {
                Err(Error::Parse { line, field, .. }) => {
                    assert_eq!((line, field.as_str()), (want_line, want_field), "{text:?}")
                }
                other => panic!("{text:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn json_form() {
        let text = r#"{"version":1,"setting":"trim_mean_30","trials":5,"windows":[
            {"start":2000,"end":3000,"error_m":0.2,"pairs":10,"class":"high"},
            {"start":1000,"end":2000,"error_m":0.01,"pairs":9,"class":"low"}]}"#;
        let r = Results::parse(text).unwrap();
        assert_eq!(r.setting.as_deref(), Some("trim_mean_30"));
        assert_eq!(r.trials, Some(5));
        assert_eq!(
            r.windows[0],
            ResultWindow {
                start: 1000,
                end: Some(2000),
                error: 0.01,
                pairs: Some(9),
                raw: None,
                interval: None,
            }
        );
        assert_eq!(
            Results::parse(&r.to_json(Thresholds::DEFAULT_M)).unwrap(),
            r
        );
        assert!(
            r.to_json(Thresholds::DEFAULT_M)
                .contains("\"class\": \"high\"")
        );
        let bad = r#"{"windows":[{"start":1,"error_m":-1}]}"#;
        match Results::parse(bad) {
            Err(Error::Parse { field, .. }) => assert_eq!(field, "windows[0].error_m"),
            other => panic!("{other:?}"),
        }
        match Results::parse("{\"windows\":[\n{\"start\":1,}]}") {
            Err(Error::Parse { line, .. }) => assert_eq!(line, 2),
            other => panic!("{other:?}"),
        }
        let secs = Results::parse(r#"{"windows":[{"start":1.5,"error_m":0.1}]}"#).unwrap();
        assert_eq!(secs.windows[0].start, 1_500_000_000);
        // Decimal seconds are read from the text, not through f64 (which keeps ~16 digits).
        let exact = Results::parse(
            r#"{"windows":[{"start":1403636579.763555527,"end":1403636580.096888861,"error_m":0.1}]}"#,
        )
        .unwrap();
        assert_eq!(exact.windows[0].start, 1_403_636_579_763_555_527);
        assert_eq!(exact.windows[0].end, Some(1_403_636_580_096_888_861));
    }

    #[test]
    fn estimator_json_shape() {
        // What sitar-estimator's Estimate::to_json writes (extra keys are ignored).
        let text = r#"{"version":1,"setting":"trim_mean_30","trials":3,"time_unit":"s",
            "pose_relation":"trans_part","windows":[{"start":1700000000000000000,
            "end":1700000000333333333,"error_m":0.031,"pairs":3,"spread_m":0.002,"class":"low"}]}"#;
        let r = Results::parse(text).unwrap();
        assert_eq!(r.windows[0].start, 1_700_000_000_000_000_000);
        assert_eq!(r.windows[0].end, Some(1_700_000_000_333_333_333));
        assert_eq!((r.windows[0].error, r.windows[0].pairs), (0.031, Some(3)));
        // A rotation-error document has no error_m: refused rather than misread.
        let rot = r#"{"version":1,"windows":[{"start":1,"end":2,"error_deg":1.5,"pairs":3}]}"#;
        assert!(
            matches!(Results::parse(rot), Err(Error::Parse { field, .. }) if field == "windows[0].error_m")
        );
        assert!(Results::parse(r#"{"version":2,"windows":[]}"#).is_err());
    }

    #[test]
    fn calibrated_json_keeps_raw_values_and_intervals() {
        // What sitar-estimator's Estimate::to_json writes once a calibration is applied.
        let text = r#"{"version":1,"setting":"median","trials":2,"time_unit":"s","pose_relation":"trans_part","window_frames":10,"unit":"m","calibration":"euroc","windows":[{"start":0.000001000,"end":0.000002000,"class":"high","error_m":0.25,"lower_m":0.0625,"pairs":3,"raw_m":0.125,"spread_m":0.5,"upper_m":0.5},{"start":0.000002000,"end":0.000003000,"class":"low","error_m":0.02,"lower_m":0.01,"pairs":3,"raw_m":null,"spread_m":0.1,"upper_m":0.04}]}"#;
        let r = Results::parse(text).unwrap();
        assert_eq!(r.calibration.as_deref(), Some("euroc"));
        assert_eq!(
            r.windows[0],
            ResultWindow {
                start: 1000,
                end: Some(2000),
                error: 0.25,
                pairs: Some(3),
                raw: Some(0.125),
                interval: Some(ErrorInterval {
                    lower: 0.0625,
                    upper: 0.5
                }),
            }
        );
        // A null raw value is absent; the interval stays.
        assert_eq!(r.windows[1].raw, None);
        assert_eq!(
            r.windows[1].interval,
            Some(ErrorInterval {
                lower: 0.01,
                upper: 0.04
            })
        );
        assert_eq!(
            r.lookup(1010, 10).and_then(|w| w.interval).unwrap().upper,
            0.5
        );
        // The JSON form writes them back.
        let json = r.to_json(Thresholds::DEFAULT_M);
        assert!(json.contains(r#""calibration": "euroc""#), "{json}");
        assert_eq!(Results::parse(&json).unwrap(), r);
        // Uncalibrated results have none of them, and say so.
        let plain = Results::parse(r#"{"windows":[{"start":1,"error_m":0.1}]}"#).unwrap();
        assert_eq!(
            (
                plain.calibration,
                plain.windows[0].raw,
                plain.windows[0].interval
            ),
            (None, None, None)
        );
        let csv = Results::parse(
            "start,error
1,0.1
",
        )
        .unwrap();
        assert_eq!((csv.windows[0].raw, csv.windows[0].interval), (None, None));
        assert!(!plain_json_has_interval_keys(
            &csv.to_json(Thresholds::DEFAULT_M)
        ));
        // Degrees: the keys of the unit.
        let deg = Results::parse(
            r#"{"unit":"deg","calibration":"c","windows":[{"start":1,"error_deg":3,
            "raw_deg":2,"lower_deg":1,"upper_deg":6,"lower_m":9,"upper_m":1}]}"#,
        )
        .unwrap();
        assert_eq!(deg.windows[0].raw, Some(2.0));
        assert_eq!(
            deg.windows[0].interval,
            Some(ErrorInterval {
                lower: 1.0,
                upper: 6.0
            })
        );
        let json = deg.to_json(Thresholds::DEFAULT_DEG);
        assert!(
            json.contains("upper_deg") && !json.contains("upper_m"),
            "{json}"
        );
        assert_eq!(Results::parse(&json).unwrap(), deg);
    }

    fn plain_json_has_interval_keys(json: &str) -> bool {
        ["calibration", "raw_m", "lower_m", "upper_m"]
            .iter()
            .any(|k| json.contains(k))
    }

    #[test]
    fn bad_bounds_name_the_key_and_the_window() {
        let window = |extra: &str| {
            format!(
                r#"{{"calibration":"euroc","windows":[{{"start":5,"error_m":0.1}},{{"start":7,"error_m":0.1,{extra}}}]}}"#
            )
        };
        let cases = [
            (
                r#""lower_m":0.3,"upper_m":0.2"#,
                "windows[1].lower_m",
                "above upper_m 0.2",
            ),
            (
                r#""lower_m":-0.1,"upper_m":0.2"#,
                "windows[1].lower_m",
                "negative",
            ),
            (
                r#""lower_m":0.1,"upper_m":-0.2"#,
                "windows[1].upper_m",
                "negative",
            ),
            (
                r#""lower_m":null,"upper_m":0.2"#,
                "windows[1].lower_m",
                "null",
            ),
            (
                r#""lower_m":0.1,"upper_m":null"#,
                "windows[1].upper_m",
                "null",
            ),
            (
                r#""lower_m":0.1,"upper_m":"0.2""#,
                "windows[1].upper_m",
                "expected a number",
            ),
            (r#""lower_m":0.1,"upper_m":1e999"#, "(document)", ""),
            (r#""lower_m":0.1"#, "windows[1].upper_m", "both bounds"),
            (r#""upper_m":0.1"#, "windows[1].lower_m", "both bounds"),
            (r#""raw_m":-1"#, "windows[1].raw_m", "negative"),
            (r#""raw_m":[1]"#, "windows[1].raw_m", "expected a number"),
        ];
        for (extra, want_field, want_message) in cases {
            let text = window(extra);
            match Results::parse(&text) {
                Err(Error::Parse { field, message, .. }) => {
                    assert_eq!(field, want_field, "{text}");
                    assert!(message.contains(want_message), "{text}: {message}");
                    if want_field != "(document)" {
                        assert!(message.contains("starting at 7 ns"), "{text}: {message}");
                    }
                }
                other => panic!("{text}: {other:?}"),
            }
        }
        match Results::parse(r#"{"calibration":3,"windows":[]}"#) {
            Err(Error::Parse { field, .. }) => assert_eq!(field, "calibration"),
            other => panic!("{other:?}"),
        }
        // Equal bounds are an interval; a null calibration is none.
        let r = Results::parse(
            r#"{"calibration":null,"windows":[{"start":1,"error_m":0.1,"lower_m":0.1,"upper_m":0.1}]}"#,
        )
        .unwrap();
        assert_eq!(r.calibration, None);
        assert_eq!(r.windows[0].interval.unwrap().upper, 0.1);
    }

    #[test]
    fn window_settings_and_degrees() {
        // What the backend and `sitar estimate -r angle_deg --delta 20` write.
        let text = r#"{"version":1,"setting":"median","trials":4,"window_frames":20,
            "pose_relation":"angle_deg","unit":"deg","windows":[
            {"start":2000,"end":3000,"error_deg":4.5,"pairs":6,"spread_deg":0.2},
            {"start":1000,"end":2000,"error_deg":0.5,"pairs":6,"spread_deg":0.1}]}"#;
        let r = Results::parse(text).unwrap();
        assert_eq!(r.window_frames, Some(20));
        assert_eq!(
            (r.relation, r.unit()),
            (PoseRelation::AngleDeg, ErrorUnit::Degrees)
        );
        assert_eq!(
            r.windows.iter().map(|w| w.error).collect::<Vec<_>>(),
            [0.5, 4.5]
        );
        let json = r.to_json(Thresholds::DEFAULT_DEG);
        assert!(
            json.contains("\"error_deg\": 4.5") && !json.contains("error_m"),
            "{json}"
        );
        assert!(json.contains("\"class\": \"high\""), "{json}");
        assert_eq!(Results::parse(&json).unwrap(), r);
        // Either key implies the other.
        let unit_only =
            Results::parse(r#"{"unit":"deg","windows":[{"start":1,"error_deg":1}]}"#).unwrap();
        assert_eq!(unit_only.relation, PoseRelation::AngleDeg);
        let relation_only =
            Results::parse(r#"{"pose_relation":"trans_part","windows":[{"start":1,"error_m":1}]}"#)
                .unwrap();
        assert_eq!(relation_only.unit(), ErrorUnit::Metres);
        // Metric results name their window length too and round-trip it.
        let m = Results::parse(r#"{"window_frames":10,"windows":[{"start":1,"error_m":0.1}]}"#)
            .unwrap();
        assert_eq!(m.window_frames, Some(10));
        assert_eq!(
            Results::parse(&m.to_json(Thresholds::DEFAULT_M)).unwrap(),
            m
        );
    }

    #[test]
    fn bad_window_settings_name_the_key() {
        let cases = [
            (r#"{"window_frames":0,"windows":[]}"#, "window_frames"),
            (r#"{"window_frames":"10","windows":[]}"#, "window_frames"),
            (r#"{"window_frames":2.5,"windows":[]}"#, "window_frames"),
            (
                r#"{"pose_relation":"angle_rad","windows":[]}"#,
                "pose_relation",
            ),
            (r#"{"pose_relation":7,"windows":[]}"#, "pose_relation"),
            (r#"{"unit":"rad","windows":[]}"#, "unit"),
            (
                r#"{"pose_relation":"angle_deg","unit":"m","windows":[]}"#,
                "unit",
            ),
            (
                r#"{"pose_relation":"angle_deg","windows":[{"start":1,"error_m":0.1}]}"#,
                "windows[0].error_deg",
            ),
        ];
        for (text, want) in cases {
            match Results::parse(text) {
                Err(Error::Parse { field, .. }) => assert_eq!(field, want, "{text}"),
                other => panic!("{text}: {other:?}"),
            }
        }
    }

    #[test]
    fn classes_and_mean() {
        let r = Results::parse("start,error\n1,0.1\n2,0.3\n").unwrap();
        assert!((r.mean_error().unwrap() - 0.2).abs() < 1e-15);
        assert_eq!(Results::default().mean_error(), None);
    }

    #[test]
    fn lookup_tolerance_is_inclusive() {
        let r = Results::parse("start,error\n100,0.1\n200,0.2\n").unwrap();
        assert_eq!(r.lookup(110, 10).map(|w| w.start), Some(100));
        assert_eq!(r.lookup(111, 10), None);
        assert_eq!(r.lookup(150, 50).map(|w| w.start), Some(100)); // tie → earlier
        assert_eq!(r.lookup(151, 50).map(|w| w.start), Some(200));
        assert_eq!(Results::default().lookup(0, 1000), None);
    }

    proptest! {
        #[test]
        fn lookup_returns_the_nearest_start(
            mut starts in prop::collection::vec(-1_000_000i64..1_000_000, 1..60),
            t in -1_100_000i64..1_100_000,
            tol in 0i64..200_000,
        ) {
            starts.sort_unstable();
            starts.dedup();
            let r = Results { windows: starts.iter().map(|&s| ResultWindow { start: s, end: None, error: 0.0, pairs: None, raw: None, interval: None }).collect(), ..Default::default() };
            let best = starts.iter().map(|s| s.abs_diff(t)).min().unwrap();
            match r.lookup(t, tol) {
                Some(w) => {
                    prop_assert_eq!(w.start.abs_diff(t), best);
                    prop_assert!(best <= tol as u64);
                }
                None => prop_assert!(best > tol as u64),
            }
        }

        #[test]
        fn lookup_many_equals_lookup(
            mut starts in prop::collection::vec(-1_000i64..1_000, 0..60),
            mut times in prop::collection::vec(-1_100i64..1_100, 0..60),
            sort_times in any::<bool>(),
            tol in 0i64..200,
        ) {
            starts.sort_unstable();
            if sort_times { times.sort_unstable(); }
            let r = Results { windows: starts.iter().map(|&s| ResultWindow { start: s, end: None, error: 0.0, pairs: None, raw: None, interval: None }).collect(), ..Default::default() };
            let many = r.lookup_many(&times, tol);
            for (t, got) in times.iter().zip(many) {
                prop_assert_eq!(got.map(|w| w.start), r.lookup(*t, tol).map(|w| w.start));
            }
        }

        #[test]
        fn seconds_parse_exactly(secs in 0i64..4_000_000_000, nanos in 0i64..1_000_000_000) {
            let token = format!("{secs}.{nanos:09}");
            prop_assert_eq!(seconds_to_ns(&token), Some(secs * 1_000_000_000 + nanos));
        }
    }
}
