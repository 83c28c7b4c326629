//! One `sitar` command run to its end for the CLI tests: its output, or its stdout (and stderr)
//! once it succeeded, or its stderr once it failed; the test's panic shows the other stream.
//! Each runs without `DISPLAY` or `WAYLAND_DISPLAY`, so `-p` finds no display wherever the tests
//! run; the `_in` forms run in folder `dir` (relative paths are the test's files there).

use std::ffi::OsStr;
use std::fmt::Debug;
use std::path::Path;
use std::process::{Command, Output};

/// Runs `sitar ARGS` in the test's working directory.
pub fn sitar<A: AsRef<OsStr>>(args: &[A]) -> Output {
    run(None, args)
}

/// Runs `sitar ARGS` in `dir`.
pub fn sitar_in<A: AsRef<OsStr>>(dir: &Path, args: &[A]) -> Output {
    run(Some(dir), args)
}

/// `sitar ARGS`, which must succeed: its stdout.
pub fn ok<A: AsRef<OsStr> + Debug>(args: &[A]) -> String {
    succeeded(args, sitar(args)).0
}

/// `sitar ARGS` in `dir`, which must succeed: its stdout.
pub fn ok_in<A: AsRef<OsStr> + Debug>(dir: &Path, args: &[A]) -> String {
    succeeded(args, sitar_in(dir, args)).0
}

/// `sitar ARGS`, which must succeed: its stdout and stderr.
pub fn ok_both<A: AsRef<OsStr> + Debug>(args: &[A]) -> (String, String) {
    succeeded(args, sitar(args))
}

/// `sitar ARGS` in `dir`, which must succeed: its stdout and stderr.
pub fn ok_both_in<A: AsRef<OsStr> + Debug>(dir: &Path, args: &[A]) -> (String, String) {
    succeeded(args, sitar_in(dir, args))
}

/// `sitar ARGS`, which must fail (any exit status but 0): its stderr.
pub fn fails<A: AsRef<OsStr> + Debug>(args: &[A]) -> String {
    failed(args, sitar(args))
}

/// `sitar ARGS` in `dir`, which must fail (any exit status but 0): its stderr.
pub fn fails_in<A: AsRef<OsStr> + Debug>(dir: &Path, args: &[A]) -> String {
    failed(args, sitar_in(dir, args))
}

fn run<A: AsRef<OsStr>>(dir: Option<&Path>, args: &[A]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_sitar"));
    command
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY");
    if let Some(dir) = dir {
        command.current_dir(dir);
    }
    command.output().expect("run sitar")
}

fn succeeded<A: Debug>(args: &[A], out: Output) -> (String, String) {
    assert!(
        out.status.success(),
        "sitar {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (
        String::from_utf8(out.stdout).expect("UTF-8 stdout"),
        String::from_utf8(out.stderr).expect("UTF-8 stderr"),
    )
}

fn failed<A: Debug>(args: &[A], out: Output) -> String {
    assert!(
        !out.status.success(),
        "sitar {args:?} should have failed; it printed: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stderr).expect("UTF-8 stderr")
}
