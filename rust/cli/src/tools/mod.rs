//! Tools generated from the command line itself: `sitar completions` and `sitar man`.

pub mod completions;
pub mod man;
