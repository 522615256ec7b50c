//! The cache and the output directory cannot give another model's answer
//! or destroy a user's files (issue 15, items 1, 5 and 9).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A scratch directory under `target/`, emptied.
fn scratch(name: &str) -> PathBuf {
    let dir = crate::root().join("target/cache-tests").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// An oscillator `x'' = −ω² x` with `x(0) = 1`, `x'(0) = 0` over `0 .. 1`.
fn oscillator(omega: f64) -> String {
    format!(
        "coord x;\nlagrangian = x'^2 / 2 - {}^2 * x^2 / 2;\ninitial x = 1, x' = 0;\ntime 0 .. 1;\n",
        omega
    )
}

fn lagc_run(model: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lagc"))
        .arg("run")
        .arg(model)
        .args(["--samples", "1"])
        .env("LAGC_CACHE_DIR", crate::root().join("target/lagc-cache"))
        .env("RUSTFLAGS", "-D warnings")
        .output()
        .unwrap()
}

/// x(1) from a run's CSV (`t,x,x'`, one row).
fn final_x(output: &Output) -> f64 {
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let last = stdout.lines().last().unwrap();
    last.split(',').nth(1).unwrap().parse().unwrap()
}

/// `a/model.lag` and `b/model.lag`, two models with one file name, run
/// at the same time: each prints its own motion, `cos(ω)`.
#[test]
fn two_models_of_one_file_name_run_together_give_their_own_answers() {
    let dir = scratch("same_name");
    let (a, b) = (dir.join("a/model.lag"), dir.join("b/model.lag"));
    for (path, omega) in [(&a, 1.0), (&b, 2.0)] {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, oscillator(omega)).unwrap();
    }
    let (run_a, run_b) = std::thread::scope(|s| {
        let ha = s.spawn(|| lagc_run(&a));
        let hb = s.spawn(|| lagc_run(&b));
        (ha.join().unwrap(), hb.join().unwrap())
    });
    assert!((final_x(&run_a) - 1f64.cos()).abs() < 1e-8);
    assert!((final_x(&run_b) - 2f64.cos()).abs() < 1e-8);
}

/// A damaged binary in the cache is noticed and rebuilt, not run.
#[test]
fn a_damaged_cached_binary_is_rebuilt() {
    let dir = scratch("damaged");
    let model = dir.join("damaged_oscillator.lag");
    std::fs::write(&model, oscillator(3.0)).unwrap();
    assert!((final_x(&lagc_run(&model)) - 3f64.cos()).abs() < 1e-8);
    let release = crate::root().join("target/lagc-cache/target/release");
    // The binary just run is the newest of the model's name: a target
    // directory kept across source changes holds older ones too.
    let binary = std::fs::read_dir(&release)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("lag-damaged-oscillator-")
                && p.extension().is_none()
        })
        .max_by_key(|p| std::fs::metadata(p).and_then(|m| m.modified()).ok())
        .expect("the model's binary");
    std::fs::write(&binary, b"#!/bin/sh\necho 0,0,0\n").unwrap();
    let rerun = lagc_run(&model);
    let stderr = String::from_utf8_lossy(&rerun.stderr);
    assert!(stderr.contains("not this model's binary"), "{stderr}");
    assert!((final_x(&rerun) - 3f64.cos()).abs() < 1e-8);
}

fn lagc_build(model: &str, out: &Path, force: bool) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lagc"));
    command
        .current_dir(crate::root())
        .args(["build", model, "-o"])
        .arg(out);
    if force {
        command.arg("--force");
    }
    command.output().unwrap()
}

/// A build over an earlier version's output removes the runtime files the
/// runtime no longer has: a module moved into a folder (`src/method.rs`
/// became `src/method/mod.rs`) left both, and the crate did not build
/// (E0761).
#[test]
fn build_removes_the_runtime_files_an_earlier_version_left() {
    let dir = scratch("build_stale_runtime").join("out");
    assert_eq!(
        lagc_build("examples/paper.lag", &dir, false).status.code(),
        Some(0)
    );
    let stale = dir.join("lagc-runtime/src/method.rs");
    let moved = dir.join("lagc-runtime/src/dop853.rs");
    std::fs::write(&stale, "// an earlier runtime's file\n").unwrap();
    std::fs::write(&moved, "// an earlier runtime's file\n").unwrap();
    assert_eq!(
        lagc_build("examples/paper.lag", &dir, false).status.code(),
        Some(0)
    );
    assert!(!stale.exists() && !moved.exists());
    assert!(dir.join("lagc-runtime/src/method/mod.rs").is_file());
    assert!(dir.join("lagc-runtime/src/lib.rs").is_file());
}

