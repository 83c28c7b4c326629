//! # sitar-evo: evo's `ape` and `rpe`, and SiTAR's `drift`, as a library
//!
//! The logic behind `sitar ape|rpe|drift` (which equal evo's `evo_ape`/`evo_rpe` to the last
//! digit), shared by the `sitar` command and the Python package (`import sitar`). In evo's
//! order: read the files ([`read`]), downsample or filter, synchronise by stamps
//! ([`sync`]), align ([`align`]), project, compute and title ([`metric`]); then the JSON
//! document `--format json` prints ([`document`], [`drift`]).
//!
//! Options are plain structs with evo's names and defaults ([`AlgorithmOptions`],
//! [`SyncOptions`], [`DriftSettings`], [`sitar_estimator::RpeOptions`]); messages (evo's
//! debug lines, warnings) go to a [`Messages`] sink: [`Quiet`] drops them. Every failure is
//! an [`Error`] naming the option, file or line; nothing here panics on bad input.
//!
//! ```
//! use sitar_evo::{AlgorithmOptions, FileFormat, Metric, Quiet, SyncOptions};
//! use sitar_estimator::PoseRelation;
//!
//! // A reference and a run 2 cm off in x (TUM: stamp x y z qx qy qz qw).
//! let dir = std::env::temp_dir().join(format!("sitar-evo-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir).unwrap();
//! let tum = |dx: f64| -> String {
//!     (0..20).map(|i| format!("{i}.0 {} {} 0 0 0 0 1\n", 0.1 * i as f64 + dx, 0.05 * (i * i) as f64)).collect()
//! };
//! std::fs::write(dir.join("ground_truth.txt"), tum(0.0)).unwrap();
//! std::fs::write(dir.join("run0.txt"), tum(0.02)).unwrap();
//!
//! let outcomes = sitar_evo::compute_files(
//!     Metric::Ape(PoseRelation::TranslationPart.into()),
//!     FileFormat::Tum,
//!     &dir.join("ground_truth.txt"),
//!     &[dir.join("run0.txt").as_path()],
//!     &SyncOptions::default(),
//!     &AlgorithmOptions::default(), // no alignment: the 2 cm stay
//!     &Quiet,
//! )?;
//! assert!((outcomes[0].stats.rmse - 0.02).abs() < 1e-9);
//! let json = sitar_evo::metric_document(&outcomes); // what `sitar ape --format json` prints
//! assert!(json.to_string().contains("rmse"));
//! # std::fs::remove_dir_all(&dir).ok();
//! # Ok::<(), sitar_evo::Error>(())
//! ```

pub mod align;
pub mod document;
pub mod drift;
pub mod error;
pub mod messages;
pub mod metric;
pub mod options;
pub mod pyfmt;
pub mod read;
pub mod sync;

use std::path::Path;

use sitar_estimator::{DeltaUnit, PoseRelation, RpeOptions};

pub use drift::{DriftOutcome, DriftSettings};
pub use error::{Error, Result};
pub use messages::{Collected, Messages, Quiet};
pub use metric::{ApeRelation, Metric, Outcome};
pub use options::{AlgorithmOptions, ChangeUnit, StampUnit, SyncMethod, SyncOptions};
pub use read::{FileFormat, Loaded, Named};
pub use sync::Pairing;

/// evo's separator line of verbose output.
pub const SEP: &str =
    "--------------------------------------------------------------------------------";

/// evo_rpe's pair options, checked (`delta` a non-negative finite number).
pub fn rpe_options(
    pose_relation: PoseRelation,
    delta: f64,
    delta_unit: DeltaUnit,
    delta_tol: f64,
    all_pairs: bool,
    pairs_from_reference: bool,
) -> Result<RpeOptions> {
    if !(delta >= 0.0 && delta.is_finite()) {
        error::invalid!("delta must be a positive number, got {delta}");
    }
    Ok(RpeOptions {
        pose_relation,
        delta,
        delta_unit,
        all_pairs,
        rel_delta_tol: delta_tol,
        pairs_from_reference,
    })
}

/// Reads the files and computes `metric` for each estimate (repeated runs of one system).
pub fn compute_files(
    metric: Metric,
    format: FileFormat,
    reference: &Path,
    estimates: &[&Path],
    sync: &SyncOptions,
    algorithm: &AlgorithmOptions,
    messages: &dyn Messages,
) -> Result<Vec<Outcome>> {
    read::load_files(format, reference, estimates, sync, messages)?
        .into_iter()
        .map(|loaded| metric::compute(metric, loaded, algorithm, false, messages))
        .collect()
}

/// What `--format json` prints: one run's document, or with several the runs' document.
pub fn metric_document(outcomes: &[Outcome]) -> serde_json::Value {
    match outcomes {
        [one] => document::outcome_json(one),
        several => document::runs_json(several),
    }
}

/// Reads the files and computes the drift of each estimate; with the document
/// `sitar drift --format json` prints.
pub fn drift_files(
    format: FileFormat,
    reference: &Path,
    estimates: &[&Path],
    sync: &SyncOptions,
    settings: &DriftSettings,
    messages: &dyn Messages,
) -> Result<(Vec<DriftOutcome>, serde_json::Value)> {
    let options = settings.options()?;
    let outcomes = read::load_files(format, reference, estimates, sync, messages)?
        .into_iter()
        .map(|loaded| drift::compute_drift(loaded, settings, options.clone(), messages))
        .collect::<Result<Vec<_>>>()?;
    let title = settings.title();
    let doc = match outcomes.as_slice() {
        [one] => one.json(&title, &options),
        several => drift::drift_runs_json(several, &title, &options),
    };
    Ok((outcomes, doc))
}
