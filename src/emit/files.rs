//! The generated crate's fixed files — `Cargo.toml`, `Cargo.lock`, the
//! one-line `main.rs` — and the runtime crate's own sources, which lagc
//! carries (`include_str!`) so that `lagc build -o DIR` writes a crate
//! that builds on its own and `lagc run` keeps one shared copy.

/// The runtime crate's files, relative to its root.
const RUNTIME: &[(&str, &str)] = &[
    ("Cargo.toml", include_str!("../../runtime/Cargo.toml")),
    ("src/choice.rs", include_str!("../../runtime/src/choice.rs")),
    (
        "src/closure.rs",
        include_str!("../../runtime/src/closure.rs"),
    ),
    ("src/domain.rs", include_str!("../../runtime/src/domain.rs")),
    (
        "src/ensemble.rs",
        include_str!("../../runtime/src/ensemble.rs"),
    ),
    (
        "src/failure.rs",
        include_str!("../../runtime/src/failure.rs"),
    ),
    (
        "src/highest.rs",
        include_str!("../../runtime/src/highest.rs"),
    ),
    (
        "src/highest/fixed.rs",
        include_str!("../../runtime/src/highest/fixed.rs"),
    ),
    ("src/io/api.rs", include_str!("../../runtime/src/io/api.rs")),
    ("src/io/cli.rs", include_str!("../../runtime/src/io/cli.rs")),
    (
        "src/io/cli/args.rs",
        include_str!("../../runtime/src/io/cli/args.rs"),
    ),
    (
        "src/io/cli/bench.rs",
        include_str!("../../runtime/src/io/cli/bench.rs"),
    ),
    (
        "src/io/cli/exit.rs",
        include_str!("../../runtime/src/io/cli/exit.rs"),
    ),
    (
        "src/io/cli/run.rs",
        include_str!("../../runtime/src/io/cli/run.rs"),
    ),
    (
        "src/io/driver.rs",
        include_str!("../../runtime/src/io/driver.rs"),
    ),
    ("src/io/mod.rs", include_str!("../../runtime/src/io/mod.rs")),
    (
        "src/io/output.rs",
        include_str!("../../runtime/src/io/output.rs"),
    ),
    (
        "src/io/plot.rs",
        include_str!("../../runtime/src/io/plot.rs"),
    ),
    (
        "src/io/summary.rs",
        include_str!("../../runtime/src/io/summary.rs"),
    ),
    (
        "src/io/table.rs",
        include_str!("../../runtime/src/io/table.rs"),
    ),
    ("src/lib.rs", include_str!("../../runtime/src/lib.rs")),
    ("src/lanes.rs", include_str!("../../runtime/src/lanes.rs")),
    ("src/linalg.rs", include_str!("../../runtime/src/linalg.rs")),
    ("src/math.rs", include_str!("../../runtime/src/math.rs")),
    (
        "src/method/deviation.rs",
        include_str!("../../runtime/src/method/deviation.rs"),
    ),
    (
        "src/method/deviation/member.rs",
        include_str!("../../runtime/src/method/deviation/member.rs"),
    ),
    (
        "src/method/direct.rs",
        include_str!("../../runtime/src/method/direct.rs"),
    ),
    (
        "src/method/field/affine.rs",
        include_str!("../../runtime/src/method/field/affine.rs"),
    ),
    (
        "src/method/field/coefficients.rs",
        include_str!("../../runtime/src/method/field/coefficients.rs"),
    ),
    (
        "src/method/field/conditions.rs",
        include_str!("../../runtime/src/method/field/conditions.rs"),
    ),
    (
        "src/method/field/global_error.rs",
        include_str!("../../runtime/src/method/field/global_error.rs"),
    ),
    (
        "src/method/field/middle.rs",
        include_str!("../../runtime/src/method/field/middle.rs"),
    ),
    (
        "src/method/field/mod.rs",
        include_str!("../../runtime/src/method/field/mod.rs"),
    ),
    (
        "src/method/field/quasilinear.rs",
        include_str!("../../runtime/src/method/field/quasilinear.rs"),
    ),
    (
        "src/method/field/window.rs",
        include_str!("../../runtime/src/method/field/window.rs"),
    ),
    (
        "src/method/mod.rs",
        include_str!("../../runtime/src/method/mod.rs"),
    ),
    (
        "src/method/segment.rs",
        include_str!("../../runtime/src/method/segment.rs"),
    ),
    (
        "src/method/solver.rs",
        include_str!("../../runtime/src/method/solver.rs"),
    ),
    ("src/model.rs", include_str!("../../runtime/src/model.rs")),
    (
        "src/ode/budget.rs",
        include_str!("../../runtime/src/ode/budget.rs"),
    ),
    (
        "src/ode/controller.rs",
        include_str!("../../runtime/src/ode/controller.rs"),
    ),
    (
        "src/ode/dense.rs",
        include_str!("../../runtime/src/ode/dense.rs"),
    ),
    (
        "src/ode/dop853.rs",
        include_str!("../../runtime/src/ode/dop853.rs"),
    ),
    (
        "src/ode/dop853/global_error.rs",
        include_str!("../../runtime/src/ode/dop853/global_error.rs"),
    ),
    (
        "src/ode/dop853/global_error/growth.rs",
        include_str!("../../runtime/src/ode/dop853/global_error/growth.rs"),
    ),
    (
        "src/ode/dop853/inside.rs",
        include_str!("../../runtime/src/ode/dop853/inside.rs"),
    ),
    (
        "src/ode/dop853/tableau.rs",
        include_str!("../../runtime/src/ode/dop853/tableau.rs"),
    ),
    (
        "src/ode/magnus.rs",
        include_str!("../../runtime/src/ode/magnus.rs"),
    ),
    (
        "src/ode/mod.rs",
        include_str!("../../runtime/src/ode/mod.rs"),
    ),
    (
        "src/ode/rodas4.rs",
        include_str!("../../runtime/src/ode/rodas4.rs"),
    ),
    (
        "src/ode/rodas4/tableau.rs",
        include_str!("../../runtime/src/ode/rodas4/tableau.rs"),
    ),
    (
        "src/ode/stepper.rs",
        include_str!("../../runtime/src/ode/stepper.rs"),
    ),
    (
        "src/ode/system.rs",
        include_str!("../../runtime/src/ode/system.rs"),
    ),
    (
        "src/ode/tolerance.rs",
        include_str!("../../runtime/src/ode/tolerance.rs"),
    ),
    (
        "src/quantity.rs",
        include_str!("../../runtime/src/quantity.rs"),
    ),
    (
        "src/run/diagnosis.rs",
        include_str!("../../runtime/src/run/diagnosis.rs"),
    ),
    (
        "src/run/events.rs",
        include_str!("../../runtime/src/run/events.rs"),
    ),
    (
        "src/run/impacts.rs",
        include_str!("../../runtime/src/run/impacts.rs"),
    ),
    (
        "src/run/inputs.rs",
        include_str!("../../runtime/src/run/inputs.rs"),
    ),
    (
        "src/run/integration.rs",
        include_str!("../../runtime/src/run/integration.rs"),
    ),
    (
        "src/run/keep.rs",
        include_str!("../../runtime/src/run/keep.rs"),
    ),
    (
        "src/run/keep/one.rs",
        include_str!("../../runtime/src/run/keep/one.rs"),
    ),
    (
        "src/run/keep/partition.rs",
        include_str!("../../runtime/src/run/keep/partition.rs"),
    ),
    (
        "src/run/mod.rs",
        include_str!("../../runtime/src/run/mod.rs"),
    ),
    (
        "src/run/options.rs",
        include_str!("../../runtime/src/run/options.rs"),
    ),
    (
        "src/run/progress.rs",
        include_str!("../../runtime/src/run/progress.rs"),
    ),
    (
        "src/run/regime.rs",
        include_str!("../../runtime/src/run/regime.rs"),
    ),
    (
        "src/run/saltation.rs",
        include_str!("../../runtime/src/run/saltation.rs"),
    ),
    (
        "src/run/sensitivity.rs",
        include_str!("../../runtime/src/run/sensitivity.rs"),
    ),
    (
        "src/run/solution.rs",
        include_str!("../../runtime/src/run/solution.rs"),
    ),
    (
        "src/run/start.rs",
        include_str!("../../runtime/src/run/start.rs"),
    ),
    (
        "src/run/watch.rs",
        include_str!("../../runtime/src/run/watch.rs"),
    ),
];

