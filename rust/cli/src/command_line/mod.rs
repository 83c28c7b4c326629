//! The command line before clap parses it (`config`: older forms and evo's --config) and its
//! usage errors' hints (`hints`).

pub mod config;
pub mod hints;
