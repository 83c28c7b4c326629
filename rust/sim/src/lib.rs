//! SiTAR sim.
#![forbid(unsafe_code)]
