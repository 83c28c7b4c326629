//! `sitar completions bash|zsh|fish|…`: generated from the clap definitions (clap_complete),
//! so it never drifts from the flags.

use anyhow::Result;

/// Prints a shell completion script for sitar.
///
/// bash: `sitar completions bash > /etc/bash_completion.d/sitar`; zsh: into a directory of
/// $fpath as `_sitar`; fish: `~/.config/fish/completions/sitar.fish`.
#[derive(clap::Args, Debug)]
pub struct CompletionsArgs {
    /// The shell.
    #[arg(value_enum)]
    shell: clap_complete::Shell,
}

pub fn completions(args: CompletionsArgs, command: &mut clap::Command) -> Result<()> {
    let mut out = Vec::new();
    clap_complete::generate(args.shell, command, "sitar", &mut out);
    crate::io::output::print(&String::from_utf8_lossy(&out))
}
