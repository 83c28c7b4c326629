//! `sitar`: SiTAR's command-line tool — evo-style trajectory metrics, ground-truth-free
//! pose error estimation, its evaluation, and the simulator.
//!
//! One module per subcommand, each with `Args` (clap) and `run(Args) -> anyhow::Result<()>`;
//! adding a subcommand is one enum variant and one match arm. The binary (`main.rs`) and the
//! Python package's `sitar` command both call [`main_with`].
//!
//! `src/` follows `sitar --help`'s groups (`GROUPS` below): a folder per group, holding its
//! commands and the helpers only they use.
//! - `getting_started/`: demo (and the venue it builds), simulate;
//! - `backend/`: serve, token, worker, migrate, and the log they share;
//! - `evo/`: ape, rpe, traj, res;
//! - `beyond_evo/`: drift, relative, bench (its results tree, table and plots), and the
//!   options they declare alike;
//! - `analysis/`: estimate, evaluate, calibrate, scene, and the sequences they read;
//! - `tools/`: completions, man.
//!
//! Shared by several groups:
//! - `figures/`: the figure model, its drawing and its files (PNG, SVG, PDF, HTML pages);
//! - `results/`: a metric's output options, its output, repeated runs, evo's result archive
//!   and evo's metric figures drawn from it;
//! - `io/`: trajectories and input files in, output formats out, evo's console;
//! - `command_line/`: the command line before clap parses it, and its usage hints.
//!
//! The workspace's `tests/tests/cli_layout.rs` keeps it so (each command in its group's
//! folder, no file over 600 lines, the figures below what draws them), and
//! `tests/tests/layout.rs` finds no import cycle among its files or its folders.
//!
//! Every command's `--help` is in the user guide's reference (`docs/src/reference/cli/`),
//! generated from these definitions by `rust/cli/tests/docs_reference.rs`; how to use the
//! commands: the guide's "For SLAM researchers" and "Running the backend" parts.
//!
//! ```
//! use std::process::ExitCode;
//!
//! // What `sitar --version` and the Python package's `sitar` command run.
//! let code = sitar_cli::main_with(vec!["sitar".into(), "--version".into()]);
//! assert_eq!(code, ExitCode::SUCCESS);
//! let code = sitar_cli::main_with(vec!["sitar".into(), "no-such-command".into()]);
//! assert_ne!(code, ExitCode::SUCCESS);
//! ```
#![forbid(unsafe_code)]
// Without `full` (the wheel's command) some helpers of the left-out commands go unused.
#![cfg_attr(not(feature = "full"), allow(dead_code))]

#[cfg(feature = "full")]
mod analysis;
#[cfg(feature = "full")]
mod backend;
mod beyond_evo;
mod command_line;
mod evo;
mod figures;
#[cfg(feature = "full")]
mod getting_started;
mod io;
mod results;
mod tools;

use std::process::ExitCode;

use clap::{FromArgMatches, Parser, Subcommand};

#[cfg(feature = "full")]
use analysis::{calibrate, estimate, evaluate, scene};
#[cfg(feature = "full")]
use backend::{migrate, serve, token, worker};
use beyond_evo::{bench, drift, relative};
use command_line::{config, hints};
use evo::{ape, res, rpe, traj};
#[cfg(feature = "full")]
use getting_started::{demo, simulate};
use tools::{completions, man};

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
    Drift(drift::Args),
    Relative(relative::Args),
    Bench(bench::Args),
    Completions(completions::CompletionsArgs),
    Man(man::ManArgs),
    #[cfg(feature = "full")]
    Estimate(estimate::Args),
    #[cfg(feature = "full")]
    Evaluate(evaluate::Args),
    #[cfg(feature = "full")]
    Calibrate(calibrate::Args),
    #[cfg(feature = "full")]
    Simulate(simulate::Args),
    #[cfg(feature = "full")]
    Serve(serve::Args),
    #[cfg(feature = "full")]
    Token(token::Args),
    #[cfg(feature = "full")]
    Worker(worker::Args),
    #[cfg(feature = "full")]
    Migrate(migrate::Args),
    #[cfg(feature = "full")]
    Demo(demo::Args),
    #[cfg(feature = "full")]
    Scene(scene::Args),
}

/// The commands of `sitar --help`, by what a person comes for (a test checks that every
/// command is in exactly one group).
#[cfg(feature = "full")]
const GROUPS: &[(&str, &[&str])] = &[
    ("Getting started", &["demo", "simulate"]),
    (
        "Backend (the server phones talk to)",
        &["serve", "token", "worker", "migrate"],
    ),
    (
        "evo-compatible (evo's command lines)",
        &["ape", "rpe", "traj", "res"],
    ),
    (
        "Beyond evo (ground-truth metrics evo lacks)",
        &["drift", "relative", "bench"],
    ),
    (
        "SiTAR analysis",
        &["estimate", "evaluate", "calibrate", "scene"],
    ),
    ("Tools", &["completions", "man", "help"]),
];

