//! `sitar ape`: absolute pose error, as `evo_ape`.

use anyhow::Result;
use sitar_estimator::{DirectionRelation, PoseRelation};

use crate::io::console::{Console, UsabilityArgs};
use crate::io::source::{self, format_subcommands};
use crate::results::metric_args::{AlgorithmArgs, OutputArgs, check_supported};
use sitar_evo::metric::{self, ApeRelation, Metric};

/// Absolute pose error of an estimate against a reference, as evo_ape.
///
/// The format comes first, as in evo: `sitar ape tum REF EST -a` (euroc: EuRoC ground
/// truth and a TUM estimate; kitti: KITTI poses). Prints evo's title and statistics table.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar ape tum ground_truth.txt trajectory_0.txt -a\n  sitar ape euroc data.csv estimate.tum -a -s --save_results ape.zip --save_plot ape.pdf\n  sitar ape kitti 00.txt 00_est.txt -r angle_deg -p\n  sitar ape tum gt.txt run0.txt run1.txt run2.txt -a --format json -o runs.json"
)]
pub struct Args {
    #[command(subcommand)]
    source: Format,
}

/// `sitar ape`'s options: evo_ape's.
#[derive(clap::Args, Debug)]
pub struct Options {
    /// Pose relation on which the APE is based. SiTAR extras: along_track, cross_track,
    /// vertical (|translation error| along the reference's heading, across it, along the
    /// gravity axis of --yaw_axis, m), yaw_deg and roll_pitch_deg (the rotation error's
    /// twist about the gravity axis and its swing, deg).
    #[arg(short = 'r', long = "pose_relation", alias = "pose-relation", default_value = "trans_part", value_parser = parse_relation)]
    pose_relation: ApeRelation,
    #[command(flatten)]
    algorithm: AlgorithmArgs,
    #[command(flatten)]
    output: OutputArgs,
    #[command(flatten)]
    usability: UsabilityArgs,
}

format_subcommands!(Format, Options);

fn parse_relation(s: &str) -> Result<ApeRelation, String> {
    if let Ok(d) = s.parse::<DirectionRelation>() {
        return Ok(ApeRelation::Direction(d));
    }
    match s.parse() {
        Ok(PoseRelation::PointDistanceErrorRatio) | Err(_) => Err(format!(
            "invalid choice: '{s}' (choose from 'full', 'trans_part', 'rot_part', 'angle_deg', 'angle_rad', 'point_distance', or SiTAR's 'along_track', 'cross_track', 'vertical', 'yaw_deg', 'roll_pitch_deg')"
        )),
        Ok(r) => Ok(ApeRelation::Evo(r)),
    }
}

pub fn run(args: Args) -> Result<()> {
    let (source, options) = args.source.split();
    let console = Console::new(&options.usability)?;
    check_supported(&options.output)?;
    let runs = source::load(&source, &console)?;
    let algorithm = options.algorithm.options();
    let outcomes = runs
        .into_iter()
        .map(|loaded| {
            metric::compute(
                Metric::Ape(options.pose_relation),
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
