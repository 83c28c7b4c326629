//! evo's commands on evo's command lines: `sitar ape`, `sitar rpe`, `sitar traj`, `sitar res`.

pub mod ape;
pub mod res;
pub mod rpe;
pub mod traj;
