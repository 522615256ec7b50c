//! Every example's generated crate: generated, compiled warning-free with
//! one shared target directory and one shared copy of the runtime crate
//! (which compiles once), run with both methods at rtol 1e-10, and
//! compared with the model's exact solution.

use lagc::emit::{EmitOptions, GeneratedCrate};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Where the tests keep generated crates, their runtime and their target.
fn base() -> PathBuf {
    root().join("target/generated-crates")
}

pub(crate) fn generate(name: &str) -> GeneratedCrate {
    generate_file(&root().join(format!("examples/{name}.lag")))
}

/// The crate of the model in `path`, named by the file's stem, laid out
/// as `lagc run` lays out its cache (`crates/<package>` beside
/// `runtime`).
pub(crate) fn generate_file(path: &Path) -> GeneratedCrate {
    let name = path.file_stem().unwrap().to_str().unwrap();
    let source = std::fs::read_to_string(path).unwrap();
    let options = EmitOptions {
        model_name: name.to_string(),
        source_hash: "test".to_string(),
        runtime_path: "../../runtime".to_string(),
        package_key: None,
    };
    let (generated, _notes) =
        lagc::compile(&source, &options).unwrap_or_else(|d| panic!("{name}: {d:?}"));
    generated
}

fn write_file(target: &Path, contents: &str) {
    std::fs::create_dir_all(target.parent().unwrap()).unwrap();
    if std::fs::read(target).is_ok_and(|old| old == contents.as_bytes()) {
        return;
    }
    std::fs::write(target, contents).unwrap();
}

fn write(generated: &GeneratedCrate, dir: &Path) {
    for (path, contents) in &generated.files {
        write_file(&dir.join(path), contents);
    }
    let runtime = base().join("runtime");
    for (path, contents) in lagc::emit::runtime_files() {
        write_file(&runtime.join(path), contents);
    }
    remove_stale_sources(&runtime);
}

/// Removes the shared runtime's `.rs` files that are no longer the
/// runtime's (a module that moved leaves its old file, and `method.rs`
/// beside `method/mod.rs` does not build).
fn remove_stale_sources(runtime: &Path) {
    let known: Vec<PathBuf> = lagc::emit::runtime_files()
        .map(|(path, _)| runtime.join(path))
        .collect();
    let mut folders = vec![runtime.join("src")];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") && !known.contains(&path) {
                std::fs::remove_file(&path).unwrap();
            }
        }
    }
}

/// Builds the crate (release: the runs below dominate a debug build's
/// saving, measured) with warnings as errors, offline; returns the binary.
pub(crate) fn build(name: &str) -> PathBuf {
    build_file(&root().join(format!("examples/{name}.lag")))
}

/// [`build`] for the model in any file.
pub(crate) fn build_file(path: &Path) -> PathBuf {
    let generated = generate_file(path);
    let name = &generated.package;
    let dir = base().join("crates").join(&generated.package);
    write(&generated, &dir);
    let target = base().join("target");
    cargo_build(&dir.join("Cargo.toml"), &target, name);
    target.join("release").join(&generated.package)
}

