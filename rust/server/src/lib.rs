//! SiTAR server.
#![forbid(unsafe_code)]
