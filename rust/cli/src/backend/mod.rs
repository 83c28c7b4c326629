//! The backend: `sitar serve`, `sitar token`, `sitar worker`, `sitar migrate`, and the log setup
//! the server and the worker share.

pub mod logging;
pub mod migrate;
pub mod serve;
pub mod token;
pub mod worker;
