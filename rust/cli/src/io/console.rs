//! evo's console: results and info on stdout, warnings and errors on stderr, debug lines
//! with `-v`/`--debug`, nothing but warnings with `--silent`, no warnings with
//! `--no_warnings`, and every line also in `--logfile`.

use std::fs::File;
use std::io::Write;
use std::path::PathBuf;
use std::sync::Mutex;

use anyhow::{Context, Result};

/// evo's separator line of verbose output.
pub use sitar_evo::SEP;

/// evo's usability options, shared by `ape`, `rpe`, `traj` and `res`.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct UsabilityArgs {
    /// No warnings (evo: no confirmation prompts; sitar never prompts and overwrites).
    #[arg(long = "no_warnings", alias = "no-warnings")]
    pub no_warnings: bool,
    /// Verbose output.
    #[arg(short = 'v', long)]
    pub verbose: bool,
    /// Don't print any output (results files are still written; warnings still shown).
    #[arg(long)]
    pub silent: bool,
    /// Verbose output with additional debug info.
    #[arg(long)]
    pub debug: bool,
    /// Local logfile path: every message is appended to it.
    #[arg(long, value_name = "FILE")]
    pub logfile: Option<PathBuf>,
    /// .json file with parameters (priority over command line args; read before parsing).
    #[arg(short = 'c', long, value_name = "FILE.json")]
    pub config: Option<PathBuf>,
}

/// Where messages go, by level.
pub struct Console {
    verbose: bool,
    silent: bool,
    no_warnings: bool,
    logfile: Option<Mutex<File>>,
}

impl Console {
    /// The console for these options; opens (appends to) the logfile.
    pub fn new(args: &UsabilityArgs) -> Result<Self> {
        let logfile = match &args.logfile {
            Some(path) => Some(Mutex::new(
                std::fs::OpenOptions::new()
                    .create(true)
                    .append(true)
                    .open(path)
                    .with_context(|| format!("{}: cannot open the logfile", path.display()))?,
            )),
            None => None,
        };
        Ok(Self {
            verbose: args.verbose || args.debug,
            silent: args.silent,
            no_warnings: args.no_warnings,
            logfile,
        })
    }

    fn log(&self, level: &str, text: &str) {
        if let Some(file) = &self.logfile
            && let Ok(mut file) = file.lock()
        {
            let _ = writeln!(file, "[{level}] {text}");
        }
    }

    /// A result or info line on stdout (not with `--silent`).
    pub fn info(&self, text: &str) -> Result<()> {
        self.log("INFO", text);
        if self.silent {
            return Ok(());
        }
        crate::io::output::print(&format!("{text}\n"))
    }

    /// A debug line on stdout, only with `-v`/`--debug`.
    pub fn debug(&self, text: &str) -> Result<()> {
        self.log("DEBUG", text);
        if !self.verbose || self.silent {
            return Ok(());
        }
        crate::io::output::print(&format!("{text}\n"))
    }

    /// A warning on stderr as evo writes it (`[WARNING] …`), unless `--no_warnings`.
    pub fn warn(&self, text: &str) {
        self.log("WARNING", text);
        if !self.no_warnings {
            eprintln!("[WARNING] {text}");
        }
    }

    /// True with `-v`/`--debug`.
    pub fn is_verbose(&self) -> bool {
        self.verbose
    }
}

/// The library's messages go where evo prints them; a failed write is the same error the
/// console's own lines give (the chain still ends in the I/O error, so a closed pipe ends
/// `sitar` quietly).
impl sitar_evo::Messages for Console {
    fn debug(&self, text: &str) -> sitar_evo::Result<()> {
        Console::debug(self, text).map_err(to_library)
    }

    fn info(&self, text: &str) -> sitar_evo::Result<()> {
        Console::info(self, text).map_err(to_library)
    }

    fn warn(&self, text: &str) {
        Console::warn(self, text);
    }

    fn note(&self, text: &str) {
        eprintln!("{text}");
    }
}

/// A console error (stdout could not be written) as the library's.
fn to_library(error: anyhow::Error) -> sitar_evo::Error {
    match error.downcast::<std::io::Error>() {
        Ok(io) => sitar_evo::Error::Output(io),
        Err(other) => sitar_evo::Error::Invalid(format!("{other:#}")),
    }
}