/// The runtime crate's sources `(path relative to its root, contents)`; a
/// test checks that they are every file of `runtime/src/`.
pub fn runtime_files() -> impl Iterator<Item = (&'static str, &'static str)> {
    RUNTIME.iter().copied()
}

/// FNV-1a of `bytes`: the cache's keys (stable across builds and
/// platforms, unlike `std`'s hasher).
pub fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(0xcbf2_9ce4_8422_2325, |hash, b| {
        (hash ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// A hash of the runtime's sources (FNV-1a): a cache keeps one built copy
/// per version of the runtime.
pub fn runtime_version() -> String {
    let bytes = RUNTIME
        .iter()
        .flat_map(|(path, text)| path.bytes().chain(text.bytes()));
    format!("{:016x}", fnv1a(bytes))
}

/// `lag-<stem>`: the package for a model named `model_name`, safe from any
/// file stem (lower-case ASCII letters, digits and `-`; never empty, never
/// starting with a digit).
pub fn package_name(model_name: &str) -> String {
    let mut stem = String::new();
    for c in model_name.chars() {
        let c = if c.is_ascii_alphanumeric() {
            c.to_ascii_lowercase()
        } else {
            '-'
        };
        if !(c == '-' && (stem.is_empty() || stem.ends_with('-'))) {
            stem.push(c);
        }
    }
    let stem = stem.trim_end_matches('-');
    let stem: String = stem.chars().take(60).collect();
    if stem.is_empty() {
        "lag-model".to_string()
    } else {
        format!("lag-{stem}")
    }
}

/// The library's name: the package's with `_`.
pub fn library_name(package: &str) -> String {
    package.replace('-', "_")
}

pub fn cargo_toml(package: &str, runtime_path: &str) -> String {
    let library = library_name(package);
    let runtime_path = toml_escape(runtime_path);
    format!(
        "# Generated by lagc. Do not edit: regenerate with `lagc build`.\n\
         [package]\n\
         name = \"{package}\"\n\
         version = \"0.1.0\"\n\
         edition = \"2021\"\n\
         publish = false\n\
         \n\
         [lib]\n\
         name = \"{library}\"\n\
         path = \"src/lib.rs\"\n\
         \n\
         [[bin]]\n\
         name = \"{package}\"\n\
         path = \"src/main.rs\"\n\
         \n\
         [dependencies]\n\
         lagc-runtime = {{ path = \"{runtime_path}\" }}\n\
         \n\
         # A crate of its own: never part of an enclosing workspace.\n\
         [workspace]\n"
    )
}

/// `Cargo.toml` of a model built as a shared library for another host (a
/// Python module, an FMU): the library `library`, the runtime and the
/// host's glue crate as path dependencies `(crate, path)`; `command` is the
/// `lagc build` flag that regenerates it.
pub fn cdylib_cargo_toml(
    command: &str,
    package: &str,
    library: &str,
    dependencies: &[(&str, &str)],
) -> String {
    let dependencies: String = dependencies
        .iter()
        .map(|(name, path)| format!("{name} = {{ path = \"{}\" }}\n", toml_escape(path)))
        .collect();
    format!(
        "# Generated by lagc. Do not edit: regenerate with `lagc build {command}`.\n\
         [package]\n\
         name = \"{package}\"\n\
         version = \"0.1.0\"\n\
         edition = \"2021\"\n\
         publish = false\n\
         \n\
         [lib]\n\
         name = \"{library}\"\n\
         path = \"src/lib.rs\"\n\
         crate-type = [\"cdylib\"]\n\
         \n\
         [dependencies]\n\
         {dependencies}\
         \n\
         # A crate of its own: never part of an enclosing workspace.\n\
         [workspace]\n"
    )
}

/// A path or name as the text of a TOML basic string.
pub fn toml_escape(text: &str) -> String {
    text.replace('\\', "\\\\").replace('"', "\\\"")
}

/// The lock file: the runtime has no dependencies, so this is all of it,
/// and the crate builds with `--offline` from the start.
pub fn cargo_lock(package: &str) -> String {
    format!(
        "# This file is automatically @generated by Cargo.\n\
         # It is not intended for manual editing.\n\
         version = 4\n\
         \n\
         [[package]]\n\
         name = \"{package}\"\n\
         version = \"0.1.0\"\n\
         dependencies = [\n \"lagc-runtime\",\n]\n\
         \n\
         [[package]]\n\
         name = \"lagc-runtime\"\n\
         version = \"0.1.0\"\n"
    )
}

pub fn main_rs(package: &str) -> String {
    let library = library_name(package);
    format!(
        "//! Generated by lagc: the model's command line is the runtime's.\n\n\
         fn main() -> std::process::ExitCode {{\n    \
         lagc_runtime::cli::main::<{library}::Model>()\n}}\n"
    )
}
