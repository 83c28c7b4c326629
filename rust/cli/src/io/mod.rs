//! Reading and writing, shared by every command: trajectories (`source`, `bag`), input files
//! (`input`), output formats (`output`) and evo's console (`console`).

pub mod bag;
pub mod console;
pub mod input;
pub mod output;
pub mod source;
