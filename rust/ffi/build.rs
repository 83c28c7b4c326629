//! Names the Android library: `DT_SONAME libsitar.so`, by which Android's dynamic linker
//! knows it (rustc gives a cdylib none; `scripts/check-android` checks it is there).

fn main() {
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("android") {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libsitar.so");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