/// `lagc build -o DIR` writes into a new or empty directory, or one an
/// earlier build wrote; it refuses a user's project unless `--force`.
#[test]
fn build_refuses_to_overwrite_a_project_it_did_not_write() {
    let dir = scratch("build_output");
    let fresh = dir.join("fresh");
    assert_eq!(
        lagc_build("examples/paper.lag", &fresh, false)
            .status
            .code(),
        Some(0)
    );
    assert!(fresh.join(".lagc-generated").is_file());
    // Its own output: overwritten without a word.
    assert_eq!(
        lagc_build("examples/paper.lag", &fresh, false)
            .status
            .code(),
        Some(0)
    );

    let project = dir.join("project");
    std::fs::create_dir_all(project.join("src")).unwrap();
    std::fs::write(project.join("Cargo.toml"), "[package]\nname = \"mine\"\n").unwrap();
    let refused = lagc_build("examples/paper.lag", &project, false);
    assert_eq!(refused.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(stderr.contains("refusing to overwrite"), "{stderr}");
    assert_eq!(
        std::fs::read_to_string(project.join("Cargo.toml")).unwrap(),
        "[package]\nname = \"mine\"\n"
    );
    assert_eq!(
        lagc_build("examples/paper.lag", &project, true)
            .status
            .code(),
        Some(0)
    );
}

/// `lagc build --runtime RDIR` writes the runtime's sources into RDIR: it
/// refuses a folder it did not write (there, once, the runtime's own
/// source tree lost its uncommitted changes to an older copy), and shares
/// one it wrote between several crates.
#[test]
fn build_refuses_to_write_the_runtime_over_a_folder_it_did_not_write() {
    let dir = scratch("build_runtime");
    let sources = dir.join("my-runtime");
    std::fs::create_dir_all(sources.join("src")).unwrap();
    std::fs::write(sources.join("src/lib.rs"), "// my changes\n").unwrap();
    let build = |out: &str, runtime: &Path, force: bool| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_lagc"));
        command
            .current_dir(crate::root())
            .args(["build", "examples/paper.lag", "-o"])
            .arg(dir.join(out))
            .arg("--runtime")
            .arg(runtime);
        if force {
            command.arg("--force");
        }
        command.output().unwrap()
    };
    let refused = build("a", &sources, false);
    assert_eq!(refused.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(
        stderr.contains("refusing to write the runtime over it"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_to_string(sources.join("src/lib.rs")).unwrap(),
        "// my changes\n"
    );
    assert!(!dir.join("a").exists(), "nothing written on refusal");
    // A new folder, then shared by a second crate.
    let shared = dir.join("shared-runtime");
    assert_eq!(build("a", &shared, false).status.code(), Some(0));
    assert!(shared.join(".lagc-generated").is_file());
    assert_eq!(build("b", &shared, false).status.code(), Some(0));
    // --force writes over the user's folder, as it does for -o.
    assert_eq!(build("c", &sources, true).status.code(), Some(0));
}

/// A file without end (`/dev/zero`) is refused, not read into memory.
#[cfg(unix)]
#[test]
fn an_endless_input_file_is_refused() {
    let out = Command::new(env!("CARGO_BIN_EXE_lagc"))
        .args(["check", "/dev/zero"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("larger than 16 MiB"), "{stderr}");
}

fn lagc_in(cache: &Path, args: &[&str], max_bytes: Option<&str>) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lagc"));
    command
        .args(args)
        .current_dir(crate::root())
        .env("LAGC_CACHE_DIR", cache);
    if let Some(bound) = max_bytes {
        command.env("LAGC_CACHE_MAX_BYTES", bound);
    }
    command.output().unwrap()
}

#[test]
fn the_cache_lists_its_models_evicts_the_least_recently_run_and_cleans() {
    let cache = scratch("cache-list");
    let _ = std::fs::remove_dir_all(&cache);
    let run = |model: &str, bound: Option<&str>| {
        let output = lagc_in(&cache, &["run", model, "--quiet"], bound);
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        String::from_utf8_lossy(&output.stderr).into_owned()
    };
    let list = || String::from_utf8(lagc_in(&cache, &["cache", "list"], None).stdout).unwrap();
    run("examples/paper.lag", None);
    let listed = list();
    assert!(
        listed.contains("lag-paper-") && listed.contains("examples/paper.lag"),
        "{listed}"
    );
    // A model another process is building (its lock held) is not evicted.
    let package = listed
        .split_whitespace()
        .find(|w| w.starts_with("lag-paper-"))
        .unwrap()
        .to_string();
    let held = std::fs::File::open(cache.join("locks").join(format!("{package}.lock"))).unwrap();
    held.lock().unwrap();
    let stderr = run("examples/damped_oscillator.lag", Some("1"));
    assert!(!stderr.contains("least recently run"), "{stderr}");
    assert!(list().contains("lag-paper-"));
    drop(held);
    // A bound of one byte: the run keeps its own model and evicts the rest.
    let stderr = run("examples/damped_oscillator.lag", Some("1"));
    assert!(
        stderr.contains("removed the 1 least recently run model"),
        "{stderr}"
    );
    let listed = list();
    assert!(
        !listed.contains("lag-paper-") && listed.contains("lag-damped-oscillator-"),
        "{listed}"
    );
    let cleaned = lagc_in(&cache, &["cache", "clean"], None);
    assert!(cleaned.status.success());
    assert!(!cache.exists());
    assert!(list().contains("0 model(s)"));
}

/// A model whose text no earlier run built (a comment with the time), so
/// that every process that runs it must write and build its crate.
fn unique_oscillator(omega: f64) -> String {
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos();
    format!("// built at {now}\n{}", oscillator(omega))
}

/// The cached crate directory of the package whose name starts with
/// `prefix`, in the tests' shared cache: the newest one, since every run of
/// a test writes its model anew (`unique_oscillator`) and a cache kept from
/// earlier runs holds the crates of those too.
fn cached_crate(prefix: &str) -> PathBuf {
    std::fs::read_dir(crate::root().join("target/lagc-cache/crates"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with(prefix))
        .max_by_key(|p| {
            std::fs::metadata(p.join("src/lib.rs"))
                .and_then(|m| m.modified())
                .ok()
        })
        .expect("the model's cached crate")
}

/// Issue 13: two `lagc run` of one model at once (its crate new to the
/// cache, so both write and build it) both succeed with identical output.
#[test]
fn two_concurrent_runs_of_one_model_agree() {
    let dir = scratch("concurrent");
    let model = dir.join("concurrent_oscillator.lag");
    std::fs::write(&model, unique_oscillator(1.5)).unwrap();
    let (first, second) = std::thread::scope(|s| {
        let a = s.spawn(|| lagc_run(&model));
        let b = s.spawn(|| lagc_run(&model));
        (a.join().unwrap(), b.join().unwrap())
    });
    assert!((final_x(&first) - 1.5f64.cos()).abs() < 1e-8);
    assert!((final_x(&second) - 1.5f64.cos()).abs() < 1e-8);
    assert_eq!(first.stdout, second.stdout);
    // No temporary file is left behind.
    let crate_dir = cached_crate("lag-concurrent-oscillator-");
    for dir in [crate_dir.clone(), crate_dir.join("src")] {
        for entry in std::fs::read_dir(dir).unwrap() {
            let name = entry.unwrap().file_name().to_string_lossy().into_owned();
            assert!(!name.contains("lagc-tmp"), "{name}");
        }
    }
}

/// Issue 13: a run killed half-way (simulated: the crate's source cut in
/// half, its `main.rs` and `Cargo.lock` missing, a temporary file left,
/// the binary gone) leaves a cache that the next run repairs.
#[test]
fn a_half_written_cached_crate_is_rebuilt() {
    let dir = scratch("half_written");
    let model = dir.join("half_written_oscillator.lag");
    std::fs::write(&model, unique_oscillator(2.5)).unwrap();
    let first = lagc_run(&model);
    assert!((final_x(&first) - 2.5f64.cos()).abs() < 1e-8);
    let crate_dir = cached_crate("lag-half-written-oscillator-");
    let lib = crate_dir.join("src/lib.rs");
    let text = std::fs::read_to_string(&lib).unwrap();
    std::fs::write(&lib, &text[..text.len() / 2]).unwrap();
    std::fs::remove_file(crate_dir.join("src/main.rs")).unwrap();
    std::fs::remove_file(crate_dir.join("Cargo.lock")).unwrap();
    std::fs::write(crate_dir.join("src/.lib.rs.lagc-tmp-1"), "fn broken(").unwrap();
    let package = crate_dir
        .file_name()
        .unwrap()
        .to_string_lossy()
        .into_owned();
    let binary = crate::root()
        .join("target/lagc-cache/target/release")
        .join(format!("{package}{}", std::env::consts::EXE_SUFFIX));
    std::fs::remove_file(&binary).unwrap();
    let second = lagc_run(&model);
    assert_eq!(first.stdout, second.stdout);
    assert_eq!(std::fs::read_to_string(&lib).unwrap(), text);
    assert!(!crate_dir.join("src/.lib.rs.lagc-tmp-1").exists());
}
