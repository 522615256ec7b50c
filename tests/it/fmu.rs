//! FMUs through a real importer (issue 26): `lagc build --fmu` on the
//! paper's example, a model driven by an input, a `stop when` and a model
//! made to fail; then FMPy 0.3.32 (from PyPI, in a venv under `target/`)
//! validates them and simulates them against closed forms
//! (`tests/fmu/check_fmus.py`): changed params and initial values as start
//! values, an input stepping through FMPy's input signal, the stop time,
//! the failure's message through the logger with fmi2Error, three
//! instances of two models in one process, fmi2Reset, saved states, bad
//! calls; the FMI cross-check files of four models checked by FMPy's
//! cross-check validation (`tests/fmu/cross_check.py`).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

/// The models, by their path under the repository.
const MODELS: [&str; 6] = [
    "examples/paper.lag",
    "examples/damped_oscillator.lag",
    "tests/data/driven_oscillator.lag",
    "tests/data/stepped_oscillator.lag",
    "examples/rocket_burnout_landing.lag",
    "tests/data/runtime_failures/newton_no_root.lag",
];

fn target() -> PathBuf {
    crate::root().join("target/fmu-tests")
}

fn checked(output: Output, what: &str) -> Output {
    assert!(
        output.status.success(),
        "{what} failed:\n{}\n{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

/// A venv with FMPy and SciPy (the closed forms' quadratures), made once.
fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| {
        let venv = crate::root().join("target/fmpy-venv");
        let python = venv.join("bin/python");
        if !python.exists() {
            let made = Command::new("python3.11")
                .args(["-m", "venv"])
                .arg(&venv)
                .output()
                .expect("python3.11 runs");
            checked(made, "python3.11 -m venv");
        }
        let pip = Command::new(&python)
            .args(["-m", "pip", "install", "--quiet", "fmpy==0.3.32", "scipy"])
            .output()
            .unwrap();
        checked(pip, "pip install fmpy scipy");
        python
    })
}

/// Every model's FMU, built once by `lagc build --fmu`.
fn fmus() -> &'static Path {
    static FMUS: OnceLock<PathBuf> = OnceLock::new();
    FMUS.get_or_init(|| {
        let dir = target();
        std::fs::create_dir_all(&dir).unwrap();
        for model in MODELS {
            let stem = Path::new(model).file_stem().unwrap().to_str().unwrap();
            let out = Command::new(env!("CARGO_BIN_EXE_lagc"))
                .args(["build", model, "--fmu", "-o"])
                .arg(dir.join(format!("{stem}.fmu")))
                .current_dir(crate::root())
                .env("LAGC_CACHE_DIR", crate::root().join("target/lagc-cache"))
                .output()
                .unwrap();
            checked(out, &format!("lagc build {model} --fmu"));
        }
        dir
    })
}

fn check(case: &str) -> String {
    let python = python();
    let out = Command::new(python)
        .arg(crate::root().join("tests/fmu/check_fmus.py"))
        .arg(case)
        .arg(fmus())
        .output()
        .unwrap();
    let out = checked(out, &format!("check_fmus.py {case}"));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    eprintln!("{stdout}");
    stdout
}

/// Builds the FMU of `model` (a path under the repository) into `dir`.
fn build_fmu(model: &Path, dir: &Path) -> PathBuf {
    let stem = model.file_stem().unwrap().to_str().unwrap();
    let fmu = dir.join(format!("{stem}.fmu"));
    let out = Command::new(env!("CARGO_BIN_EXE_lagc"))
        .args(["build"])
        .arg(model)
        .args(["--fmu", "-o"])
        .arg(&fmu)
        .current_dir(crate::root())
        .env("LAGC_CACHE_DIR", crate::root().join("target/lagc-cache"))
        .output()
        .unwrap();
    checked(out, &format!("lagc build {} --fmu", model.display()));
    fmu
}

#[test]
fn the_fmu_of_every_example_passes_fmpy_validate() {
    let fmpy = python().with_file_name("fmpy");
    let dir = target().join("examples");
    std::fs::create_dir_all(&dir).unwrap();
    for model in crate::expect::lag_files("examples") {
        let fmu = build_fmu(&model, &dir);
        let out = checked(
            Command::new(&fmpy)
                .arg("validate")
                .arg(&fmu)
                .output()
                .unwrap(),
            "fmpy validate",
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            stdout.contains("No problems found."),
            "{}: {stdout}",
            model.display()
        );
    }
}

