//! Helpers of the instance tests (`serve_instances.rs`).

pub mod serving;
