//! The Python package (`python/`) as researchers install it: `python/build-wheel` makes the
//! wheel (`maturin build --release`: the small extension and the `sitar` command without the
//! backend), a fresh venv with no cargo or rustc on its PATH installs it (≤ 10 s, offline:
//! numpy, pytest and evo come from the system's site-packages), and the pytest suite runs
//! against that install: `sitar.evo` against evo's Python API, `sitar.ape/rpe/drift` against
//! this build's `sitar --format json`, `sitar.estimate`, the installed `sitar` command.
//! SKIPPED (with the reason) when python3, its venv module or maturin is missing.
//!
//! The wheel builds into TARGET/wheel (its own release build: the first run compiles the
//! extension and the command, about 8 min of CPU on 2 cores; `.ci/run` builds it before the
//! tests, so here it only repacks).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// The maturin CI installs (pinned; python/pyproject.toml requires the same).
const MATURIN: &str = "maturin==1.8.0";
/// The bound on installing the wheel.
const INSTALL_BOUND: Duration = Duration::from_secs(10);

fn run(what: &str, command: &mut Command) -> Result<String, String> {
    let out = command.output().map_err(|e| format!("{what}: {e}"))?;
    if out.status.success() {
        return Ok(String::from_utf8_lossy(&out.stdout).into_owned());
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

/// A venv with the system's site-packages (numpy, pytest, evo), or None with the reason.
fn venv(at: &Path) -> Result<PathBuf, String> {
    run(
        "python3 -m venv",
        Command::new("python3")
            .args(["-m", "venv", "--system-site-packages"])
            .arg(at),
    )?;
    Ok(at.join("bin"))
}

/// PATH with `first` in front, and without the directories that hold cargo or rustc.
fn path_without_rust(first: &Path) -> std::ffi::OsString {
    let original = std::env::var_os("PATH").unwrap_or_default();
    let kept = std::env::split_paths(&original)
        .filter(|dir| !dir.join("cargo").exists() && !dir.join("rustc").exists());
    std::env::join_paths(std::iter::once(first.to_owned()).chain(kept)).unwrap()
}

#[test]
fn the_wheel_installs_without_rust_and_its_pytest_suite_passes() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let repo = repo.canonicalize().unwrap();
    let temp = tempfile::tempdir().unwrap();
    let build_bin = match venv(&temp.path().join("build")) {
        Ok(bin) => bin,
        Err(why) => {
            eprintln!("SKIPPED the Python package: no python3 with venv ({why})");
            return;
        }
    };
    let build_path = std::env::join_paths(std::iter::once(build_bin.clone()).chain(
        std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default()),
    ))
    .unwrap();
    let has_maturin = Command::new(build_bin.join("python"))
        .args(["-m", "maturin", "--version"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_maturin {
        let install = run(
            "pip install maturin",
            Command::new(build_bin.join("python"))
                .args([
                    "-m",
                    "pip",
                    "install",
                    "-q",
                    "--disable-pip-version-check",
                    MATURIN,
                ])
                .env("PATH", &build_path),
        );
        if let Err(why) = install {
            eprintln!("SKIPPED the Python package: maturin did not install ({why})");
            return;
        }
    }

    let started = Instant::now();
    let built = run(
        "python/build-wheel",
        Command::new(repo.join("python/build-wheel"))
            .current_dir(&repo)
            .env("PATH", &build_path)
            .env("CARGO_TARGET_DIR", target_dir(&repo)),
    )
    .unwrap();
    eprintln!("{} ({:.0?})", built.trim(), started.elapsed());
    let wheels = target_dir(&repo).join("wheels");
    let wheel = std::fs::read_dir(&wheels)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "whl"))
        .expect("python/build-wheel leaves one wheel in TARGET/wheels");
    let name = wheel.file_name().unwrap().to_string_lossy().into_owned();
    assert!(
        name.contains("-cp39-abi3-") && name.contains("manylinux_2_"),
        "one abi3 wheel for CPython ≥ 3.9 with a manylinux tag, got {name}"
    );

    // The user's side: a fresh venv, no Rust toolchain on PATH, no package index.
    let bin = venv(&temp.path().join("user")).unwrap();
    let path = path_without_rust(&bin);
    let started = Instant::now();
    run(
        "pip install WHEEL",
        Command::new(bin.join("python"))
            .args(["-m", "pip", "install", "-q", "--disable-pip-version-check"])
            .arg("--no-index")
            .arg(&wheel)
            .env("PATH", &path),
    )
    .unwrap();
    let install = started.elapsed();
    eprintln!("pip install {name} without cargo or rustc on PATH: {install:.1?}");
    assert!(
        install <= INSTALL_BOUND,
        "installing the wheel took {install:.1?}, more than {INSTALL_BOUND:?}"
    );

    let started = Instant::now();
    run(
        "pytest python/tests",
        Command::new(bin.join("python"))
            .args(["-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider"])
            .arg(repo.join("python/tests"))
            .current_dir(temp.path())
            .env("PATH", &path)
            .env("SITAR_BIN", env!("CARGO_BIN_EXE_sitar"))
            .env("SITAR_EXPECT_WHEEL", "1")
            .env("MPLBACKEND", "Agg"),
    )
    .unwrap();
    eprintln!("pytest python/tests: {:.0?}", started.elapsed());
}

/// The extension's own Rust unit tests (its matrix readers), in the wheel's target directory
/// (the release build of its dependencies is shared with python/build-wheel's).
#[test]
fn the_extension_s_rust_unit_tests_pass() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let started = Instant::now();
    let out = run(
        "cargo test (python/Cargo.toml)",
        Command::new(env!("CARGO"))
            .args(["test", "--release", "--locked", "--lib", "--manifest-path"])
            .arg(repo.join("python/Cargo.toml"))
            .env("CARGO_TARGET_DIR", target_dir(&repo).join("wheel")),
    )
    .unwrap();
    assert!(out.contains("test result: ok"), "{out}");
    eprintln!("the extension's unit tests: {:.0?}", started.elapsed());
}
