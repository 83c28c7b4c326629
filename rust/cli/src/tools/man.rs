//! `sitar man`: generated from the clap definitions (clap_mangen), so it never drifts from
//! the flags.

use std::path::PathBuf;

use anyhow::{Context, Result};

/// Prints sitar's man page (roff), or writes one page per command into a directory.
#[derive(clap::Args, Debug)]
pub struct ManArgs {
    /// Write sitar.1 and sitar-COMMAND.1 for every command into this directory instead.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

pub fn man(args: ManArgs, command: clap::Command) -> Result<()> {
    match args.out {
        None => {
            let mut out = Vec::new();
            clap_mangen::Man::new(command)
                .render(&mut out)
                .context("cannot render the man page")?;
            crate::io::output::print(&String::from_utf8_lossy(&out))
        }
        Some(dir) => {
            std::fs::create_dir_all(&dir)
                .with_context(|| format!("{}: cannot create", dir.display()))?;
            clap_mangen::generate_to(command, &dir)
                .with_context(|| format!("{}: cannot write the man pages", dir.display()))
        }
    }
}
