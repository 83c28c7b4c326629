//! The paper's observation holds on simulated trials: where the trials disagree most, the
//! true (ground-truth) error is highest, so the pairwise estimate tracks it.

use std::collections::HashMap;

use sitar_estimator::{EstimateOptions, RpeOptions, estimate, rpe};
use sitar_sim::{Recording, play_trial};

/// Mean ground-truth RPE per window start over trials `range` (the paper's set A).
fn true_error(rec: &Recording, range: std::ops::Range<u32>) -> HashMap<i64, f64> {
    let gt = &rec.walk().ground_truth;
    let mut sum: HashMap<i64, (f64, u32)> = HashMap::new();
    for i in range {
        let trial = play_trial(rec, i);
        let errors = rpe(gt, &trial, &RpeOptions::default()).unwrap();
        for (&(start, _), e) in errors.pairs.iter().zip(&errors.errors) {
            let entry = sum.entry(gt.stamps[start]).or_default();
            entry.0 += e;
            entry.1 += 1;
        }
    }
    sum.into_iter()
        .map(|(k, (s, n))| (k, s / f64::from(n)))
        .collect()
}

fn pearson(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let cov: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let vx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let vy: f64 = y.iter().map(|b| (b - my).powi(2)).sum();
    cov / (vx * vy).sqrt()
}

#[test]
fn estimated_uncertainty_correlates_strongly_with_true_error() {
    for seed in [1u64, 2, 3] {
        let rec = Recording::demo(15.0, 30.0, seed).unwrap();
        // Set B: trials 0..20 for the estimate; set A: 20 other trials for the truth.
        let trials: Vec<_> = (0..20).map(|i| play_trial(&rec, i)).collect();
        let est = estimate(&trials, &EstimateOptions::default()).unwrap();
        let truth = true_error(&rec, 100..120);
        let (mut e, mut t) = (vec![], vec![]);
        for w in &est.windows {
            e.push(w.error_m);
            t.push(truth[&w.start]);
        }
        assert_eq!(e.len(), 440);
        let r = pearson(&e, &t);
        assert!(r > 0.8, "seed {seed}: correlation {r}");
        // And the estimate is on the truth's scale (within a factor of 2 on average).
        let ratio = e.iter().sum::<f64>() / t.iter().sum::<f64>();
        assert!((0.5..2.0).contains(&ratio), "seed {seed}: ratio {ratio}");
        eprintln!("seed {seed}: r = {r:.3}, estimate/truth = {ratio:.2}");
    }
}

#[test]
fn the_worst_estimated_windows_face_hard_surfaces() {
    for seed in 10u64..16 {
        let rec = Recording::demo(15.0, 30.0, seed).unwrap();
        let trials: Vec<_> = (0..10).map(|i| play_trial(&rec, i)).collect();
        let est = estimate(&trials, &EstimateOptions::default()).unwrap();
        let stamps = &rec.walk().ground_truth.stamps;
        let mut windows: Vec<_> = est.windows.iter().collect();
        windows.sort_by(|a, b| b.error_m.total_cmp(&a.error_m));
        // The three worst windows at least a second apart, like the app's three markers.
        let mut picked: Vec<i64> = Vec::new();
        for w in windows {
            if picked.iter().all(|&p| (p - w.start).abs() >= 1_000_000_000) {
                picked.push(w.start);
            }
            if picked.len() == 3 {
                break;
            }
        }
        for start in picked {
            // The surface at the image centre in the middle of the window.
            let mid = stamps.iter().position(|&s| s == start).unwrap() + 5;
            let kind = rec.views()[mid].facing_kind.unwrap();
            assert!(
                kind.is_hard(),
                "seed {seed}: window at {start} faces {kind:?}"
            );
        }
    }
}
