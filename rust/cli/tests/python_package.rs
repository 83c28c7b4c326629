//! The Python package (`python/`): builds it in a fresh venv as a user would (`pip install
//! maturin==1.8.0`, then `pip install ./python`) and runs its pytest suite, which checks
//! `sitar.ape/rpe/drift` against this build's `sitar --format json`, against evo's Python
//! API, and the installed `sitar` command. SKIPPED (with the reason) when python3, its venv
//! module or the package registry is missing.
//!
//! The wheel is built with cargo's dev profile into this workspace's target directory
//! (`MATURIN_PEP517_ARGS`), so the crates the CLI's tests built are reused: the release
//! build a user's `pip install` makes would add minutes to the suite.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The maturin CI installs (pinned; python/pyproject.toml requires the same).
const MATURIN: &str = "maturin==1.8.0";

fn run(what: &str, command: &mut Command) -> Result<(), String> {
    let out = command.output().map_err(|e| format!("{what}: {e}"))?;
    if out.status.success() {
        return Ok(());
    }
    Err(format!(
        "{what} failed ({}):\n{}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    ))
}

fn target_dir(repo: &Path) -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| repo.join("target"), PathBuf::from)
}

#[test]
fn the_python_package_builds_and_its_pytest_suite_passes() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let repo = repo.canonicalize().unwrap();
    let temp = tempfile::tempdir().unwrap();
    let venv = temp.path().join("venv");
    // numpy, pytest and evo from the system's site-packages when present (CI installs evo).
    if let Err(why) = run(
        "python3 -m venv",
        Command::new("python3")
            .args(["-m", "venv", "--system-site-packages"])
            .arg(&venv),
    ) {
        eprintln!("SKIPPED the Python package: no python3 with venv ({why})");
        return;
    }
    let bin = venv.join("bin");
    let path = std::env::join_paths(std::iter::once(bin.clone()).chain(std::env::split_paths(
        &std::env::var_os("PATH").unwrap_or_default(),
    )))
    .unwrap();
    let python = bin.join("python");
    let pip = |args: &[&str]| {
        let mut command = Command::new(&python);
        command
            .args(["-m", "pip", "install", "-q", "--disable-pip-version-check"])
            .args(args)
            .env("PATH", &path);
        command
    };
    if let Err(why) = run("pip install maturin", &mut pip(&[MATURIN])) {
        eprintln!("SKIPPED the Python package: maturin did not install ({why})");
        return;
    }
    let has_pytest = Command::new(&python)
        .args(["-c", "import pytest"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_pytest {
        run("pip install pytest", &mut pip(&["pytest"])).unwrap();
    }
    let started = std::time::Instant::now();
    run(
        "pip install ./python",
        pip(&["--no-build-isolation", "./python"])
            .current_dir(&repo)
            .env("CARGO_TARGET_DIR", target_dir(&repo))
            .env("MATURIN_PEP517_ARGS", "--profile dev"),
    )
    .unwrap();
    eprintln!("pip install ./python: {:.0?}", started.elapsed());
    let started = std::time::Instant::now();
    run(
        "pytest python/tests",
        Command::new(&python)
            .args(["-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider"])
            .arg(repo.join("python/tests"))
            .current_dir(temp.path())
            .env("PATH", &path)
            .env("SITAR_BIN", env!("CARGO_BIN_EXE_sitar")),
    )
    .unwrap();
    eprintln!("pytest python/tests: {:.0?}", started.elapsed());
}
