//! The library's API on small files: a computed document, and errors that name the file,
//! line and option instead of panicking.

use std::io::Write;
use std::path::{Path, PathBuf};

use sitar_estimator::PoseRelation;
use sitar_evo::{AlgorithmOptions, DriftSettings, FileFormat, Metric, Quiet, SyncOptions};

/// A TUM reference (a circle, 120 poses) and the estimate shifted by (1, -0.5, 0).
fn pair(dir: &Path) -> (PathBuf, PathBuf) {
    let (r, e) = (dir.join("ref.txt"), dir.join("est.txt"));
    let (mut rf, mut ef) = (
        std::fs::File::create(&r).unwrap(),
        std::fs::File::create(&e).unwrap(),
    );
    for i in 0..120 {
        let (t, a) = (10.0 + 0.1 * f64::from(i), 0.05 * f64::from(i));
        let (x, y, qz, qw) = (
            2.0 * a.cos(),
            2.0 * a.sin(),
            (a / 2.0).sin(),
            (a / 2.0).cos(),
        );
        writeln!(rf, "{t:.3} {x} {y} 0 0 0 {qz} {qw}").unwrap();
        writeln!(ef, "{t:.3} {} {} 0 0 0 {qz} {qw}", x + 1.0, y - 0.5).unwrap();
    }
    (r, e)
}

#[test]
fn ape_with_alignment_removes_a_shift_and_the_document_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let (r, e) = pair(dir.path());
    let ape = Metric::Ape(PoseRelation::TranslationPart.into());
    let raw = sitar_evo::compute_files(
        ape,
        FileFormat::Tum,
        &r,
        &[&e],
        &SyncOptions::default(),
        &AlgorithmOptions::default(),
        &Quiet,
    )
    .unwrap();
    assert!((raw[0].stats.rmse - 1.25f64.sqrt()).abs() < 1e-9);
    let aligned = AlgorithmOptions {
        align: true,
        ..Default::default()
    };
    let out = sitar_evo::compute_files(
        ape,
        FileFormat::Tum,
        &r,
        &[&e],
        &SyncOptions::default(),
        &aligned,
        &Quiet,
    )
    .unwrap();
    assert!(out[0].stats.rmse < 1e-9, "{}", out[0].stats.rmse);
    let doc = sitar_evo::metric_document(&out);
    assert_eq!(doc["alignment"], "se3");
    assert_eq!(doc["errors"].as_array().unwrap().len(), 120);
    assert_eq!(doc["pairing"]["paired"], 120);
}

#[test]
fn bad_inputs_are_errors_naming_file_line_or_option() {
    let dir = tempfile::tempdir().unwrap();
    let (r, _) = pair(dir.path());
    let bad = dir.path().join("bad.txt");
    std::fs::write(&bad, "1 0 0 0 0 0 0 1\n2 0 x 0 0 0 0 1\n").unwrap();
    let ape = Metric::Ape(PoseRelation::TranslationPart.into());
    let error = sitar_evo::compute_files(
        ape,
        FileFormat::Tum,
        &r,
        &[&bad],
        &SyncOptions::default(),
        &AlgorithmOptions::default(),
        &Quiet,
    )
    .unwrap_err();
    assert!(
        error
            .chain_text()
            .contains(&format!("{}:2:", bad.display())),
        "{}",
        error.chain_text()
    );
    let n0 = AlgorithmOptions {
        align: true,
        n_to_align: 0,
        ..Default::default()
    };
    let error = sitar_evo::compute_files(
        ape,
        FileFormat::Tum,
        &r,
        &[&r],
        &SyncOptions::default(),
        &n0,
        &Quiet,
    )
    .unwrap_err();
    assert!(
        error.chain_text().contains("--n_to_align must be -1"),
        "{}",
        error.chain_text()
    );
    assert!(FileFormat::from_name("tumm").is_err());
    let slow = DriftSettings {
        speed_step: 0.0,
        ..Default::default()
    };
    let error = sitar_evo::drift_files(
        FileFormat::Tum,
        &r,
        &[&r],
        &SyncOptions::default(),
        &slow,
        &Quiet,
    )
    .unwrap_err();
    assert!(error.to_string().contains("--speed_step"), "{error}");
}
