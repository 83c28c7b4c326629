//! Helpers shared by the tests that run the built `sitar`.

// Each test binary uses the part it needs.
#![allow(dead_code)]

pub mod cluster;
pub mod process;
pub mod run;
pub mod sessions;