/// The commands without the `full` feature (the Python wheel's `sitar`).
#[cfg(not(feature = "full"))]
const GROUPS: &[(&str, &[&str])] = &[
    (
        "evo-compatible (evo's command lines)",
        &["ape", "rpe", "traj", "res"],
    ),
    (
        "Beyond evo (ground-truth metrics evo lacks)",
        &["drift", "relative", "bench"],
    ),
    ("Tools", &["completions", "man", "help"]),
];

/// The first sentence of a command's about (up to a colon or a full stop).
fn short_about(about: &str) -> &str {
    let end = about
        .find(": ")
        .into_iter()
        .chain(about.find(". "))
        .min()
        .unwrap_or(about.len());
    about[..end].trim_end_matches('.')
}

/// The command line, its top-level help listing the commands in [`GROUPS`].
fn cli() -> clap::Command {
    let command = <Cli as clap::CommandFactory>::command();
    let width = GROUPS
        .iter()
        .flat_map(|(_, names)| names.iter().map(|n| n.len()))
        .max()
        .unwrap_or(0);
    let mut list = String::new();
    for (title, names) in GROUPS {
        list.push_str(&format!("{title}:\n"));
        for name in *names {
            let about = command
                .find_subcommand(name)
                .and_then(|c| c.get_about())
                .map(|a| a.to_string())
                .unwrap_or_else(|| "Prints this message or the help of the given command".into());
            list.push_str(&format!("  {name:width$}  {}\n", short_about(&about)));
        }
        list.push('\n');
    }
    // Braces are the template's own syntax; the abouts have none (checked by a test).
    command.help_template(format!(
        "{{before-help}}{{about-with-newline}}\n{{usage-heading}} {{usage}}\n\n{list}\
         Options:\n{{options}}{{after-help}}"
    ))
}

/// Runs `sitar` on a command line (`argv[0]` first), as the binary does: parses, runs the
/// command, prints errors; returns the exit code (clap's `--help`/usage errors exit here).
pub fn main_with(args: Vec<std::ffi::OsString>) -> ExitCode {
    figures::canvas::register_font();
    let argv = match config::expand(args, &cli()) {
        Ok(argv) => argv,
        Err(error) => {
            eprintln!("sitar: error: {}", one_line(&error));
            return ExitCode::FAILURE;
        }
    };
    let command = cli();
    let matches = command
        .clone()
        .try_get_matches_from(argv)
        .unwrap_or_else(|e| hints::canonical_suggestions(e, &command).exit());
    let parsed = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let result = match parsed.command {
        Command::Rpe(args) => rpe::run(args),
        Command::Ape(args) => ape::run(args),
        Command::Traj(args) => traj::run(args),
        Command::Res(args) => res::run(args),
        Command::Drift(args) => drift::run(args),
        Command::Relative(args) => relative::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Completions(args) => completions::completions(args, &mut cli()),
        Command::Man(args) => man::man(args, cli()),
        #[cfg(feature = "full")]
        Command::Estimate(args) => estimate::run(args),
        #[cfg(feature = "full")]
        Command::Evaluate(args) => evaluate::run(args),
        #[cfg(feature = "full")]
        Command::Calibrate(args) => calibrate::run(args),
        #[cfg(feature = "full")]
        Command::Simulate(args) => simulate::run(args),
        #[cfg(feature = "full")]
        Command::Serve(args) => serve::run(args),
        #[cfg(feature = "full")]
        Command::Token(args) => token::run(args),
        #[cfg(feature = "full")]
        Command::Worker(args) => worker::run(args),
        #[cfg(feature = "full")]
        Command::Migrate(args) => migrate::run(args),
        #[cfg(feature = "full")]
        Command::Demo(args) => demo::run(args),
        #[cfg(feature = "full")]
        Command::Scene(args) => scene::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // `sitar … | head`: the reader has gone, which is no error of ours.
        Err(error) if io::output::is_broken_pipe(&error) => ExitCode::SUCCESS,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[cfg(feature = "full")]
    fn the_help_lists_every_command_once_in_its_group() {
        let mut command = cli();
        command.build();
        let mut names: Vec<&str> = command.get_subcommands().map(|c| c.get_name()).collect();
        names.sort_unstable();
        let mut grouped: Vec<&str> = GROUPS.iter().flat_map(|(_, n)| n.iter().copied()).collect();
        grouped.sort_unstable();
        assert_eq!(grouped, names);
        let help = command.render_help().to_string();
        let at = |text: &str| help.find(text).unwrap_or_else(|| panic!("{text}: {help}"));
        assert!(at("Getting started:") < at("  demo "));
        assert!(at("  demo ") < at("Backend"));
        assert!(at("Backend") < at("  serve ") && at("  serve ") < at("evo-compatible"));
        assert!(at("  ape ") < at("SiTAR analysis:") && at("  estimate ") < at("Tools:"));
        assert!(
            help.contains("  serve        Runs the SiTAR backend\n"),
            "{help}"
        );
        assert!(at("Options:") > at("  man "));
        assert!(!help.contains("Commands:"), "{help}");
        for sub in command.get_subcommands() {
            let about = sub.get_about().map(|a| a.to_string()).unwrap_or_default();
            assert!(!about.contains('{') && !about.contains('}'), "{about}");
        }
    }
}
