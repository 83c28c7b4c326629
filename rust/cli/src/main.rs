//! `sitar`: SiTAR's command-line tool — evo-style trajectory metrics, ground-truth-free
//! pose error estimation, its evaluation, and the simulator.
//!
//! One module per subcommand, each with `Args` (clap) and `run(Args) -> anyhow::Result<()>`;
//! adding a subcommand is one enum variant and one match arm.
#![forbid(unsafe_code)]

mod ape;
mod compare;
mod demo;
mod estimate;
mod evaluate;
mod input;
mod output;
mod plot;
mod rpe;
mod serve;
mod simulate;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// SiTAR: situated trajectory analysis for AR — pose error without ground truth.
#[derive(Parser)]
#[command(name = "sitar", version, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    Rpe(rpe::Args),
    Ape(ape::Args),
    Estimate(estimate::Args),
    Evaluate(evaluate::Args),
    Simulate(simulate::Args),
    Serve(serve::Args),
    Demo(demo::Args),
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Command::Rpe(args) => rpe::run(args),
        Command::Ape(args) => ape::run(args),
        Command::Estimate(args) => estimate::run(args),
        Command::Evaluate(args) => evaluate::run(args),
        Command::Simulate(args) => simulate::run(args),
        Command::Serve(args) => serve::run(args),
        Command::Demo(args) => demo::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("sitar: error: {}", one_line(&error));
            ExitCode::FAILURE
        }
    }
}

/// The cause chain on one line, outermost first, skipping causes an outer message already
/// quotes (many errors print their source themselves).
fn one_line(error: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line.replace('\n', " ")
}
