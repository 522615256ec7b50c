//! The generated crate's fixed files — `Cargo.toml`, `Cargo.lock`, the
//! one-line `main.rs` — and the runtime crate's own sources, which lagc
//! carries (`include_str!`) so that `lagc build -o DIR` writes a crate
//! that builds on its own and `lagc run` keeps one shared copy.

/// The runtime crate's files, relative to its root.
const RUNTIME: &[(&str, &str)] = &[
    ("Cargo.toml", include_str!("../../runtime/Cargo.toml")),
    ("src/api.rs", include_str!("../../runtime/src/api.rs")),
    ("src/budget.rs", include_str!("../../runtime/src/budget.rs")),
    ("src/cli.rs", include_str!("../../runtime/src/cli.rs")),
    (
        "src/cli/args.rs",
        include_str!("../../runtime/src/cli/args.rs"),
    ),
    (
        "src/cli/bench.rs",
        include_str!("../../runtime/src/cli/bench.rs"),
    ),
    (
        "src/cli/exit.rs",
        include_str!("../../runtime/src/cli/exit.rs"),
    ),
    (
        "src/cli/run.rs",
        include_str!("../../runtime/src/cli/run.rs"),
    ),
    (
        "src/closure.rs",
        include_str!("../../runtime/src/closure.rs"),
    ),
    (
        "src/controller.rs",
        include_str!("../../runtime/src/controller.rs"),
    ),
    ("src/dense.rs", include_str!("../../runtime/src/dense.rs")),
    ("src/direct.rs", include_str!("../../runtime/src/direct.rs")),
    ("src/domain.rs", include_str!("../../runtime/src/domain.rs")),
    ("src/dop853.rs", include_str!("../../runtime/src/dop853.rs")),
    (
        "src/dop853/global_error.rs",
        include_str!("../../runtime/src/dop853/global_error.rs"),
    ),
    (
        "src/dop853/tableau.rs",
        include_str!("../../runtime/src/dop853/tableau.rs"),
    ),
    ("src/driver.rs", include_str!("../../runtime/src/driver.rs")),
    (
        "src/ensemble.rs",
        include_str!("../../runtime/src/ensemble.rs"),
    ),
    ("src/events.rs", include_str!("../../runtime/src/events.rs")),
    (
        "src/failure.rs",
        include_str!("../../runtime/src/failure.rs"),
    ),
    (
        "src/field/affine.rs",
        include_str!("../../runtime/src/field/affine.rs"),
    ),
    (
        "src/field/coefficients.rs",
        include_str!("../../runtime/src/field/coefficients.rs"),
    ),
    (
        "src/field/conditions.rs",
        include_str!("../../runtime/src/field/conditions.rs"),
    ),
    (
        "src/field/mod.rs",
        include_str!("../../runtime/src/field/mod.rs"),
    ),
    (
        "src/field/members.rs",
        include_str!("../../runtime/src/field/members.rs"),
    ),
    (
        "src/field/quasilinear.rs",
        include_str!("../../runtime/src/field/quasilinear.rs"),
    ),
    (
        "src/field/window.rs",
        include_str!("../../runtime/src/field/window.rs"),
    ),
    (
        "src/highest.rs",
        include_str!("../../runtime/src/highest.rs"),
    ),
    (
        "src/impacts.rs",
        include_str!("../../runtime/src/impacts.rs"),
    ),
    ("src/inputs.rs", include_str!("../../runtime/src/inputs.rs")),
    ("src/keep.rs", include_str!("../../runtime/src/keep.rs")),
    ("src/lib.rs", include_str!("../../runtime/src/lib.rs")),
    ("src/linalg.rs", include_str!("../../runtime/src/linalg.rs")),
    ("src/magnus.rs", include_str!("../../runtime/src/magnus.rs")),
    ("src/math.rs", include_str!("../../runtime/src/math.rs")),
    ("src/method.rs", include_str!("../../runtime/src/method.rs")),
    ("src/model.rs", include_str!("../../runtime/src/model.rs")),
    ("src/output.rs", include_str!("../../runtime/src/output.rs")),
    ("src/plot.rs", include_str!("../../runtime/src/plot.rs")),
    (
        "src/progress.rs",
        include_str!("../../runtime/src/progress.rs"),
    ),
    (
        "src/quantity.rs",
        include_str!("../../runtime/src/quantity.rs"),
    ),
    (
        "src/sensitivity.rs",
        include_str!("../../runtime/src/sensitivity.rs"),
    ),
    ("src/rodas4.rs", include_str!("../../runtime/src/rodas4.rs")),
    (
        "src/rodas4/tableau.rs",
        include_str!("../../runtime/src/rodas4/tableau.rs"),
    ),
    (
        "src/run/diagnosis.rs",
        include_str!("../../runtime/src/run/diagnosis.rs"),
    ),
    (
        "src/run/integration.rs",
        include_str!("../../runtime/src/run/integration.rs"),
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
        "src/run/regime.rs",
        include_str!("../../runtime/src/run/regime.rs"),
    ),
    (
        "src/run/solution.rs",
        include_str!("../../runtime/src/run/solution.rs"),
    ),
    (
        "src/segment.rs",
        include_str!("../../runtime/src/segment.rs"),
    ),
    ("src/solver.rs", include_str!("../../runtime/src/solver.rs")),
    (
        "src/stepper.rs",
        include_str!("../../runtime/src/stepper.rs"),
    ),
    (
        "src/summary.rs",
        include_str!("../../runtime/src/summary.rs"),
    ),
    ("src/system.rs", include_str!("../../runtime/src/system.rs")),
    ("src/table.rs", include_str!("../../runtime/src/table.rs")),
    (
        "src/tolerance.rs",
        include_str!("../../runtime/src/tolerance.rs"),
    ),
    ("src/watch.rs", include_str!("../../runtime/src/watch.rs")),
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
