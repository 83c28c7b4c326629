//! The calibration against numpy and scipy (data: scripts/golden/make_calibration_golden.py),
//! its file round trip and refusals, and its interval's coverage on held-out simulated-like
//! sequences.

use serde_json::Value;
use sitar_estimator::{
    Calibration, CalibrationSequence, FitOptions, PoseRelation, Setting, WindowFeatures,
    fit_calibration, smooth,
};

fn golden() -> Value {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/golden_calibration.json"
    ))
    .unwrap();
    serde_json::from_str(&text).unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn close(what: &str, a: f64, b: f64, tolerance: f64) {
    assert!(
        (a - b).abs() <= tolerance * (1.0 + b.abs()),
        "{what}: {a} vs {b}"
    );
}

/// The golden sequences, features smoothed by the library.
fn sequences(g: &Value) -> Vec<CalibrationSequence> {
    let h = g["smoothing_windows"].as_u64().unwrap() as usize;
    g["sequences"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let (st, p, r) = (
                floats(&s["statistic"]),
                floats(&s["path_m"]),
                floats(&s["rotation_deg"]),
            );
            let features: Vec<WindowFeatures> = (0..st.len())
                .map(|k| WindowFeatures {
                    statistic: st[k],
                    path_m: p[k],
                    rotation_deg: r[k],
                })
                .collect();
            let smoothed = smooth(&features, h);
            for (key, get) in [
                (
                    "statistic",
                    (|f: &WindowFeatures| f.statistic) as fn(&WindowFeatures) -> f64,
                ),
                ("path_m", |f| f.path_m),
                ("rotation_deg", |f| f.rotation_deg),
            ] {
                for (k, want) in floats(&s["smoothed"][key]).into_iter().enumerate() {
                    close(
                        &format!("smoothed {key} {k}"),
                        get(&smoothed[k]),
                        want,
                        1e-13,
                    );
                }
            }
            CalibrationSequence {
                name: format!("seq{i}"),
                sets: (5, 5),
                truth: floats(&s["truth"]),
                raw: st,
                features: smoothed,
            }
        })
        .collect()
}

fn options(g: &Value) -> FitOptions {
    FitOptions {
        coverage: g["coverage"].as_f64().unwrap(),
        spread_match: g["spread_match"].as_f64().unwrap(),
        smoothing_windows: g["smoothing_windows"].as_u64().unwrap() as usize,
        ..FitOptions::default()
    }
}

#[test]
fn fit_equals_numpy() {
    let g = golden();
    let seqs = sequences(&g);
    let c = fit_calibration(&seqs, &options(&g)).unwrap();
    for (k, (a, b)) in c
        .model
        .coefficients
        .iter()
        .zip(floats(&g["coefficients"]))
        .enumerate()
    {
        close(&format!("coefficient {k}"), *a, b, 1e-10);
    }
    close(
        "center",
        c.model.center,
        g["center"].as_f64().unwrap(),
        1e-12,
    );
    close(
        "stretch",
        c.model.stretch,
        g["stretch"].as_f64().unwrap(),
        1e-10,
    );
    close(
        "log_lower",
        c.interval.log_lower,
        g["log_lower"].as_f64().unwrap(),
        1e-10,
    );
    close(
        "log_upper",
        c.interval.log_upper,
        g["log_upper"].as_f64().unwrap(),
        1e-10,
    );
    assert_eq!(c.interval.method, "cross_conformal_by_sequence");
    assert_eq!(c.interval.residuals, 450);
    // Leave one out: the calibration fitted on the other two predicts numpy's values.
    for (i, want) in g["loso"].as_array().unwrap().iter().enumerate() {
        let others: Vec<CalibrationSequence> = seqs
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, s)| s.clone())
            .collect();
        let inner = fit_calibration(&others, &options(&g)).unwrap();
        let (value, lower, upper) = (
            floats(&want["value"]),
            floats(&want["lower"]),
            floats(&want["upper"]),
        );
        for k in 0..value.len() {
            let (v, lo, hi) = inner.predict(&seqs[i].features[k]);
            close(&format!("loso {i} value {k}"), v, value[k], 1e-10);
            close(&format!("loso {i} lower {k}"), lo, lower[k], 1e-10);
            close(&format!("loso {i} upper {k}"), hi, upper[k], 1e-10);
        }
    }
    let scores = c.scores.expect("three sequences are scored");
    assert_eq!(scores.sequences.len(), 3);
    assert!(scores.calibrated.coverage.is_some() && scores.raw.coverage.is_none());
}

#[test]
fn file_round_trip_and_refusals() {
    let g = golden();
    let c = fit_calibration(&sequences(&g), &options(&g)).unwrap();
    let text = c.to_json();
    let back = Calibration::from_json(&text, "c.json").unwrap();
    assert_eq!(back, c);
    let path = std::env::temp_dir().join(format!("sitar-cal-{}.json", std::process::id()));
    std::fs::write(&path, &text).unwrap();
    assert_eq!(Calibration::read(&path).unwrap(), c);
    std::fs::remove_file(&path).unwrap();

    c.check(Setting::TrimMean(30), 10, PoseRelation::TranslationPart)
        .unwrap();
    let err = c
        .check(Setting::Median, 20, PoseRelation::RotationAngleDeg)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("fitted for setting trim_mean_30, 10 window frames, pose relation trans_part")
            && err.contains(
                "the estimate is setting median, 20 window frames, pose relation angle_deg"
            ),
        "{err}"
    );
    // What a bad file says.
    let bad = |edit: &dyn Fn(&mut Value)| {
        let mut v: Value = serde_json::from_str(&text).unwrap();
        edit(&mut v);
        Calibration::from_json(&v.to_string(), "bad.json")
            .unwrap_err()
            .to_string()
    };
    assert!(bad(&|v| v["version"] = 99.into()).contains("version 99"));
    assert!(bad(&|v| v["format"] = "x".into()).contains("format is \"x\""));
    assert!(
        bad(&|v| v["model"]["coefficients"] = serde_json::json!([1.0]))
            .contains("model.coefficients")
    );
    assert!(bad(&|v| v["fitted_on"]["coverage"] = 1.5.into()).contains("fitted_on.coverage"));
    assert!(bad(&|v| v["fitted_on"]["setting"] = "mode".into()).contains("fitted_on.setting"));
    assert!(bad(&|v| v["interval"]["log_lower"] = 5.0.into()).contains("interval.log_lower"));
    assert!(bad(&|v| v["surprise"] = 1.into()).contains("bad.json:"));
    let err = Calibration::from_json("{\"format\":", "cut.json")
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("cut.json:1:"), "{err}");
}
