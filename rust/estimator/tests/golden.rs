//! Compares against golden files made by `scripts/golden/make_goldens.py` with evo, numpy
//! and scipy (see that script for the synthetic data: ns stamps, dropped frames, stamp
//! jitter, a decimal-seconds trial, a different world frame per trial).

use std::path::{Path, PathBuf};

use serde_json::Value;
use sitar_estimator::{
    Alignment, DeltaUnit, EstimateOptions, PairwiseValues, PoseRelation, RpeOptions, Setting,
    Statistics, Trajectory, align, ape, associate_trajectories, read_tum, rpe,
};

const TOLERANCE: f64 = 1e-9;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn load_json(name: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(data(name)).unwrap()).unwrap()
}

fn trajectory(name: &str) -> Trajectory {
    let path = if name == "gt.txt" {
        data(name)
    } else {
        data(&format!("trials/{name}"))
    };
    read_tum(&path).unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn assert_close(what: &str, got: f64, want: f64) {
    assert!(
        (got - want).abs() <= TOLERANCE,
        "{what}: got {got}, evo {want} (diff {})",
        (got - want).abs()
    );
}

fn assert_stats(what: &str, got: Statistics, want: &Value) {
    for (name, value) in [
        ("rmse", got.rmse),
        ("mean", got.mean),
        ("median", got.median),
        ("std", got.std),
        ("min", got.min),
        ("max", got.max),
    ] {
        assert_close(
            &format!("{what} {name}"),
            value,
            want[name].as_f64().unwrap(),
        );
    }
    // sse sums hundreds of squares: compare relatively.
    let sse = want["sse"].as_f64().unwrap();
    assert!(
        (got.sse - sse).abs() <= TOLERANCE * sse.max(1.0),
        "{what} sse {} vs {sse}",
        got.sse
    );
}

#[test]
fn rpe_equals_evo() {
    let cases = load_json("golden_rpe.json");
    let cases = cases.as_array().unwrap();
    assert!(cases.len() >= 72);
    for case in cases {
        let reference = trajectory(case["reference"].as_str().unwrap());
        let estimate = trajectory(case["estimate"].as_str().unwrap());
        let (reference, estimate) = associate_trajectories(
            &reference,
            &estimate,
            case["t_max_diff"].as_f64().unwrap(),
            case["t_offset"].as_f64().unwrap(),
        )
        .unwrap();
        let opts = RpeOptions {
            pose_relation: case["pose_relation"].as_str().unwrap().parse().unwrap(),
            delta: case["delta"].as_f64().unwrap(),
            delta_unit: if case["delta_unit"] == "m" {
                DeltaUnit::Meters
            } else {
                DeltaUnit::Frames
            },
            all_pairs: case["all_pairs"].as_bool().unwrap(),
            ..RpeOptions::default()
        };
        let what = format!(
            "rpe {} {} {:?} {}",
            case["reference"], case["estimate"], opts.delta_unit, opts.pose_relation
        );
        let result = rpe(&reference, &estimate, &opts).unwrap();
        let want = floats(&case["errors"]);
        let end_ids: Vec<usize> = case["end_ids"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap() as usize)
            .collect();
        assert_eq!(
            result.pairs.iter().map(|p| p.1).collect::<Vec<_>>(),
            end_ids,
            "{what}: pairs"
        );
        for (k, (got, want)) in result.errors.iter().zip(&want).enumerate() {
            assert_close(&format!("{what} [{k}]"), *got, *want);
        }
        assert_stats(&what, result.statistics(), &case["stats"]);
    }
}

#[test]
fn ape_equals_evo() {
    let cases = load_json("golden_ape.json");
    let cases = cases.as_array().unwrap();
    assert!(cases.len() >= 140);
    for case in cases {
        let reference = trajectory(case["reference"].as_str().unwrap());
        let estimate = trajectory(case["estimate"].as_str().unwrap());
        let (reference, mut estimate) = associate_trajectories(
            &reference,
            &estimate,
            case["t_max_diff"].as_f64().unwrap(),
            0.0,
        )
        .unwrap();
        let alignment = match case["align"].as_str().unwrap() {
            "none" => Alignment::None,
            "se3" => Alignment::Se3,
            "sim3" => Alignment::Sim3,
            "scale" => Alignment::ScaleOnly,
            "origin" => Alignment::Origin,
            other => panic!("unknown alignment {other}"),
        };
        align(&mut estimate, &reference, alignment).unwrap();
        let relation: PoseRelation = case["pose_relation"].as_str().unwrap().parse().unwrap();
        let what = format!("ape {} {alignment:?} {relation}", case["estimate"]);
        let result = ape(&reference, &estimate, relation).unwrap();
        let want = floats(&case["errors"]);
        assert_eq!(result.errors.len(), want.len(), "{what}");
        for (k, (got, want)) in result.errors.iter().zip(&want).enumerate() {
            assert_close(&format!("{what} [{k}]"), *got, *want);
        }
        assert_stats(&what, result.statistics(), &case["stats"]);
    }
}

fn check_estimate(golden: &str, relation: PoseRelation) {
    let golden = load_json(golden);
    let trials: Vec<Trajectory> = golden["trials"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| trajectory(n.as_str().unwrap()))
        .collect();
    let opts = EstimateOptions {
        delta: golden["delta"].as_u64().unwrap() as usize,
        t_max_diff_s: golden["t_max_diff"].as_f64().unwrap(),
        pose_relation: relation,
        ..EstimateOptions::default()
    };
    let values = PairwiseValues::compute(&trials, &opts).unwrap();
    let settings = golden["settings"].as_object().unwrap();
    assert_eq!(settings.len(), Setting::ALL.len());
    for (name, rows) in settings {
        let setting: Setting = name.parse().unwrap();
        let estimate = values.estimate(setting);
        let rows = rows.as_array().unwrap();
        assert_eq!(estimate.windows.len(), rows.len(), "{name}: window count");
        for (w, row) in estimate.windows.iter().zip(rows) {
            let what = format!("{relation} {name} window {}", w.start);
            assert_eq!(w.start, row[0].as_i64().unwrap(), "{what}: start");
            assert_close(&what, w.error_m, row[1].as_f64().unwrap());
            assert_eq!(w.pairs as u64, row[2].as_u64().unwrap(), "{what}: pairs");
            assert_close(
                &format!("{what} spread"),
                w.spread_m,
                row[3].as_f64().unwrap(),
            );
        }
    }
}

#[test]
fn estimate_equals_evo_and_scipy_for_every_setting() {
    check_estimate("golden_estimate.json", PoseRelation::TranslationPart);
}

#[test]
fn rotational_estimate_equals_evo_and_scipy() {
    check_estimate(
        "golden_estimate_angle_deg.json",
        PoseRelation::RotationAngleDeg,
    );
}

/// Associated trajectories may repeat a stamp (two frames share their nearest match); evo keeps
/// both matches, so the estimate must too.
#[test]
fn estimate_keeps_frames_that_share_a_nearest_stamp() {
    check_estimate(
        "golden_estimate_shared_nearest.json",
        PoseRelation::TranslationPart,
    );
}

#[test]
fn evaluation_protocol_runs_on_the_golden_trials() {
    use sitar_estimator::{EvaluationOptions, PAPER_CLASSIFIERS, evaluate, ground_truth_errors};
    let gt = trajectory("gt.txt");
    let trials: Vec<Trajectory> = (0..8)
        .map(|i| trajectory(&format!("trial_{i:02}.txt")))
        .collect();
    let (a, b) = trials.split_at(4);
    // The ground-truth error of one window equals the mean of the per-trial evo RPEs.
    let truth = ground_truth_errors(&gt, a, &EstimateOptions::default()).unwrap();
    let first = truth[0];
    let mut per_trial = Vec::new();
    for t in a {
        let (g, e) = associate_trajectories(&gt, t, 0.01, 0.0).unwrap();
        let r = rpe(&g, &e, &RpeOptions::default()).unwrap();
        if let Some(k) = r.pairs.iter().position(|&(i, _)| g.stamps[i] == first.0) {
            per_trial.push(r.errors[k]);
        }
    }
    assert_eq!(per_trial.len(), 4);
    assert_close("gt mean", first.1, per_trial.iter().sum::<f64>() / 4.0);
    let opts = EvaluationOptions {
        trial_counts: vec![2, 3, 4, 5],
        ..EvaluationOptions::default()
    };
    let evaluation = evaluate(&gt, a, b, &opts).unwrap();
    assert_eq!(
        evaluation.rows.len(),
        3 * Setting::ALL.len() * PAPER_CLASSIFIERS.len()
    );
    for row in &evaluation.rows {
        let s = row.scores;
        assert!(s.windows > 400, "{row:?}");
        assert!(
            (0.0..=1.0).contains(&s.accuracy) && (0.0..=1.0).contains(&s.macro_f1),
            "{row:?}"
        );
        assert_eq!(s.confusion.iter().flatten().sum::<usize>(), s.windows);
    }
}

#[test]
fn euroc_and_kitti_files_hold_the_same_ground_truth() {
    use sitar_estimator::{read_euroc_csv, read_kitti};
    let tum = trajectory("gt.txt");
    let euroc = read_euroc_csv(&data("gt_euroc.csv")).unwrap();
    assert_eq!(euroc.stamps, tum.stamps);
    assert_eq!(euroc.positions, tum.positions);
    // Same rotation: q or −q, compared componentwise.
    let same = |a: glam::DQuat, b: glam::DQuat, tolerance: f64| {
        (a - b).length().min((a + b).length()) < tolerance
    };
    for (a, b) in euroc.orientations.iter().zip(&tum.orientations) {
        assert!(same(*a, *b, 1e-15));
    }
    let kitti = read_kitti(&data("gt_kitti.txt")).unwrap();
    assert_eq!(kitti.len(), tum.len());
    assert_eq!(kitti.positions, tum.positions);
    for (a, b) in kitti.orientations.iter().zip(&tum.orientations) {
        assert!(same(*a, *b, 1e-12), "{a} vs {b}");
    }
}
