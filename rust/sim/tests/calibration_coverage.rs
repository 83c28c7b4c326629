//! The calibration's interval on simulated sequences it was not fitted on: fitted on six
//! fixed-seed sequences of the RANSAC tracker (5 runs for the truth, 5 for the estimate), its
//! 80 % interval holds the true error of 75–85 % of the windows of four other sequences.

use sitar_estimator::{
    CalibrationSequence, DEFAULT_SMOOTHING_WINDOWS, EstimateOptions, FitOptions, fit_calibration,
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
        let (mut inside, mut total) = (0usize, 0usize);
        for s in held {
            for (f, &truth) in s.features.iter().zip(&s.truth) {
                let (value, lower, upper) = calibration.predict(f);
                assert!(lower <= value && value <= upper);
                inside += usize::from(lower <= truth && truth <= upper);
                total += 1;
            }
        }
        let held_share = inside as f64 / total as f64;
        eprintln!("coverage {coverage}: {inside} of {total} held-out windows ({held_share:.3})");
        assert!(
            (held_share - coverage).abs() <= 0.05,
            "the {coverage} interval holds {held_share:.3} of the held-out windows"
        );
    }
}
