//! `sitar rpe`: relative pose error, as `evo_rpe`.

use anyhow::Result;
use clap::ValueEnum;
use sitar_estimator::{DeltaUnit, PoseRelation};

use crate::io::console::{Console, UsabilityArgs};
use crate::io::source::{self, format_subcommands};
use crate::results::metric_args::{AlgorithmArgs, OutputArgs, check_supported};
use sitar_evo::metric::{self, Metric};

/// Relative pose error of an estimate against a reference, as evo_rpe.
///
/// The format comes first, as in evo: `sitar rpe tum REF EST -d 10 --all_pairs`. Defaults
/// as evo: delta 1 frame, consecutive pairs, translation part. Several estimates are
/// repeated runs of one system: each run's statistics and their summary over the runs.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar rpe tum ground_truth.txt trajectory_0.txt\n  sitar rpe tum ground_truth.txt trajectory_0.txt -r angle_deg -d 10 --all_pairs --save_results rpe.zip\n  sitar rpe tum gt.txt est.txt -d 1 -u m -a --save_plot rpe.png\n  sitar rpe tum gt.txt run0.txt run1.txt run2.txt -d 10 --save_plot runs.pdf"
)]
pub struct Args {
    #[command(subcommand)]
    source: Format,
}

/// `sitar rpe`'s options: evo_rpe's.
#[derive(clap::Args, Debug)]
pub struct Options {
    /// Pose relation on which the RPE is based.
    #[arg(short = 'r', long = "pose_relation", alias = "pose-relation", default_value = "trans_part", value_parser = parse_relation)]
    pose_relation: PoseRelation,
    /// Delta between relative poses, in --delta_unit.
    #[arg(short = 'd', long, default_value_t = 1.0)]
    delta: f64,
    /// Relative delta tolerance for all_pairs mode.
    #[arg(
        short = 't',
        long = "delta_tol",
        alias = "delta-tol",
        default_value_t = 0.1
    )]
    delta_tol: f64,
    /// Unit of delta: f (frames), d (deg), r (rad), m (metres).
    #[arg(short = 'u', long = "delta_unit", alias = "delta-unit", value_enum, default_value_t = Unit::F)]
    delta_unit: Unit,
    /// Use all pairs instead of consecutive pairs.
    #[arg(long = "all_pairs", alias = "all-pairs")]
    all_pairs: bool,
    /// Determine the pose pairs from the reference trajectory.
    #[arg(long = "pairs_from_reference", alias = "pairs-from-reference")]
    pairs_from_reference: bool,
    #[command(flatten)]
    algorithm: AlgorithmArgs,
    #[command(flatten)]
    output: OutputArgs,
    #[command(flatten)]
    usability: UsabilityArgs,
}

format_subcommands!(Format, Options);

/// evo's `-u f|d|r|m`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Unit {
    /// Frames.
    F,
    /// Degrees.
    D,
    /// Radians.
    R,
    /// Metres of travelled path.
    M,
}

fn parse_relation(s: &str) -> Result<PoseRelation, String> {
    s.parse().map_err(|_| {
        format!(
            "invalid choice: '{s}' (choose from 'full', 'trans_part', 'rot_part', 'angle_deg', 'angle_rad', 'point_distance', 'point_distance_error_ratio')"
        )
    })
}

pub fn run(args: Args) -> Result<()> {
    let (source, options) = args.source.split();
    let console = Console::new(&options.usability)?;
    check_supported(&options.output)?;
    let rpe = sitar_evo::rpe_options(
        options.pose_relation,
        options.delta,
        match options.delta_unit {
            Unit::F => DeltaUnit::Frames,
            Unit::D => DeltaUnit::Degrees,
            Unit::R => DeltaUnit::Radians,
            Unit::M => DeltaUnit::Meters,
        },
        options.delta_tol,
        options.all_pairs,
        options.pairs_from_reference,
    )?;
    let runs = source::load(&source, &console)?;
    let algorithm = options.algorithm.options();
    let outcomes = runs
        .into_iter()
        .map(|loaded| {
            metric::compute(
                Metric::Rpe(rpe),
                loaded,
                &algorithm,
                options.output.plot_full_ref,
                &console,
            )
        })
        .collect::<sitar_evo::Result<Vec<_>>>()?;
    match outcomes.as_slice() {
        [one] => crate::results::compare::finish(one, &options.output, &console),
        several => crate::results::runs::finish(several, &options.output, &console),
    }
}
