//! The Python module of a model (`lagc build --python`), tested as a user
//! meets it: a virtual environment of its own (`python3.11 -m venv` under
//! `target/python-tests/`, maturin, pytest, numpy and dask from PyPI with
//! pip), each test model's project built into a wheel and pip-installed,
//! then pytest on `tests/python/` against the installed modules.
//!
//! The environment is made once and kept while its requirements stay the
//! same (`requirements.txt` beside it); the wheels are rebuilt and
//! reinstalled on every run. The models' projects share one runtime, one
//! `lagc-python` and one cargo target directory, so the second model builds
//! without the libraries (its time is printed).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Instant;

/// What the tests install, pinned to what was checked (the
/// `docs/BENCHMARKS.md` figures and `/work/shared` notes).
const REQUIREMENTS: &str =
    "maturin>=1.9.4,<2\npytest>=8\nnumpy>=1.24\ndask[distributed]>=2024.1\n";

/// The models the suite imports: `(file, module)`.
const MODELS: &[(&str, &str)] = &[
    ("examples/paper.lag", "paper"),
    ("tests/data/rocket_outputs.lag", "rocket_outputs"),
];

fn base() -> PathBuf {
    crate::root().join("target/python-tests")
}

fn show(output: &Output) -> String {
    format!(
        "status {}\n--- stdout ---\n{}\n--- stderr ---\n{}",
        output.status,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

fn run(command: &mut Command, what: &str) -> Output {
    let output = command
        .output()
        .unwrap_or_else(|e| panic!("{what}: cannot start: {e}"));
    assert!(output.status.success(), "{what} failed: {}", show(&output));
    output
}

/// `python3.11`, or a failure saying it is needed (never a silent pass).
fn python311() -> PathBuf {
    let found = Command::new("python3.11").arg("--version").output();
    match found {
        Ok(output) if output.status.success() => PathBuf::from("python3.11"),
        _ => panic!(
            "python3.11 was not found on PATH: the Python module's tests (tests/python/, run by \
             tests/it/python.rs) need CPython 3.11 with its `venv` module and pip access to \
             PyPI (maturin, pytest, numpy, dask). Install it (e.g. Debian's python3.11 and \
             python3.11-venv) and run `cargo test` again."
        ),
    }
}

/// The test environment's directory, made (or remade) when its
/// requirements changed.
fn environment() -> PathBuf {
    let venv = base().join("venv");
    let stamp = venv.join("lagc-requirements.txt");
    if std::fs::read_to_string(&stamp).is_ok_and(|s| s == REQUIREMENTS)
        && venv.join("bin/python").exists()
    {
        return venv;
    }
    let python = python311();
    let _ = std::fs::remove_dir_all(&venv);
    std::fs::create_dir_all(base()).unwrap();
    run(
        Command::new(&python).args(["-m", "venv"]).arg(&venv),
        "python3.11 -m venv",
    );
    let requirements = base().join("requirements.txt");
    std::fs::write(&requirements, REQUIREMENTS).unwrap();
    run(
        Command::new(venv.join("bin/python"))
            .args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "-r"])
            .arg(&requirements),
        "pip install of maturin, pytest, numpy, dask",
    );
    std::fs::write(&stamp, REQUIREMENTS).unwrap();
    venv
}

/// `PATH` with the environment's `bin` first (maturin, pip).
fn path_with(venv: &Path) -> std::ffi::OsString {
    let mut paths = vec![venv.join("bin")];
    if let Some(path) = std::env::var_os("PATH") {
        paths.extend(std::env::split_paths(&path));
    }
    std::env::join_paths(paths).unwrap()
}

/// Builds the model's project into a wheel and installs it; returns the
/// seconds the wheel took.
fn build_and_install(venv: &Path, file: &str, module: &str) -> f64 {
    let project = base().join("projects").join(module);
    let wheels = base().join("wheels").join(module);
    run(
        Command::new(env!("CARGO_BIN_EXE_lagc"))
            .args(["build", "--python"])
            .arg(crate::root().join(file))
            .arg("-o")
            .arg(&project)
            .arg("--runtime")
            .arg(base().join("lagc-runtime"))
            .arg("--python-lib")
            .arg(base().join("lagc-python")),
        &format!("lagc build --python {file}"),
    );
    let _ = std::fs::remove_dir_all(&wheels);
    let start = Instant::now();
    run(
        Command::new(venv.join("bin/python"))
            .args(["-m", "pip", "wheel", "--quiet", "--no-deps", "--no-build-isolation"])
            .arg("--disable-pip-version-check")
            .arg("-w")
            .arg(&wheels)
            .arg(&project)
            .env("PATH", path_with(venv))
            .env("CARGO_TARGET_DIR", base().join("target"))
            // Generated code and the libraries are warning-free.
            .env("RUSTFLAGS", "-D warnings"),
        &format!("pip wheel of {module}'s project"),
    );
    let seconds = start.elapsed().as_secs_f64();
    let wheel = std::fs::read_dir(&wheels)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "whl"))
        .unwrap_or_else(|| panic!("no wheel of {module} in {}", wheels.display()));
    run(
        Command::new(venv.join("bin/python"))
            .args(["-m", "pip", "install", "--quiet", "--no-deps", "--force-reinstall"])
            .arg("--disable-pip-version-check")
            .arg(&wheel),
        &format!("pip install of {}", wheel.display()),
    );
    seconds
}

#[test]
fn python_modules_pass_their_pytest_suite_installed_in_a_venv() {
    let venv = environment();
    for (file, module) in MODELS {
        let seconds = build_and_install(&venv, file, module);
        eprintln!("python: the wheel of {module} built in {seconds:.1} s");
    }
    let output = Command::new(venv.join("bin/python"))
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(crate::root().join("tests/python"))
        .current_dir(base())
        .env("PATH", path_with(&venv))
        .env("LAGC", env!("CARGO_BIN_EXE_lagc"))
        .env("LAGC_ROOT", crate::root())
        .env("LAGC_CACHE_DIR", crate::root().join("target/lagc-cache"))
        .env("LAGC_WHEELS", base().join("wheels"))
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "pytest failed on tests/python: {}",
        show(&output)
    );
}
