//! SiTAR estimator.
#![forbid(unsafe_code)]
