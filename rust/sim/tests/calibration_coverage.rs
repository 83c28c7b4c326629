//! The calibration's interval on simulated sequences it was not fitted on: fitted on six
//! fixed-seed sequences of the RANSAC tracker (5 runs for the truth, 5 for the estimate), the
//! 80 % and 90 % intervals of each of its models (a live run alone, a live run with replays,
//! the expected error) hold the true error of their windows of four other sequences within
//! 7 points of their coverage (a conformal interval fitted on six sequences holds its
//! coverage on new ones only as well as those six stand for them).

use sitar_estimator::{
    CalibrationSequence, DEFAULT_SMOOTHING_WINDOWS, EstimateOptions, FitOptions, MODELS,
    fit_calibration,
};
use sitar_sim::{Recording, Tracker, Trajectory, play_trial};

const SEED: u64 = 7;

fn sequence(index: u32) -> CalibrationSequence {
    let rec = Recording::sequence(index, 20.0, 30.0, SEED, Tracker::Ransac).unwrap();
    let runs: Vec<Trajectory> = (0..10).map(|i| play_trial(&rec, i)).collect();
    CalibrationSequence::new(
        &format!("sim {index}"),
        &rec.walk().ground_truth,
        &runs[..5],
        &runs[5..],
        &EstimateOptions::default(),
        DEFAULT_SMOOTHING_WINDOWS,
    )
    .unwrap()
}

#[test]
fn the_interval_holds_its_coverage_on_held_out_sequences() {
    let all: Vec<CalibrationSequence> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..10u32).map(|i| s.spawn(move || sequence(i))).collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let (train, held) = all.split_at(6);
    for coverage in [0.8, 0.9] {
        let calibration = fit_calibration(
            train,
            &FitOptions {
                coverage,
                ..FitOptions::default()
            },
        )
        .unwrap();
        for (target, runs) in MODELS {
            let model = calibration
                .model(target, if runs.name() == "one" { 1 } else { 5 })
                .unwrap();
            let (mut inside, mut total) = (0usize, 0usize);
            for s in held {
                let windows = s.windows(target);
                for (f, &truth) in windows.features.iter().zip(&windows.truth) {
                    let p = model.predict(f);
                    assert!(p.lower <= p.value && p.value <= p.upper);
                    inside += usize::from(p.lower <= truth && truth <= p.upper);
                    total += 1;
                }
            }
            let held_share = inside as f64 / total as f64;
            let name = format!("{} from {}", target.name(), runs.name());
            eprintln!(
                "{name}, coverage {coverage}: {inside} of {total} held-out windows ({held_share:.3})"
            );
            assert!(
                (held_share - coverage).abs() <= 0.07,
                "{name}: the {coverage} interval holds {held_share:.3} of the held-out windows"
            );
        }
    }
}