#[test]
fn fmpy_simulates_the_examples_as_lagc_run_does() {
    // Variable mass and non-holonomic (the paper), a k = 2 constraint, an
    // implicit constraint with candidates that switch, a mass law of the
    // state, a rolling disk, a non-linear implicit constraint: FMPy's
    // rows against lagc run's CSV at the same tolerance and times.
    let dir = target().join("versus-run");
    std::fs::create_dir_all(&dir).unwrap();
    for name in [
        "paper",
        "second_order_constraint",
        "knife_edge_turning",
        "cayley_chain",
        "rolling_disk",
        "constant_speed_implicit",
    ] {
        let model = crate::root().join(format!("examples/{name}.lag"));
        let fmu = build_fmu(&model, &dir);
        let run = Command::new(env!("CARGO_BIN_EXE_lagc"))
            .arg("run")
            .arg(&model)
            .args(["--rtol", "1e-10", "--atol", "1e-12"])
            .env("LAGC_CACHE_DIR", crate::root().join("target/lagc-cache"))
            .output()
            .unwrap();
        let run = checked(run, &format!("lagc run {name}"));
        let csv = dir.join(format!("{name}.csv"));
        std::fs::write(&csv, &run.stdout).unwrap();
        let out = Command::new(python())
            .arg(crate::root().join("tests/fmu/check_fmus.py"))
            .arg("versus_run")
            .arg(&fmu)
            .arg(&csv)
            .output()
            .unwrap();
        let out = checked(out, &format!("versus_run {name}"));
        eprint!("{}", String::from_utf8_lossy(&out.stdout));
    }
}

#[test]
fn every_fmu_passes_fmpy_validate_and_exports_the_34_functions() {
    let fmpy = python().with_file_name("fmpy");
    for model in MODELS {
        let stem = Path::new(model).file_stem().unwrap().to_str().unwrap();
        let fmu = fmus().join(format!("{stem}.fmu"));
        let out = checked(
            Command::new(&fmpy)
                .arg("validate")
                .arg(&fmu)
                .output()
                .unwrap(),
            "fmpy validate",
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains("No problems found."), "{stem}: {stdout}");
        // The archive as Python's zipfile reads it, and the library's
        // exported symbols (FMPy looks all of them up).
        let script = "import sys, zipfile, ctypes, tempfile\n\
            z = zipfile.ZipFile(sys.argv[1]); assert z.testzip() is None\n\
            names = z.namelist(); so = [n for n in names if n.endswith('.so')][0]\n\
            assert sorted(names) == ['binaries/linux64/' + so.split('/')[-1], 'modelDescription.xml'], names\n\
            d = tempfile.mkdtemp(); lib = ctypes.CDLL(z.extract(so, d))\n\
            fns = '''GetTypesPlatform GetVersion SetDebugLogging Instantiate FreeInstance SetupExperiment\n\
            EnterInitializationMode ExitInitializationMode Terminate Reset GetReal GetInteger GetBoolean\n\
            GetString SetReal SetInteger SetBoolean SetString GetFMUstate SetFMUstate FreeFMUstate\n\
            SerializedFMUstateSize SerializeFMUstate DeSerializeFMUstate GetDirectionalDerivative\n\
            SetRealInputDerivatives GetRealOutputDerivatives DoStep CancelStep GetStatus GetRealStatus\n\
            GetIntegerStatus GetBooleanStatus GetStringStatus'''.split()\n\
            assert len(fns) == 34\n\
            for f in fns: getattr(lib, 'fmi2' + f)\n\
            print(len(fns))\n";
        let out = checked(
            Command::new(python())
                .args(["-c", script])
                .arg(&fmu)
                .output()
                .unwrap(),
            "the archive and its library",
        );
        assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), "34");
    }
}

#[test]
fn the_papers_fmu_meets_the_exact_solution_with_changed_params_and_initial_values() {
    let out = check("paper");
    assert!(out.contains("largest error"), "{out}");
}

#[test]
fn an_input_stepped_through_fmpy_drives_the_oscillator_exactly_by_pieces() {
    check("driven");
}

#[test]
fn a_stop_ends_the_simulation_and_a_failure_is_an_error_with_lagcs_message() {
    check("stop_and_failure");
}

#[test]
fn a_tunable_param_set_between_steps_restarts_and_saved_states_come_back_bit_for_bit() {
    let out = check("tuning");
    assert!(out.contains("bit for bit"), "{out}");
}

#[test]
fn instances_of_two_models_in_one_process_are_independent() {
    check("two_instances");
}

#[test]
fn lagc_carries_every_file_of_the_fmu_library() {
    let carried: Vec<&str> = lagc::emit::fmu_library_files().map(|(p, _)| p).collect();
    let dir = crate::root().join("fmu/src");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        assert!(
            carried.contains(&format!("src/{name}").as_str()),
            "src/emit/fmu.rs does not carry fmu/src/{name}"
        );
    }
    for (path, contents) in lagc::emit::fmu_library_files() {
        let on_disk = std::fs::read_to_string(crate::root().join("fmu").join(path)).unwrap();
        assert_eq!(on_disk, contents, "{path}");
    }
}

/// `steps: N (+R rejected); right-side evaluations: E` of a summary, or
/// `N steps (+R rejected), E right-side evaluations` of the FMU's log.
fn work(text: &str) -> (u64, u64) {
    let numbers: Vec<u64> = text
        .split(|c: char| !c.is_ascii_digit())
        .filter(|s| !s.is_empty())
        .filter_map(|s| s.parse().ok())
        .collect();
    // The method's name holds no digits before them ("DOP853" aside).
    let at = numbers.iter().position(|&n| n != 853).unwrap();
    (numbers[at], numbers[at + 2])
}

