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
const REQUIREMENTS: &str = "maturin>=1.9.4,<2\npytest>=8\nnumpy>=1.24\ndask[distributed]>=2024.1\n";

/// The models the suite imports: `(file, module)`.
const MODELS: &[(&str, &str)] = &[
    ("examples/paper.lag", "paper"),
    ("tests/data/rocket_outputs.lag", "rocket_outputs"),
    ("tests/data/driven_oscillator.lag", "driven_oscillator"),
    // `Model.linearize` against `lagc linearize` (test_linearize.py).
    ("examples/spherical_pendulum.lag", "spherical_pendulum"),
    (
        "examples/double_pendulum_energy.lag",
        "double_pendulum_energy",
    ),
    ("examples/rolling_disk.lag", "rolling_disk"),
    ("examples/knife_edge.lag", "knife_edge"),
    ("tests/data/steered_spring.lag", "steered_spring"),
    ("examples/rolling_disk_3d.lag", "rolling_disk_3d"),
    ("examples/cartesian_pendulum.lag", "cartesian_pendulum"),
    ("examples/chaplygin_sleigh.lag", "chaplygin_sleigh"),
    ("examples/particle_on_circle.lag", "particle_on_circle"),
    ("examples/four_bar_closure.lag", "four_bar_closure"),
    (
        "tests/data/v2/spherical_pendulum_cartesian.lag",
        "spherical_pendulum_cartesian",
    ),
    (
        "examples/third_order_constraint.lag",
        "third_order_constraint",
    ),
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
    // Asked first, also when the environment exists: it is made from it.
    let python = python311();
    let venv = base().join("venv");
    let stamp = venv.join("lagc-requirements.txt");
    if std::fs::read_to_string(&stamp).is_ok_and(|s| s == REQUIREMENTS)
        && venv.join("bin/python").exists()
    {
        return venv;
    }
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
            .args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "--disable-pip-version-check",
                "-r",
            ])
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
            .args([
                "-m",
                "pip",
                "wheel",
                "--quiet",
                "--no-deps",
                "--no-build-isolation",
            ])
            .arg("--disable-pip-version-check")
            .arg("-w")
            .arg(&wheels)
            .arg(&project)
            .env("PATH", path_with(venv))
            .env("CARGO_TARGET_DIR", base().join("target"))
            // The project's Cargo.lock is complete: cargo may not change it.
            .env("MATURIN_PEP517_ARGS", "--locked")
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
            .args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "--no-deps",
                "--force-reinstall",
            ])
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

/// `lagc build --python`'s project: named after the file, the model's code
/// and a `#[pymodule]` handing it to `lagc_python::register`, the libraries
/// where asked; a `--python-lib` folder lagc did not write is refused.
#[test]
fn build_python_writes_a_project_named_after_the_file() {
    let dir = crate::root().join("target/python-build-tests");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let lagc = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_lagc"))
            .current_dir(crate::root())
            .args(args)
            .output()
            .unwrap()
    };
    let out = dir.join("paper");
    let built = lagc(&[
        "build",
        "--python",
        "examples/paper.lag",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(built.status.success(), "{}", show(&built));
    let read = |path: &str| std::fs::read_to_string(out.join(path)).unwrap();
    assert!(read("pyproject.toml").contains("module-name = \"paper\""));
    assert!(read("pyproject.toml").contains("build-backend = \"maturin\""));
    let cargo = read("Cargo.toml");
    assert!(cargo.contains("name = \"paper\"") && cargo.contains("crate-type = [\"cdylib\"]"));
    assert!(
        cargo.contains("lagc-python = { path = \"lagc-python\" }"),
        "{cargo}"
    );
    let lib = read("src/lib.rs");
    assert!(lib.contains("impl lagc_runtime::model::Model for Model"));
    assert!(lib.contains("lagc_python::register::<Model>(module, \"paper\")"));
    assert!(
        read("lagc-python/Cargo.toml").contains("lagc-runtime = { path = \"../lagc-runtime\" }")
    );
    assert!(out.join("lagc-runtime/src/io/table.rs").is_file());

    // A module name Python accepts from any file stem.
    let odd = dir.join("2d arm.lag");
    std::fs::copy(crate::root().join("examples/paper.lag"), &odd).unwrap();
    let out = dir.join("odd");
    let built = lagc(&[
        "build",
        "--python",
        odd.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(built.status.success(), "{}", show(&built));
    let pyproject = std::fs::read_to_string(out.join("pyproject.toml")).unwrap();
    assert!(
        pyproject.contains("module-name = \"_2d_arm\""),
        "{pyproject}"
    );

    // A folder lagc did not write is not written over.
    let mine = dir.join("mine");
    std::fs::create_dir_all(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "mine\n").unwrap();
    let refused = lagc(&[
        "build",
        "--python",
        "examples/paper.lag",
        "-o",
        dir.join("refused").to_str().unwrap(),
        "--python-lib",
        mine.to_str().unwrap(),
    ]);
    assert_eq!(refused.status.code(), Some(2), "{}", show(&refused));
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(
        stderr.contains("refusing to write the Python library over it"),
        "{stderr}"
    );
    assert!(!dir.join("refused").exists(), "nothing written on refusal");
    // --python-lib belongs to --python.
    let alone = lagc(&[
        "build",
        "examples/paper.lag",
        "-o",
        "x",
        "--python-lib",
        "y",
    ]);
    assert_eq!(alone.status.code(), Some(2), "{}", show(&alone));
}

/// lagc carries every source file of `python/` (as it does the runtime's).
#[test]
fn the_python_library_lagc_carries_is_every_file_of_python_src() {
    let python = crate::root().join("python");
    let mut on_disk = vec!["Cargo.toml".to_string()];
    for entry in std::fs::read_dir(python.join("src")).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        on_disk.push(format!("src/{name}"));
    }
    on_disk.sort();
    let mut known: Vec<String> = lagc::emit::python::python_library_files("../runtime")
        .into_iter()
        .map(|(p, _)| p.to_string())
        .collect();
    known.sort();
    assert_eq!(known, on_disk);
}
