//! `sitar ape`: absolute pose error, as evo_ape.

use anyhow::{Context, Result};
use sitar_estimator::ape;

use crate::compare::{PairArgs, result_json};
use crate::output::{OutputFormat, emit};

/// Absolute pose error of EST against REF, as evo_ape.
///
/// Writes CSV `t,error` or JSON with the statistics. Trials live in their own world frame: use --align (or --align-origin).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example: sitar ape ground_truth.txt trials/trajectory_0.txt --align --format json"
)]
pub struct Args {
    #[command(flatten)]
    pair: PairArgs,
}

pub fn run(args: Args) -> Result<()> {
    let prepared = args.pair.prepare()?;
    let errors = ape(
        &prepared.reference,
        &prepared.estimate,
        args.pair.pose_relation,
    )
    .context("computing the APE")?;
    let reference = &prepared.reference;
    let text = match args.pair.format {
        OutputFormat::Csv => {
            let mut out = String::with_capacity(32 * (errors.errors.len() + 1));
            out.push_str("t,error\n");
            for (&(i, _), e) in errors.pairs.iter().zip(&errors.errors) {
                out.push_str(&format!(
                    "{},{e}\n",
                    reference.time_unit.format_stamp(reference.stamps[i])
                ));
            }
            out
        }
        OutputFormat::Json => {
            result_json(
                "ape",
                &args.pair,
                &prepared,
                &errors,
                serde_json::Map::new(),
            ) + "\n"
        }
    };
    emit(args.pair.output.as_deref(), &text)
}
