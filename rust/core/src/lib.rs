//! SiTAR core.
#![forbid(unsafe_code)]
