//! Where the computation's messages go. evo prints debug lines, info lines and warnings as
//! it works; the CLI's console prints them as evo does, the Python package drops them
//! ([`Quiet`]) or collects them ([`Collected`]).

use std::sync::Mutex;

use crate::error::Result;

/// A sink for evo's messages by level.
pub trait Messages {
    /// A debug line (evo's `-v`).
    fn debug(&self, text: &str) -> Result<()>;
    /// An info line.
    fn info(&self, text: &str) -> Result<()>;
    /// A warning (`[WARNING] …` on the CLI's stderr).
    fn warn(&self, text: &str);
    /// A note always shown (the CLI's stderr): the offset `--estimate_t_offset` found and the
    /// pairing of `--show_pairing`.
    fn note(&self, text: &str);
}

/// Drops every message.
#[derive(Debug, Default, Clone, Copy)]
pub struct Quiet;

impl Messages for Quiet {
    fn debug(&self, _: &str) -> Result<()> {
        Ok(())
    }
    fn info(&self, _: &str) -> Result<()> {
        Ok(())
    }
    fn warn(&self, _: &str) {}
    fn note(&self, _: &str) {}
}

/// Keeps the warnings and notes (the Python package hands them to `warnings`).
#[derive(Debug, Default)]
pub struct Collected {
    lines: Mutex<Vec<String>>,
}

impl Collected {
    /// The warnings and notes, in order.
    pub fn take(&self) -> Vec<String> {
        self.lines
            .lock()
            .map(|mut lines| std::mem::take(&mut *lines))
            .unwrap_or_default()
    }

    fn push(&self, text: &str) {
        if let Ok(mut lines) = self.lines.lock() {
            lines.push(text.to_owned());
        }
    }
}

impl Messages for Collected {
    fn debug(&self, _: &str) -> Result<()> {
        Ok(())
    }
    fn info(&self, _: &str) -> Result<()> {
        Ok(())
    }
    fn warn(&self, text: &str) {
        self.push(text);
    }
    fn note(&self, text: &str) {
        self.push(text);
    }
}
