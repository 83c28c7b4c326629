//! A metric's result, shared by the metric commands: the output options (`metric_args`), one
//! result's output (`compare`), repeated runs (`runs`), evo's result archive (`archive`) and
//! evo's metric figures drawn from it (`error_figures`).

pub mod archive;
pub mod compare;
pub mod error_figures;
pub mod metric_args;
pub mod runs;
