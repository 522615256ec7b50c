//! The built `lagc` binary: exit codes and where diagnostics go.

use std::process::{Command, Output};

fn lagc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lagc"))
        .args(args)
        .current_dir(crate::root())
        .output()
        .expect("lagc runs")
}

#[test]
fn clean_example_exits_0() {
    let out = lagc(&["check", "examples/paper.lag"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn model_error_exits_1_with_location() {
    let out = lagc(&["check", "tests/data/errors/unknown_name.lag"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("tests/data/errors/unknown_name.lag:6:"),
        "{stderr}"
    );
    assert!(stderr.contains("error[E0002]"), "{stderr}");
    // stderr is not a terminal here: no colour codes.
    assert!(!stderr.contains('\u{1b}'), "{stderr}");
}

#[test]
fn invalid_utf8_exits_1() {
    let out = lagc(&["check", "tests/data/errors/invalid_utf8.lag"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("E0016"));
}

#[test]
fn missing_file_exits_2() {
    let out = lagc(&["check", "no/such/file.lag"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read `no/such/file.lag`"));
}

#[test]
fn bad_usage_exits_2() {
    for args in [
        &[][..],
        &["frobnicate"],
        &["check"],
        &["check", "a.lag", "b.lag"],
    ] {
        let out = lagc(args);
        assert_eq!(out.status.code(), Some(2), "lagc {args:?}");
    }
}

#[test]
fn help_exits_0() {
    let out = lagc(&["check", "--help"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stdout).contains("Usage: lagc check"));
}

/// `lagc run` end to end: it builds the paper's crate in the cache, runs
/// it (CSV with the state's header, the exact motion of SPEC 1.6), and a
/// second run of the unchanged model does not rebuild. The cache is the
/// tests' own `lagc` cache: the generated-crate tests write crates of the
/// same names with other contents into theirs.
#[test]
fn run_reproduces_the_paper_and_does_not_rebuild_an_unchanged_model() {
    let cache = crate::root().join("target/lagc-cache");
    let run = || {
        Command::new(env!("CARGO_BIN_EXE_lagc"))
            .args(["run", "examples/paper.lag", "--samples", "3"])
            .env("LAGC_CACHE_DIR", &cache)
            .env("RUSTFLAGS", "-D warnings")
            .current_dir(crate::root())
            .output()
            .expect("lagc runs")
    };
    let first = run();
    let stderr = String::from_utf8_lossy(&first.stderr);
    assert_eq!(first.status.code(), Some(0), "{stderr}");
    let stdout = String::from_utf8(first.stdout).unwrap();
    let mut lines = stdout.lines();
    assert_eq!(lines.next(), Some("t,q1,q2,q1',q2'"));
    let last: Vec<f64> = lines
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    // t = 5: q1' = e^{αt}/√(1+t²) with α = 0.5, q2' = t q1'.
    let q1_dot = (0.5_f64 * 5.0).exp() / 26.0_f64.sqrt();
    assert!((last[3] - q1_dot).abs() <= 1e-9 * q1_dot, "{last:?}");
    assert!((last[4] - 5.0 * q1_dot).abs() <= 1e-9 * q1_dot, "{last:?}");

    let second = run();
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("Compiling"), "rebuilt:\n{stderr}");
    assert_eq!(String::from_utf8(second.stdout).unwrap(), stdout);
}

/// `lagc derive` shows the reduced system (7) of every candidate of an
/// implicit constraint (SPEC 2.2: "lagc derives the reduced system (7) for
/// each"); it showed the first only.
#[test]
fn derive_shows_every_candidates_reduced_system() {
    let out = Command::new(env!("CARGO_BIN_EXE_lagc"))
        .args(["derive", "examples/knife_edge_turning.lag"])
        .current_dir(crate::root())
        .output()
        .expect("lagc runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("  y' = sin(th)*x'/cos(th)"), "{stdout}");
    assert!(stdout.contains("--- mode 2 of 2"), "{stdout}");
    assert!(stdout.contains("  x' = cos(th)*y'/sin(th)"), "{stdout}");
}

/// `lagc run … --plot F --phase X,Y` may name an output column (SPEC 2.2:
/// "one column against another"): `lagc run` checks the options before it
/// builds, with the outputs among the columns (it listed only the state).
#[test]
fn run_draws_a_phase_plot_of_an_output_against_a_coordinate() {
    let cache = crate::root().join("target/lagc-cache");
    let svg = crate::root().join("target/phase-output.svg");
    let _ = std::fs::remove_file(&svg);
    let out = Command::new(env!("CARGO_BIN_EXE_lagc"))
        .args([
            "run",
            "examples/double_pendulum_energy.lag",
            "--samples",
            "3",
            "--plot",
        ])
        .arg(&svg)
        .args(["--phase", "a,E"])
        .env("LAGC_CACHE_DIR", &cache)
        .current_dir(crate::root())
        .output()
        .expect("lagc runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let drawn = std::fs::read_to_string(&svg).expect("the plot is written");
    assert!(drawn.contains("<svg"), "{drawn}");
}

/// Issue 15, item 4: every path runs the same derivation checks. A model
/// whose equations (4) fail the cross-check is refused by `check`,
/// `derive`, `build`, `run` and `report` alike, with the same message, and
/// nothing is written, built or integrated.
#[test]
fn every_path_refuses_a_model_that_fails_the_cross_check() {
    let file = "tests/data/errors/cross_check_fails.lag";
    let out_dir = crate::root().join("target/cross-check-build");
    let _ = std::fs::remove_dir_all(&out_dir);
    let out_dir_arg = out_dir.to_string_lossy().into_owned();
    let cache = crate::root().join("target/lagc-cache");
    let mut messages = Vec::new();
    for args in [
        vec!["check", file],
        vec!["derive", file],
        vec!["build", file, "-o", &out_dir_arg],
        vec!["run", file, "--samples", "3"],
        vec!["report", file, "--out", &out_dir_arg],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_lagc"))
            .args(&args)
            .env("LAGC_CACHE_DIR", &cache)
            .current_dir(crate::root())
            .output()
            .expect("lagc runs");
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(1), "lagc {args:?}:\n{stderr}");
        assert!(out.stdout.is_empty(), "lagc {args:?} printed a result");
        assert!(stderr.contains("error[E0033]"), "lagc {args:?}:\n{stderr}");
        messages.push(stderr);
    }
    assert!(
        messages.iter().all(|m| *m == messages[0]),
        "the paths report differently:\n{messages:#?}"
    );
    assert!(!out_dir.exists(), "build or report wrote {out_dir:?}");
    insta::assert_snapshot!(messages[0]);
}

/// Issue 15, item 12: tolerances out of (0, 1) are usage errors (exit 2)
/// in lagc's own words, negative ones included (not clap's "unexpected
/// argument"), reported before anything is built; one below the rounding
/// of f64 is run with a warning.
#[test]
fn bad_tolerances_are_refused_in_lagcs_words() {
    let cache = crate::root().join("target/lagc-cache");
    let lagc_in_cache = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_lagc"))
            .args(args)
            .env("LAGC_CACHE_DIR", &cache)
            // As in the paper's `run` test, so that the two share one build.
            .env("RUSTFLAGS", "-D warnings")
            .current_dir(crate::root())
            .output()
            .expect("lagc runs")
    };
    let mut rendered = String::new();
    for args in [
        &["run", "examples/paper.lag", "--rtol", "10"][..],
        &["run", "examples/paper.lag", "--rtol", "1"],
        &["run", "examples/paper.lag", "--rtol", "-1"],
        &["run", "examples/paper.lag", "--rtol", "0"],
        &["run", "examples/paper.lag", "--atol", "-1e-9"],
        &["report", "examples/paper.lag", "--tolerances", "-1"],
        &["report", "examples/paper.lag", "--tolerances", "-1e-3,1e-4"],
        &["report", "examples/paper.lag", "--tolerances", "1e-3,10"],
    ] {
        let out = lagc_in_cache(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "lagc {args:?}:\n{stderr}");
        assert!(out.stdout.is_empty(), "lagc {args:?}");
        assert!(!stderr.contains("unexpected argument"), "{stderr}");
        assert!(!stderr.contains("Compiling"), "built for {args:?}");
        let first = stderr.lines().next().unwrap_or_default();
        rendered.push_str(&format!("lagc {}\n  {first}\n", args.join(" ")));
    }
    insta::assert_snapshot!(rendered);

    let out = lagc_in_cache(&[
        "run",
        "examples/paper.lag",
        "--rtol",
        "1e-300",
        "--samples",
        "2",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("warning: --rtol 1e-300 is below the rounding of f64"),
        "{stderr}"
    );
}

/// Issue 15, item 10: a literal that underflows to 0 is a warning (the
/// model still checks, exit 0) located at the literal, on every command;
/// beside an error it is reported in source order.
/// `atan2` in a position constraint (a helix written in Cartesian
/// coordinates): warned at check time, once, and the check succeeds.
#[test]
fn atan2_in_a_position_constraint_is_warned_about() {
    let out = lagc(&["check", "tests/data/warnings/atan2_helix.lag"]);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert_eq!(stderr.matches("warning[W0002]").count(), 1, "{stderr}");
    insta::assert_snapshot!(stderr);
}

#[test]
fn a_literal_that_underflows_is_warned_about() {
    let file = "tests/data/warnings/literal_underflows.lag";
    let out = lagc(&["check", file]);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert_eq!(stderr.matches("warning[W0001]").count(), 1, "{stderr}");
    let derive = lagc(&["derive", file]);
    assert_eq!(derive.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&derive.stderr)
        .starts_with(&stderr[..stderr.find("\n\n").unwrap()]));

    let with_error =
        std::env::temp_dir().join(format!("lagc-underflow-{}.lag", std::process::id()));
    std::fs::write(
        &with_error,
        "coord x;\nparam a = 1e-400;\nlagrangian = x'^2 - k;\n",
    )
    .unwrap();
    let out = lagc(&["check", &with_error.to_string_lossy()]);
    let _ = std::fs::remove_file(&with_error);
    let errors = String::from_utf8_lossy(&out.stderr)
        .replace(&*with_error.to_string_lossy(), "with_error.lag");
    assert_eq!(out.status.code(), Some(1), "{errors}");
    insta::assert_snapshot!(format!("{stderr}\n{errors}"));
}

/// A stand-in for cargo that fails the way a machine without a linker does.
#[cfg(unix)]
#[test]
fn a_build_that_fails_for_the_machine_is_explained_in_lagcs_words() {
    use std::os::unix::fs::PermissionsExt;
    let dir = crate::root().join("target/lagc-cache-fake-cargo");
    std::fs::create_dir_all(&dir).unwrap();
    let fake = dir.join("cargo");
    std::fs::write(
        &fake,
        "#!/bin/sh\necho '   Compiling lag-paper v0.1.0' >&2\n\
         echo 'error: linker `cc` not found' >&2\n\
         echo '  = note: No such file or directory (os error 2)' >&2\nexit 101\n",
    )
    .unwrap();
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_lagc"))
        .args(["run", "examples/paper.lag"])
        .current_dir(crate::root())
        .env("CARGO", &fake)
        .env("LAGC_CACHE_DIR", dir.join("cache"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("error: linker `cc` not found")
            && stderr.contains("no C linker (`cc`) was found")
            && stderr.contains("build-essential"),
        "{stderr}"
    );
    assert!(output.stdout.is_empty());
}

/// Issue 28: the note N0001 (the local field method; about nine lines) is
/// shown when `lagc run` builds the model's crate, not on every run; lagc's
/// own `--verbose` shows it on every run and is not passed to the binary.
#[test]
fn the_local_field_note_is_shown_once_per_build_or_with_verbose() {
    let cache = crate::root().join("target/lagc-cache");
    let dir = crate::root().join("target/notes-once");
    std::fs::create_dir_all(&dir).unwrap();
    // A new text (so a new build) on every test run, at one path (so one
    // crate in the cache).
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos();
    let model = std::fs::read_to_string(crate::root().join("examples/knife_edge.lag")).unwrap();
    let file = dir.join("knife_edge.lag");
    std::fs::write(&file, format!("{model}// {stamp}\n")).unwrap();
    let run = |extra: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_lagc"))
            .arg("run")
            .arg(&file)
            .args(["--samples", "3"])
            .args(extra)
            .env("LAGC_CACHE_DIR", &cache)
            .env("RUSTFLAGS", "-D warnings")
            .output()
            .expect("lagc runs");
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(0), "{stderr}");
        (String::from_utf8(out.stdout).unwrap(), stderr)
    };
    let note = "note[N0001]";
    let (built, stderr) = run(&[]);
    assert!(stderr.contains(note), "the build shows the note:\n{stderr}");
    assert_eq!(stderr.matches(note).count(), 1);
    let (again, stderr) = run(&[]);
    assert!(!stderr.contains(note), "shown again:\n{stderr}");
    assert_eq!(again, built);
    let (verbose, stderr) = run(&["--verbose"]);
    assert!(stderr.contains(note), "--verbose shows it:\n{stderr}");
    assert_eq!(verbose, built);
    let (_, help) = {
        let out = Command::new(env!("CARGO_BIN_EXE_lagc"))
            .arg("run")
            .arg(&file)
            .arg("--help")
            .env("LAGC_CACHE_DIR", &cache)
            .output()
            .expect("lagc runs");
        (
            out.status,
            String::from_utf8_lossy(&out.stdout).into_owned(),
        )
    };
    assert!(help.contains("--verbose"), "{help}");
}
