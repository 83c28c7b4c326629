//! What `sitar bench` computes: per algorithm and sequence, every run's numbers (the table
//! and the plots read them; `bench.rs` fills them).

use std::path::PathBuf;

use sitar_estimator::RelativeAtLength;

use crate::beyond_evo::bench_layout::Cell;

/// How the sub-trajectory lengths are chosen.
#[derive(Debug, Clone, PartialEq)]
pub enum Lengths {
    Metres(Vec<f64>),
    Percent(Vec<f64>),
}

/// One run's numbers.
pub struct RunResult {
    pub file: PathBuf,
    pub pairs: usize,
    pub scale: f64,
    pub ape_rmse: f64,
    pub relative: Vec<RelativeAtLength>,
    /// KITTI drift over every segment (%, deg/m); none when no segment fits.
    pub drift: Option<(f64, f64)>,
}

/// One cell: an algorithm on a sequence, every run.
pub struct CellResult {
    pub cell: Cell,
    pub lengths_m: Vec<f64>,
    pub runs: Vec<RunResult>,
}

/// What `bench` computes, for the table.
pub struct Bench {
    pub lengths: Lengths,
    pub cells: Vec<CellResult>,
}
