//! The `sitar` binary: the command line of [`sitar_cli::main_with`].
#![forbid(unsafe_code)]

use std::process::ExitCode;

fn main() -> ExitCode {
    sitar_cli::main_with(std::env::args_os().collect())
}
