//! SiTAR native library.
