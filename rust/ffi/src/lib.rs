//! # sitar-ffi — the native library the AR apps load (`libsitar.so`)
//!
//! One safe Rust API (the functions re-exported here from the bridge,
//! returning `Result`) wraps [`sitar_core::Session`] and `sitar-client`.
//! Two thin layers expose it:
//!
//! - the **C ABI** (`sitar_*` functions, header `include/sitar.h`, C# bindings
//!   `unity-plugin/Runtime/NativeMethods.g.cs`) used by Unity, and
//! - **JNI** entry points `Java_io_github_sitar_Native_*` used by the Kotlin
//!   library in `android/` (`Native.kt`).
//!
//! Both are made from one declaration per export (`src/exports.rs`, the `exports!` macro
//! of `src/exports_macro.rs`), which also describes each entry point ([`C_EXPORTS`],
//! [`JNI_EXPORTS`], [`FLAT_LAYOUTS`]) so that the header, the C# bindings, `Native.kt`, the
//! Kotlin array layouts and the Kotlin and C# status enums are generated from the same
//! place (`tests/generated_bindings.rs`, which fails when a committed file differs).
//!
//! Every entry point goes through one guard: panics are caught, errors become
//! a [`SitarStatus`] code (C) or a `SitarException` (Kotlin), and the message
//! is kept as the calling thread's last error (`sitar_last_error`). Objects
//! are reached through handles — ids in a registry, never pointers — so a
//! NULL, freed or garbage handle is `SITAR_ERR_INVALID_HANDLE`, not undefined
//! behaviour. Each session sits behind its own mutex, so it may be used from
//! several threads; the frame path neither allocates nor blocks (an
//! uncontended lock).
//!
//! ```
//! use sitar::{session_frame, session_free, session_new, session_start, SitarPose};
//!
//! let h = session_new("{}").unwrap();
//! let pose = SitarPose { qw: 1.0, ..SitarPose::default() };
//! session_start(h, 0, &pose).unwrap();
//! let flags = session_frame(h, 33_000_000, &pose).unwrap();
//! assert_eq!(flags, 0); // frame 1: neither midpoint nor endpoint
//! session_free(h).unwrap();
//! assert_eq!(session_free(h).unwrap_err().status(), sitar::SitarStatus::SITAR_ERR_INVALID_HANDLE);
//! ```
//!
//! Features: `testing` exports `sitar_testing_panic` / `Native.testingPanic`,
//! which panic on purpose so binding tests can prove the panic path.
#![deny(missing_docs)]

mod android_tls;
mod bridge;
mod c_api;
#[doc(hidden)]
pub mod descriptors;
mod error;
mod exports;
mod exports_macro;
mod flat;
mod guard;
mod jni_api;
mod logging;
mod registry;
mod trace;
mod types;
mod upload;

pub use bridge::*;
pub use c_api::sitar_last_error;
pub use error::{Error, SitarStatus};
pub use exports::*;
#[doc(hidden)]
pub use flat::FLAT_LAYOUTS;
pub use registry::SitarHandle;
pub use types::*;
