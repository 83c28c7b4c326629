//! `sitar`: SiTAR's command-line tool — evo-style trajectory metrics, ground-truth-free
//! pose error estimation, its evaluation, and the simulator.
//!
//! One module per subcommand, each with `Args` (clap) and `run(Args) -> anyhow::Result<()>`;
//! adding a subcommand is one enum variant and one match arm.
#![forbid(unsafe_code)]

mod ape;
mod archive;
mod bag;
mod canvas;
mod compare;
mod config;
mod console;
mod demo;
mod distribution;
mod estimate;
mod evaluate;
mod figure;
mod figures;
mod hints;
mod input;
mod logging;
mod metric;
mod metric_args;
mod output;
mod panels;
mod pdf;
mod plot;
mod pyfmt;
mod res;
mod rpe;
mod scene;
mod serve;
mod shell;
mod simulate;
mod source;
mod token;
mod traj;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// SiTAR: situated trajectory analysis for AR — pose error without ground truth.
///
/// `ape`, `rpe`, `traj` and `res` take evo's command lines (`evo_ape tum REF EST -a` is
/// `sitar ape tum REF EST -a`).
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
    Traj(traj::Args),
    Res(res::Args),
    Completions(shell::CompletionsArgs),
    Man(shell::ManArgs),
    Estimate(estimate::Args),
    Evaluate(evaluate::Args),
    Simulate(simulate::Args),
    Serve(serve::Args),
    Token(token::Args),
    Demo(demo::Args),
    Scene(scene::Args),
}

fn main() -> ExitCode {
    canvas::register_font();
    let argv = match config::expand(
        std::env::args_os().collect(),
        &<Cli as clap::CommandFactory>::command(),
    ) {
        Ok(argv) => argv,
        Err(error) => {
            eprintln!("sitar: error: {}", one_line(&error));
            return ExitCode::FAILURE;
        }
    };
    let command = <Cli as clap::CommandFactory>::command();
    let cli = Cli::try_parse_from(argv)
        .unwrap_or_else(|e| hints::canonical_suggestions(e, &command).exit());
    let result = match cli.command {
        Command::Rpe(args) => rpe::run(args),
        Command::Ape(args) => ape::run(args),
        Command::Traj(args) => traj::run(args),
        Command::Res(args) => res::run(args),
        Command::Completions(args) => {
            shell::completions(args, &mut <Cli as clap::CommandFactory>::command())
        }
        Command::Man(args) => shell::man(args, <Cli as clap::CommandFactory>::command()),
        Command::Estimate(args) => estimate::run(args),
        Command::Evaluate(args) => evaluate::run(args),
        Command::Simulate(args) => simulate::run(args),
        Command::Serve(args) => serve::run(args),
        Command::Token(args) => token::run(args),
        Command::Demo(args) => demo::run(args),
        Command::Scene(args) => scene::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // `sitar … | head`: the reader has gone, which is no error of ours.
        Err(error) if output::is_broken_pipe(&error) => ExitCode::SUCCESS,
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
