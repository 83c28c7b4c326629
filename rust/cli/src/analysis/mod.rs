//! SiTAR's analysis: `sitar estimate`, `sitar evaluate`, `sitar calibrate`, `sitar scene`, and
//! the recorded sequences evaluate and calibrate read.

pub mod calibrate;
pub mod estimate;
pub mod evaluate;
pub mod scene;
pub mod sequences;
