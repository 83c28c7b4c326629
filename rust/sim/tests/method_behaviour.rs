//! The method's known failure on trials of the RANSAC tracker: the consistently-wrong scene
//! (the dark wall), where every trial coasts alike on the same IMU data, is under-estimated.

use sitar_estimator::{
    EstimateOptions, EvaluationOptions, Setting, Thresholds, matched_windows, median_ratio,
};
use sitar_sim::{Recording, Trajectory, play_trial};

/// Trials `range` of `rec`, two threads.
fn trials(rec: &Recording, range: std::ops::Range<u32>) -> Vec<Trajectory> {
    let indices: Vec<u32> = range.collect();
    let (first, second) = indices.split_at(indices.len() / 2);
    std::thread::scope(|s| {
        let a = s.spawn(|| {
            first
                .iter()
                .map(|&i| play_trial(rec, i))
                .collect::<Vec<_>>()
        });
        let mut out: Vec<Trajectory> = second.iter().map(|&i| play_trial(rec, i)).collect();
        let mut all = a.join().unwrap();
        all.append(&mut out);
        all
    })
}

#[test]
fn the_consistently_wrong_scene_is_under_estimated() {
    let rec = Recording::dark_wall(15.0, 30.0, 4).unwrap();
    let (a, b) = (trials(&rec, 0..10), trials(&rec, 10..30));
    let opts = EvaluationOptions {
        trial_counts: vec![20],
        settings: vec![Setting::TrimMean(30)],
        boundaries: vec![Thresholds::DEFAULT_M],
        estimate: EstimateOptions::default(),
    };
    let (_, matched) = matched_windows(&rec.walk().ground_truth, &a, &b, &opts).unwrap();
    let m = &matched[0];
    let stamps = &rec.walk().ground_truth.stamps;
    let (mut truth, mut estimate) = (Vec::new(), Vec::new());
    for ((start, t), e) in m.starts.iter().zip(&m.truth).zip(&m.estimate) {
        let mid = stamps.iter().position(|s| s == start).unwrap() + 5;
        if rec.views()[mid].facing.as_deref() == Some("dark wall") {
            truth.push(*t);
            estimate.push(*e);
        }
    }
    assert!(
        truth.len() > 20,
        "{} windows face the dark wall",
        truth.len()
    );
    let ratio = median_ratio(&truth, &estimate).unwrap();
    let mean_truth = truth.iter().sum::<f64>() / truth.len() as f64;
    eprintln!(
        "dark wall: {} windows, true error {mean_truth:.4} m, estimate/truth {ratio:.3}",
        truth.len()
    );
    assert!(ratio < 0.5, "estimate/truth {ratio}");
}
