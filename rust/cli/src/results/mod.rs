//! A metric's result, shared by the metric commands: the output options (`metric_args`), one
//! result's output (`compare`), repeated runs (`runs`) and evo's result archive (`archive`).

pub mod archive;
pub mod compare;
pub mod metric_args;
pub mod runs;
