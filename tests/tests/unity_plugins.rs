//! `scripts/build-unity-plugins` puts the host `libsitar.so` where a Linux
//! Editor's Play Mode loads it (`Plugins/Linux/x86_64/`, next to its committed
//! `.meta`), and it is the real library: loaded here, it answers
//! `sitar_version`. Run on a copy of the package, with the dev profile and
//! without Android (the CI machine has no NDK; the script says it skipped it).

mod bindings_support;

use std::path::Path;
use std::process::Command;

use bindings_support::{run, skip, which, workspace_root};

#[test]
fn build_unity_plugins_places_a_loadable_library_for_play_mode() {
    const NAME: &str = "build_unity_plugins_places_a_loadable_library_for_play_mode";
    if !(cfg!(target_os = "linux") && cfg!(target_arch = "x86_64")) {
        return skip(NAME, "the Play Mode library is built for Linux x86_64 only");
    }
    if which("python3").is_none() {
        return skip(NAME, "`python3` is not on PATH (Debian package `python3`)");
    }
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("unity-plugin");
    let status = Command::new("cp")
        .arg("-r")
        .arg(workspace_root().join("unity-plugin"))
        .arg(&copy)
        .status()
        .unwrap();
    assert!(status.success());
    let _ = std::fs::remove_file(copy.join("Plugins/Linux/x86_64/libsitar.so"));
    let stdout = run(
        Command::new(workspace_root().join("scripts/build-unity-plugins"))
            // The binding tests' target directory: its dependencies are built already.
            .env(
                "CARGO_TARGET_DIR",
                Path::new(env!("CARGO_TARGET_TMPDIR")).join("bindings-target"),
            )
            .args(["--profile", "dev", "--no-android", "--package-dir"])
            .arg(&copy),
        "scripts/build-unity-plugins",
    );
    assert!(stdout.contains("skipped Android: --no-android"), "{stdout}");
    assert!(stdout.contains(".meta files up to date"), "{stdout}");
    let lib = copy.join("Plugins/Linux/x86_64/libsitar.so");
    assert!(lib.is_file(), "{stdout}");
    assert!(copy.join("Plugins/Linux/x86_64/libsitar.so.meta").is_file());
    assert!(!copy.join("Plugins/Linux/x86_64/libsitar.so.part").exists());
    // SAFETY: libsitar's sitar_version takes nothing and returns a static NUL-terminated string.
    let version = unsafe {
        let library = libloading::Library::new(&lib).unwrap();
        let f: libloading::Symbol<'_, unsafe extern "C" fn() -> *const std::ffi::c_char> =
            library.get(b"sitar_version\0").unwrap();
        std::ffi::CStr::from_ptr(f()).to_string_lossy().into_owned()
    };
    assert!(version.contains(env!("CARGO_PKG_VERSION")), "{version}");
    println!("Plugins/Linux/x86_64/libsitar.so: libsitar {version}");
}
