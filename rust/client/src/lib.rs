//! SiTAR client.
#![forbid(unsafe_code)]