#[test]
fn co_simulation_at_a_communication_step_of_1e_3_takes_the_steps_of_lagc_run() {
    // The FMU advances one integration across all 5000 fmi2DoStep calls:
    // the same steps and right-side evaluations as `lagc run` writing the
    // same 5001 rows from its dense output.
    let out = check("steps");
    let logged = out.lines().find(|l| l.contains(" steps (+")).unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_lagc"))
        .args([
            "run",
            "examples/paper.lag",
            "--rtol",
            "1e-10",
            "--samples",
            "5001",
        ])
        .args(["--quiet"])
        .current_dir(crate::root())
        .env("LAGC_CACHE_DIR", crate::root().join("target/lagc-cache"))
        .output()
        .unwrap();
    let run = checked(run, "lagc run");
    let stderr = String::from_utf8_lossy(&run.stderr);
    let summary = stderr.lines().find(|l| l.contains("steps: ")).unwrap();
    let summary = summary.split("steps: ").nth(1).unwrap();
    assert_eq!(work(logged), work(summary), "{logged}\n{summary}");
}

#[test]
fn the_fmi_cross_check_files_pass_fmpys_cross_check_validation() {
    // `_ref.csv`, `_ref.opt` (and `_in.csv` for a driven model) from
    // `lagc run` in the cross-check repository's layout; FMPy's
    // validate_test_fmu on each FMU folder, then its simulation as a
    // cross-check importer checked by validate_cross_check_result
    // (tests/fmu/cross_check.py).
    let dir = target().join("cross-check");
    std::fs::create_dir_all(&dir).unwrap();
    for model in [
        "examples/paper.lag",
        "examples/knife_edge_turning.lag",
        "examples/vertical_rocket.lag",
        "tests/data/driven_oscillator.lag",
    ] {
        build_fmu(Path::new(model), &dir);
    }
    let out = Command::new(python())
        .arg(crate::root().join("tests/fmu/cross_check.py"))
        .arg(env!("CARGO_BIN_EXE_lagc"))
        .arg(crate::root())
        .arg(&dir)
        .arg(dir.join("tree"))
        .env("LAGC_CACHE_DIR", crate::root().join("target/lagc-cache"))
        .output()
        .unwrap();
    let out = checked(out, "cross_check.py");
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprint!("{stdout}");
    assert_eq!(
        stdout
            .matches("validate_cross_check_result: no problems")
            .count(),
        4,
        "{stdout}"
    );
}

/// Which params an FMU lets an importer tune between steps
/// (`check::model::Param::tunable`): those used only where an input may
/// be (forces, through lets too) and in initial values; fixed where a
/// jump would be an impulse or a moved body, and the params those are
/// computed from.
#[test]
fn params_are_tunable_only_where_a_change_between_steps_is_sound() {
    let tunable = |source: &str| -> Vec<(String, bool)> {
        let model = crate::check_bytes(source.as_bytes(), "model.lag").unwrap();
        model
            .params
            .iter()
            .map(|p| (p.name.clone(), p.tunable))
            .collect()
    };
    let named = |pairs: &[(&str, bool)]| -> Vec<(String, bool)> {
        pairs.iter().map(|&(n, t)| (n.to_string(), t)).collect()
    };
    // k in the Lagrangian fixes k0 it is computed from; T is the span's
    // end; c reaches the force through c2 and a let; x0 is read once.
    let source = "param k0 = 4;\nparam k = 2 * k0;\nparam c = 0.1;\nparam c2 = c;\n\
                  param T = 5;\nparam x0 = 1;\nlet drag = c2 * x';\ncoord x;\n\
                  lagrangian = x'^2 / 2 - k / 2 * x^2;\nforce x = -drag;\n\
                  initial x = x0, x' = 0;\ntime 0 .. T;\n";
    assert_eq!(
        tunable(source),
        named(&[
            ("k0", false),
            ("k", false),
            ("c", true),
            ("c2", true),
            ("T", false),
            ("x0", true),
        ])
    );
    let example = |name: &str| {
        let path = crate::root().join(format!("examples/{name}.lag"));
        tunable(&std::fs::read_to_string(path).unwrap())
    };
    // A mass law (the paper), a holonomic constraint and the Lagrangian
    // (the pendulum), an impact's reset (the ball): fixed.
    assert!(example("paper").iter().all(|(_, t)| !t));
    assert!(example("cartesian_pendulum").iter().all(|(_, t)| !t));
    let ball = example("bouncing_ball");
    assert!(ball.contains(&("e".to_string(), false)), "{ball:?}");
    assert!(ball.contains(&("g".to_string(), false)), "{ball:?}");
    // The damping of the damped oscillator: a force only.
    let damped = example("damped_oscillator");
    assert!(damped.contains(&("c".to_string(), true)), "{damped:?}");
    assert!(damped.contains(&("m".to_string(), false)), "{damped:?}");
}