/// `cargo build --release --offline` of the crate at `manifest` into the
/// shared `target`, warnings as errors; panics naming `what` on failure.
pub(crate) fn cargo_build(manifest: &Path, target: &Path, what: &str) {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let output = Command::new(&cargo)
        .args([
            "build",
            "--release",
            "--offline",
            "--quiet",
            "--manifest-path",
        ])
        .arg(manifest)
        .env("CARGO_TARGET_DIR", target)
        .env("RUSTFLAGS", "-D warnings")
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{what}: cargo build failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

struct Run {
    csv: Vec<Vec<f64>>,
    stderr: String,
}

fn run(binary: &Path, args: &[&str]) -> Result<Run, String> {
    let output = Command::new(binary).args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    if !output.status.success() {
        return Err(stderr);
    }
    let stdout = String::from_utf8(output.stdout).unwrap();
    let csv = stdout
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    Ok(Run { csv, stderr })
}

/// The summary's `constraints kept: largest residual R` (models whose
/// constraints fix state components).
fn constraint_residual(stderr: &str) -> Option<f64> {
    let rest = stderr.split("constraints kept: largest residual ").nth(1)?;
    rest.split_whitespace().next()?.parse().ok()
}

fn exact_error(run: &Run) -> f64 {
    crate::exact_error(&run.stderr)
}

/// Every example's `// expect: field|direct … within TOL at rtol R atol A`
/// lines: the generated binary, run so, exits 0 and meets the model's
/// `exact` lines to TOL. (The long runs' error is tolerance-proportional,
/// ~100–230·rtol, so they state rtol 1e-11, atol 1e-14.)
#[test]
fn every_example_meets_its_exact_solution_as_its_header_states() {
    let mut report = String::new();
    let mut failures = Vec::new();
    let mut runs = 0;
    for path in crate::expect::lag_files("examples") {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let stated: Vec<_> = crate::expect::expectations_of(&path)
            .into_iter()
            .filter_map(|e| match e {
                crate::expect::Expectation::Within { run, tol } => Some((run, tol)),
                _ => None,
            })
            .collect();
        if stated.is_empty() {
            continue;
        }
        let binary = build_file(&path);
        for (how, tol) in stated {
            let args = how.args();
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let label = format!("{name} {}", args.join(" "));
            runs += 1;
            let (error, carried) = match run(&binary, &args) {
                Ok(result) => (exact_error(&result), constraint_residual(&result.stderr)),
                Err(stderr) => {
                    failures.push(format!("{label}: {stderr}"));
                    continue;
                }
            };
            // No run ends with exit 0 having carried its state far from
            // its constraints (issue 28: 1e-6 at the most, or 10·rtol for
            // a loose tolerance).
            if let Some(residual) = carried {
                let rtol: f64 = args
                    .windows(2)
                    .find(|w| w[0] == "--rtol")
                    .and_then(|w| w[1].parse().ok())
                    .unwrap_or(1e-10);
                let bound = (10.0 * rtol).max(1e-6);
                report.push_str(&format!(
                    "{label}: constraints kept within {residual:.1e}\n"
                ));
                if residual.is_nan() || residual > bound {
                    failures.push(format!(
                        "{label}: constraint residual {residual:e} > {bound:e}"
                    ));
                }
            }
            report.push_str(&format!("{label}: {error:.2e} (stated {tol:e})\n"));
            if error.is_nan() || error > tol {
                failures.push(format!("{label}: {error:e} > {tol:e}"));
            }
        }
    }
    eprintln!("{report}");
    assert!(runs >= 40, "{runs} runs");
    assert!(failures.is_empty(), "{failures:?}\n{report}");
}

#[test]
fn paper_field_solution_does_not_depend_on_the_anchor() {
    let binary = build("paper");
    let zero = run(&binary, &["--samples", "26"]).unwrap();
    let other = run(&binary, &["--samples", "26", "--anchor", "0.7"]).unwrap();
    assert_eq!(zero.csv.len(), 26);
    let mut largest = 0.0_f64;
    for (a, b) in zero.csv.iter().zip(&other.csv) {
        for (x, y) in a.iter().zip(b) {
            largest = largest.max((x - y).abs() / x.abs().max(1.0));
        }
    }
    assert!(largest <= 1e-9, "anchors differ by {largest:e}");
}

/// `--step-to-times` (issue 29): the rocket's 11 samples, stepped onto, carry
/// the step ends' error instead of the continuous extension's (7–25×
/// smaller at rtol 1e-10, direct and field), and the samples are the same
/// times.
#[test]
fn stepping_onto_the_output_times_makes_the_samples_as_accurate_as_the_steps() {
    let binary = build("vertical_rocket");
    for method in ["direct", "field"] {
        let args = [
            "--method",
            method,
            "--rtol",
            "1e-10",
            "--atol",
            "1e-12",
            "--samples",
            "11",
        ];
        let free = run(&binary, &args).unwrap();
        let stepped = run(&binary, &[&args[..], &["--step-to-times"]].concat()).unwrap();
        let times = |r: &Run| r.csv.iter().map(|row| row[0]).collect::<Vec<f64>>();
        assert_eq!(times(&free), times(&stepped));
        let (free, stepped) = (exact_error(&free), exact_error(&stepped));
        assert!(
            stepped * 3.0 < free,
            "{method}: {stepped:e} stepped onto the times, {free:e} interpolated"
        );
    }
}

/// `--no-global-error`: the run without its estimate (the peers' and a
/// sweep's measure) prints the same states byte for byte, by both methods,
/// on an affine constrained model, a non-affine constrained one, an affine
/// one, a non-affine free one and one with impacts; the summary has no
/// estimate, and the run costs no more evaluations.
#[test]
fn a_run_without_its_global_error_estimate_has_the_same_states() {
    let evaluations = |stderr: &str| -> f64 {
        let json = stderr.lines().last().unwrap();
        let key = "\"rhs_evaluations\":";
        let from = json.find(key).unwrap() + key.len();
        json[from..].split(',').next().unwrap().parse().unwrap()
    };
    for name in [
        "paper",
        "knife_edge",
        "damped_oscillator",
        "double_pendulum_energy",
        "bouncing_ball",
    ] {
        let binary = build(name);
        for method in ["field", "direct"] {
            let args = ["--method", method, "--rtol", "1e-9", "--summary", "json"];
            let output = |extra: &[&str]| {
                let out = Command::new(&binary)
                    .args(args)
                    .args(extra)
                    .output()
                    .unwrap();
                assert!(out.status.success(), "{name} {method}");
                (out.stdout, String::from_utf8(out.stderr).unwrap())
            };
            let (with, with_summary) = output(&[]);
            let (without, without_summary) = output(&["--no-global-error"]);
            assert!(with == without, "{name} {method}: the states differ");
            assert!(
                !with_summary.contains("\"global_error_estimate\":null"),
                "{name} {method}: {with_summary}"
            );
            assert!(
                without_summary.contains("\"global_error_estimate\":null"),
                "{name} {method}: {without_summary}"
            );
            assert!(
                evaluations(&without_summary) <= evaluations(&with_summary),
                "{name} {method}"
            );
        }
    }
}

#[test]
fn param_override_recomputes_later_params_and_bad_usage_exits_2() {
    // damped_oscillator: gam = c/(2m), wd from it; the exact solution uses
    // them, so a wrong recomputation shows as a large error.
    let binary = build("damped_oscillator");
    let result = run(&binary, &["--param", "c=1", "--param", "k=9"]).unwrap();
    assert!(exact_error(&result) <= 1e-8, "{}", result.stderr);
    let output = Command::new(&binary)
        .args(["--param", "nope=1"])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
}

fn lib_rs(name: &str) -> String {
    generate(name).file("src/lib.rs").unwrap().to_string()
}

#[test]
fn generated_code_holds_only_what_the_system_needs() {
    // The paper: explicit and affine; no Newton, no mass-matrix solve; its
    // reduced system has no mass left (M divides out); a linear
    // coefficient system with f1 and f2 at rest (F ≡ 0).
    let paper = lib_rs("paper");
    assert!(!paper.contains("newton") && !paper.contains("mass_system"));
    assert!(paper.contains("df[0] = 0.0_f64;") && paper.contains("df[1] = 0.0_f64;"));
    assert!(paper.contains("const COEFFICIENTS_LINEAR: bool = true;"));
    // A mass law that stays in the equations is evaluated by the right
    // side; one that divides out is not (it is emitted only to name a mass
    // that reaches zero).
    let rhs_body = |lib: &str| {
        lib.split("fn rhs(")
            .nth(1)
            .unwrap()
            .split("\n    }")
            .next()
            .unwrap()
            .to_string()
    };
    assert!(rhs_body(&lib_rs("mass_loss_stiff_spring")).contains("mass_m("));
    assert!(!rhs_body(&lib_rs("damped_oscillator")).contains("mass_"));
    // The oscillator's coefficient system is Riccati.
    assert!(lib_rs("damped_oscillator").contains("const COEFFICIENTS_LINEAR: bool = false;"));
    // Non-linear highest derivatives: Newton, no coefficient system.
    let implicit = lib_rs("nonlinear_second_order");
    assert!(implicit.contains("highest::newton") && !implicit.contains("fn coefficients"));
    // Non-affine systems have no coefficient system.
    assert!(!lib_rs("knife_edge").contains("const AFFINE"));
    // A right side over lanes only where a non-affine ensemble can run
    // (one mode, no switches, not affine).
    assert!(lib_rs("knife_edge").contains("fn rhs_lanes("));
    assert!(!paper.contains("rhs_lanes") && !implicit.contains("rhs_lanes"));
    assert!(!lib_rs("coulomb_friction").contains("rhs_lanes"));
    // Exact-solution code only with `exact`.
    assert!(paper.contains("fn exact("));
    // Impact code only with `when`; the derivatives the constraints fix
    // are recomputed after a reset only where there are some.
    assert!(!paper.contains("impact") && !paper.contains("IMPACTS"));
    let reset = item(&lib_rs("bouncing_ball"), "impact_reset");
    assert!(reset.contains("out[1] = -e * y_d1;") && !reset.contains("out[0]"));
    assert!(item(&lib_rs("constrained_wall"), "impact_reset").contains("out[3] = t * q1_d1;"));
    // Nothing model-independent: the runtime is a dependency.
    assert!(
        paper.lines().count() < 400,
        "{} lines",
        paper.lines().count()
    );
    let main = generate("paper").file("src/main.rs").unwrap().to_string();
    assert_eq!(
        main.lines()
            .filter(|l| l.contains(';') || l.contains("::main"))
            .count(),
        1
    );
}

/// A power whose exponent is the state (`f64::powf` of a param by a
/// lane value would not type-check): no right side over lanes, and the
/// crate builds warning-free (its ensemble steps members one at a time).
#[test]
fn a_power_of_the_state_builds_without_a_right_side_over_lanes() {
    let dir = std::env::temp_dir().join(format!("lagc-power-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("power_of_the_state.lag");
    std::fs::write(
        &path,
        "param a = 2;\ncoord x;\nlagrangian = x'^2 / 2;\nforce x = -a^x - x';\n\
         initial x = 0.5, x' = 0;\ntime 0 .. 1;\n",
    )
    .unwrap();
    let lib = generate_file(&path).file("src/lib.rs").unwrap().to_string();
    assert!(lib.contains(".powf("), "{lib}");
    assert!(!lib.contains("rhs_lanes"));
    let binary = build_file(&path);
    let out = std::process::Command::new(binary)
        .args(["--ensemble", "8", "--spread", "1e-2"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The generated item `fn NAME(` of `lib`, up to its end.
fn item(lib: &str, name: &str) -> String {
    let start = lib
        .find(&format!("fn {name}("))
        .unwrap_or_else(|| panic!("no fn {name}"));
    let end = lib[start..].find("\n    }\n").unwrap();
    lib[start..start + end].to_string()
}

#[test]
fn an_unrelated_change_renames_nothing_in_other_items() {
    // The paper without its `exact` lines: the items it still has are the
    // same text (the shared sub-expressions of each item are named in a
    // scope of that item's own, not numbered across the file).
    let source = std::fs::read_to_string(root().join("examples/paper.lag")).unwrap();
    let without: String = source
        .lines()
        .filter(|l| !l.starts_with("exact "))
        .map(|l| format!("{l}\n"))
        .collect();
    let dir = std::env::temp_dir().join(format!("lagc-namer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("paper.lag");
    std::fs::write(&path, without).unwrap();
    let changed = generate_file(&path).file("src/lib.rs").unwrap().to_string();
    let _ = std::fs::remove_dir_all(&dir);
    let original = lib_rs("paper");
    assert!(original.contains("fn exact(") && !changed.contains("fn exact("));
    for name in [
        "rhs",
        "jacobian",
        "time_partial",
        "linearize",
        "coefficients",
    ] {
        assert_eq!(item(&original, name), item(&changed, name), "fn {name}");
    }
}

#[test]
fn generated_crates_pass_clippy() {
    // Contrasting systems: affine/linear, Riccati with a mass law, local
    // field, Newton, k = 3 consistency, impacts (with a constraint), a mass
    // law of the state; several candidates with a numeric solve of each
    // mode's mass matrix, and with every construct; holonomic constraints
    // solved together in several modes (Newton on the closure, projection);
    // a mass matrix solved at run time with dependent rows (`linearize`
    // on the stack).
    for name in [
        "rolling_disk_3d",
        "paper",
        "incline_bounce",
        "constrained_wall",
        "mass_loss_stiff_spring",
        "knife_edge",
        "nonlinear_second_order",
        "third_order_constraint",
        "cayley_chain",
        "four_bar_closure",
    ] {
        clippy_file(&root().join(format!("examples/{name}.lag")));
    }
    for name in ["parallel_velocities", "candidates_combined"] {
        clippy_file(&root().join(format!("tests/data/v2/{name}.lag")));
    }
}

/// `cargo clippy` of the crate of the model in `path`, warnings as errors.
pub(crate) fn clippy_file(path: &Path) {
    let generated = generate_file(path);
    let base = root().join("target/generated-crates");
    let dir = base.join("crates").join(&generated.package);
    write(&generated, &dir);
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let output = Command::new(&cargo)
        .args(["clippy", "--release", "--quiet", "--manifest-path"])
        .arg(dir.join("Cargo.toml"))
        .env("CARGO_TARGET_DIR", base.join("target"))
        .env("RUSTFLAGS", "-D warnings")
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}: clippy:\n{}",
        path.display(),
        String::from_utf8_lossy(&output.stderr)
    );
}

/// `--ensemble K`: one field for K initial states agrees with K direct
/// integrations (a linear and a Riccati coefficient system) to the
/// tolerance; a non-affine system's members, corrected along the field,
/// agree with theirs to 10·rtol whatever the spread (they were first order
/// in it: more tests in `ensemble.rs`).
#[test]
fn ensemble_mode_agrees_with_direct_integrations() {
    for name in ["paper", "damped_oscillator"] {
        let binary = build(name);
        for k in ["1", "3", "20"] {
            let output = Command::new(&binary)
                .args(["--ensemble", k, "--summary", "json", "--samples", "21"])
                .output()
                .unwrap();
            let stderr = String::from_utf8_lossy(&output.stderr);
            assert!(output.status.success(), "{name}: {stderr}");
            assert!(output.stdout.is_empty());
            let difference: f64 = stderr
                .split("\"largest_difference\":")
                .nth(1)
                .and_then(|rest| rest.split([',', '}']).next())
                .and_then(|v| v.parse().ok())
                .unwrap_or_else(|| panic!("{name}: {stderr}"));
            assert!(difference <= 1e-8, "{name} K = {k}: {difference:e}");
            assert!(stderr.contains(&format!("\"ensemble\":{k},")), "{stderr}");
        }
    }
    // The knife edge: y' = tan(θ) x', not affine in the state.
    let binary = build("knife_edge");
    let difference = |spread: &str| -> f64 {
        let output = Command::new(&binary)
            .args(["--ensemble", "4", "--spread", spread, "--summary", "json"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        assert!(output.status.success(), "{stderr}");
        stderr
            .split("\"largest_difference\":")
            .nth(1)
            .and_then(|rest| rest.split([',', '}']).next())
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{stderr}"))
    };
    let (coarse, fine) = (difference("1e-2"), difference("1e-3"));
    assert!(
        coarse <= 1e-9 && fine <= 1e-9,
        "spread 1e-2: {coarse:e}, 1e-3: {fine:e}"
    );
}

/// lagc carries every file of the runtime crate: one missing from its
/// list would make `lagc build -o` write a runtime that does not build.
#[test]
fn the_emitter_carries_every_runtime_file() {
    fn walk(dir: &Path, base: &Path, out: &mut Vec<String>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, base, out);
            } else {
                out.push(path.strip_prefix(base).unwrap().display().to_string());
            }
        }
    }
    let runtime = root().join("runtime");
    let mut on_disk = vec!["Cargo.toml".to_string()];
    walk(&runtime.join("src"), &runtime, &mut on_disk);
    on_disk.sort();
    let mut known: Vec<String> = lagc::emit::runtime_files()
        .map(|(p, _)| p.to_string())
        .collect();
    known.sort();
    assert_eq!(known, on_disk);
}

/// The numeric LU solve for the highest derivatives (s > 2, a full mass
/// matrix: the 3-link pendulum) checked by an independent invariant: the
/// energy `T + V` is conserved along the generated crate's trajectory, by
/// direct integration and by the (local) field method, and both agree.
#[test]
fn implicit_linear_solve_conserves_the_pendulum_energy() {
    let binary = build_file(&root().join("benches/data/pendulum_3.lag"));
    let lib = generate_file(&root().join("benches/data/pendulum_3.lag"))
        .files
        .into_iter()
        .find(|(path, _)| path == "src/lib.rs")
        .unwrap()
        .1;
    assert!(
        lib.contains("fn mass_system"),
        "the mass-matrix solve is emitted"
    );
    let g = 9.81;
    // Columns: t, th1, th2, th3, th1', th2', th3'.
    let energy = |row: &[f64]| {
        let (th, om) = (&row[1..4], &row[4..7]);
        let (mut vx, mut vy, mut kinetic) = (0.0, 0.0, 0.0);
        for i in 0..3 {
            vx += th[i].cos() * om[i];
            vy += th[i].sin() * om[i];
            kinetic += 0.5 * (vx * vx + vy * vy);
        }
        kinetic - g * (3.0 * th[0].cos() + 2.0 * th[1].cos() + th[2].cos())
    };
    let mut finals = Vec::new();
    for method in ["direct", "field"] {
        let run = run(
            &binary,
            &["--method", method, "--rtol", "1e-10", "--atol", "1e-12"],
        )
        .unwrap_or_else(|e| panic!("{method}: {e}"));
        let e0 = energy(&run.csv[0]);
        let drift = run
            .csv
            .iter()
            .map(|row| (energy(row) - e0).abs())
            .fold(0.0, f64::max);
        assert!(
            drift <= 1e-7 * e0.abs(),
            "{method}: energy drift {drift:e} of {e0}"
        );
        finals.push(run.csv.last().unwrap().clone());
    }
    let difference = finals[0]
        .iter()
        .zip(&finals[1])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        difference <= 1e-7,
        "direct and field differ by {difference:e}"
    );
}

/// Issue 15, item 12: Rust keywords as model names (`self` and `Self`,
/// which both sanitize to `self_`, `super`, `crate`, `fn`, `type`) give a
/// crate that builds with warnings as errors and runs, the CSV header
/// keeping the model's own names.
#[test]
fn keyword_names_build_warning_free() {
    let binary = build_file(&root().join("tests/data/keyword_names.lag"));
    let run = run(&binary, &["--samples", "3"]).unwrap_or_else(|stderr| panic!("{stderr}"));
    assert_eq!(run.csv.len(), 3);
    let output = Command::new(&binary)
        .args(["--samples", "2"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(stdout.lines().next(), Some("t,self,super,self',super'"));
}

/// Issue 13: `Initial` names the state by the model's names (a derivative
/// `q'` as `q_dot`, `q''` as `q_ddot`; a clash numbered, coordinates
/// first; keywords as the namer writes them), and each field's doc says
/// where its value comes from: the model's value, the constraints, or the
/// equations of motion.
#[test]
fn initial_fields_name_the_state() {
    let paper = lib_rs("paper");
    for field in ["q1", "q2", "q1_dot", "q2_dot"] {
        assert!(
            paper.contains(&format!("pub {field}: Option<f64>,")),
            "{field}"
        );
    }
    assert!(paper.contains("/// `q1'` at `t0`; `None`: the model's value, `1`."));
    assert!(paper.contains("fixed by the constraints as `q2' = t*q1'`"));
    assert!(paper.contains("vec![self.q1, self.q2, self.q1_dot, self.q2_dot]"));
    assert!(paper.contains("pub fn solve(\n    params: &Params,\n    initial: &Initial,"));

    let third = lib_rs("third_order_constraint");
    assert!(third.contains("pub x_ddot: Option<f64>,"));
    assert!(third.contains("pub y_ddot: Option<f64>,"));
    assert!(third.contains("fixed by the equations of motion"));

    let clash = generate_file(&root().join("tests/data/initial_name_clash.lag"));
    let clash = clash.file("src/lib.rs").unwrap();
    assert!(clash.contains("vec![self.a, self.a_dot, self.a_dot_2, self.a_dot_dot]"));

    let keywords = generate_file(&root().join("tests/data/keyword_names.lag"));
    let keywords = keywords.file("src/lib.rs").unwrap();
    assert!(keywords.contains("vec![self.self_, self.super_, self.self_dot, self.super_dot]"));
}

/// Issue 13: `cargo doc` of a generated crate (its runtime included) gives
/// no warning: the library API a user reads.
#[test]
fn generated_crates_document_without_warnings() {
    for path in [
        root().join("examples/paper.lag"),
        root().join("examples/third_order_constraint.lag"),
        root().join("tests/data/initial_name_clash.lag"),
    ] {
        let generated = generate_file(&path);
        let dir = base().join("crates").join(&generated.package);
        write(&generated, &dir);
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let output = Command::new(&cargo)
            .args(["doc", "--offline", "--quiet", "--manifest-path"])
            .arg(dir.join("Cargo.toml"))
            .env("CARGO_TARGET_DIR", base().join("target"))
            .env("RUSTDOCFLAGS", "-D warnings")
            .output()
            .unwrap();
        assert!(
            output.status.success() && output.stderr.is_empty(),
            "{}: cargo doc:\n{}",
            path.display(),
            String::from_utf8_lossy(&output.stderr)
        );
    }
}
