//! The demo's estimate from one walk (issue 41): a calibration for the simulated SLAM, fitted
//! in-process on other simulated walks with ground truth; the phone colours its walk with it
//! the moment the walk stops (no replay, no network); the backend, given the same calibration
//! and the walk, publishes first results from it at upload and refines them with the replays.
//!
//! The calibration is fitted here rather than read from a committed file: it is then always
//! the simulator's as it is now (a committed file would go stale silently when the
//! simulator's error model changes), it is fitted on walks the demo never shows (other seeds),
//! and the fit takes well under a second in a release build.

use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use sitar_core::{ErrorClass, Session as PhoneSession};
use sitar_estimator::{
    Calibration, CalibrationSequence, DEFAULT_SMOOTHING_WINDOWS, EstimateOptions, FitOptions,
    Trajectory, fit_calibration,
};
use sitar_sim::Recording;

/// The name the demo's backend knows the calibration by.
pub const CALIBRATION_NAME: &str = "demo_sim";

/// Seeds of the walks the calibration is fitted on (never the demo's own walk: its seed is
/// kept out).
const FIT_SEEDS: [u64; 3] = [1001, 1002, 1003];
/// Seconds of each fitting walk.
const FIT_SECONDS: f64 = 10.0;
/// Runs per fitting walk: the truth's set (its mean error is the expected error) and the
/// estimate's set (each in turn the live run, the others its replays).
const SET_A: u32 = 4;
const SET_B: u32 = 4;

/// A calibration for the simulated SLAM with the backend's default estimate settings, fitted
/// on simulated walks with ground truth (none of them `demo_seed`'s); the time it took.
pub fn fit(demo_seed: u64) -> Result<(Calibration, Duration)> {
    let started = Instant::now();
    let sequences = FIT_SEEDS
        .iter()
        .map(|&seed| seed + u64::from(seed == demo_seed) * 100)
        .map(|seed| {
            let recording = Recording::demo(FIT_SECONDS, 30.0, seed)
                .context("cannot simulate a walk to fit the calibration on")?;
            let truth = &recording.walk().ground_truth;
            // Set A from trial indices the estimate's set never uses.
            let set_a: Vec<Trajectory> = (100..100 + SET_A)
                .map(|i| sitar_sim::play_trial(&recording, i))
                .collect();
            let set_b = sitar_sim::simulate_trials(&recording, SET_B);
            CalibrationSequence::new(
                &format!("sim-{seed}"),
                truth,
                &set_a,
                &set_b,
                &EstimateOptions::default(),
                DEFAULT_SMOOTHING_WINDOWS,
            )
            .context("cannot fit the demo's calibration")
        })
        .collect::<Result<Vec<_>>>()?;
    let calibration = fit_calibration(&sequences, &FitOptions::default())
        .context("cannot fit the demo's calibration")?;
    Ok((calibration, started.elapsed()))
}

/// The demo's step 1b: the phone colours its walk with `calibration` the moment it stopped
/// (offline: no replay, no network). The classes it gave.
pub fn colour_walk(
    session: &mut PhoneSession,
    calibration: &Calibration,
) -> Result<Vec<ErrorClass>> {
    let json = calibration.to_json();
    let started = Instant::now();
    session
        .set_calibration(&json)
        .context("the phone refused the demo's calibration")?;
    let took = started.elapsed();
    let instant = classes(session);
    println!(
        "instant     {} sub-trajectories, coloured on the phone from the walk alone in {:.1} ms: {}{}",
        instant.len(),
        took.as_secs_f64() * 1e3,
        counts(&instant),
        if calibration.informative {
            ""
        } else {
            " (the calibration's runs do not predict their error: colours are a guess)"
        }
    );
    Ok(instant)
}

/// The class of every sub-trajectory of `session` from its loaded results.
pub fn classes(session: &PhoneSession) -> Vec<ErrorClass> {
    session
        .subtrajectories()
        .iter()
        .map(|sub| session.error_at(sub.start_ns).0)
        .collect()
}

/// `3 high, 10 medium, 31 low` (and unknown, if any).
pub fn counts(classes: &[ErrorClass]) -> String {
    let n = |c: ErrorClass| classes.iter().filter(|k| **k == c).count();
    let mut text = format!(
        "{} high, {} medium, {} low",
        n(ErrorClass::High),
        n(ErrorClass::Medium),
        n(ErrorClass::Low)
    );
    if n(ErrorClass::Unknown) > 0 {
        text.push_str(&format!(", {} without an estimate", n(ErrorClass::Unknown)));
    }
    text
}

/// How many sub-trajectories have another class in `after` than in `before`.
pub fn changed(before: &[ErrorClass], after: &[ErrorClass]) -> usize {
    before.iter().zip(after).filter(|(a, b)| a != b).count() + before.len().abs_diff(after.len())
}

/// Where results come from, as their JSON says: `the walk alone`, `the walk and 7 replays`,
/// `7 replays`.
pub fn source_of(results_json: &str) -> String {
    let doc: serde_json::Value = serde_json::from_str(results_json).unwrap_or_default();
    let runs = doc["runs"].as_u64().or(doc["trials"].as_u64()).unwrap_or(0);
    match (doc["source"].as_str(), doc["target"].as_str()) {
        (Some("walk"), _) => "the walk alone".to_string(),
        (_, Some("live")) => format!("the walk and {}", replays(runs.saturating_sub(1))),
        _ => replays(runs),
    }
}

fn replays(n: u64) -> String {
    format!("{n} replay{}", if n == 1 { "" } else { "s" })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The demo with data directory `data` and report file `report` kept the walk and the
    /// calibration in the phone's folder, and its backend published first from the walk alone,
    /// last from the walk and `replays` replays.
    pub(crate) fn assert_started_from_the_walk(data: &std::path::Path, report: &str, replays: u64) {
        let phone = data.join("demo-phone-session");
        assert!(phone.join("walk.txt").is_file() && phone.join("calibration.json").is_file());
        let id = report
            .strip_prefix("report-")
            .and_then(|n| n.strip_suffix(".html"))
            .unwrap();
        let session = data.join("sessions").join(id);
        let text = std::fs::read_to_string(session.join("results.json")).unwrap();
        let results: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(
            (&results["source"], &results["runs"], &results["target"]),
            (
                &serde_json::json!("replays"),
                &serde_json::json!(replays + 1),
                &serde_json::json!("live")
            ),
            "{results}"
        );
        let history = std::fs::read_to_string(session.join("history.jsonl")).unwrap();
        let first: serde_json::Value =
            serde_json::from_str(history.lines().next().unwrap()).unwrap();
        assert_eq!(first["trials"], 1, "the walk alone first: {history}");
    }

    #[test]
    fn sources_counts_and_changes_read_as_the_demo_prints_them() {
        assert_eq!(
            source_of(r#"{"source":"walk","runs":1,"target":"live"}"#),
            "the walk alone"
        );
        assert_eq!(
            source_of(r#"{"source":"replays","runs":8,"target":"live"}"#),
            "the walk and 7 replays"
        );
        assert_eq!(source_of(r#"{"trials":2}"#), "2 replays");
        use ErrorClass::*;
        let before = [High, Low, Low, Medium];
        let after = [High, Medium, Low, Low];
        assert_eq!(changed(&before, &after), 2);
        assert_eq!(counts(&after), "1 high, 1 medium, 2 low");
        assert_eq!(
            counts(&[Unknown, Low]),
            "0 high, 0 medium, 1 low, 1 without an estimate"
        );
    }
}
