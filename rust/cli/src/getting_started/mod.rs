//! Getting started: `sitar demo` (with the venue it builds) and `sitar simulate`.

pub mod demo;
pub mod demo_venue;
pub mod demo_walk;
pub mod simulate;
