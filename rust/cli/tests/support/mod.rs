//! Helpers shared by the real-process tests.

// Each test binary uses the part it needs.
#![allow(dead_code)]

pub mod cluster;
pub mod process;
pub mod sessions;
