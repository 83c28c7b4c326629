//! Ground-truth metrics evo lacks: `sitar drift`, `sitar relative`, and `sitar bench` (with its
//! layout, results, table and plot), and the options they declare alike (`shared_args`).

pub mod bench;
pub mod bench_layout;
pub mod bench_plot;
pub mod bench_results;
pub mod bench_table;
pub mod drift;
pub mod relative;
pub mod shared_args;
