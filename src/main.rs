//! The `lagc` command line: the only place that does IO.
//!
//! Exit status (SPEC §3): 0 success, 1 the model has errors, 2 bad usage —
//! including a FILE that cannot be read, since that is a wrong argument
//! rather than a wrong model.

mod cli;

use clap::{Args, Parser, Subcommand};
use lagc::diagnostic::{render, Diagnostic};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// lagc compiles a `.lag` model of a mechanical system with variable mass
/// and non-holonomic constraints into the generalized Lagrange equations of
/// the second kind, and integrates them with the field method.
#[derive(Debug, Parser)]
#[command(name = "lagc", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Check a model and report every problem; prints nothing else.
    ///
    /// Runs the front end and the derivation, so that mistakes only the
    /// symbolic stage can see (an initial value that violates a constraint,
    /// an identically singular mass matrix) are reported too.
    ///
    /// Exit status: 0 when the model is clean, 1 when it has errors, 2 when
    /// FILE cannot be read.
    Check(CheckArgs),
    /// Derive equations (4) and the reduced first-order system (7).
    ///
    /// Prints the equations, the reduced system, the state and its initial
    /// values, and the result of the cross-check of (4) against the
    /// multiplier route. Exit status: 0 on success, 1 when the model has
    /// errors, 2 when FILE cannot be read.
    Derive(DeriveArgs),
    /// Write the generated crate that integrates the model.
    ///
    /// The crate builds with `cargo build --release` alone and holds only
    /// what this system needs. Exit status: 0 on success, 1 when the model
    /// has errors, 2 when FILE cannot be read or DIR cannot be written.
    Build(BuildArgs),
    /// Build the generated crate (cached) and run it.
    ///
    /// The crate is kept under `$LAGC_CACHE_DIR` (or `$XDG_CACHE_HOME/lagc`,
    /// or `~/.cache/lagc`), one directory per model and one shared cargo
    /// target directory, so an unchanged model is not rebuilt. The
    /// trajectory goes to stdout as CSV (`t,q1,…,q1',…`), cargo's progress
    /// and the run summary to stderr. Exit status: that of the model's
    /// binary (3 on a numerical failure), or 1/2 as for `build`.
    Run(RunArgs),
    /// The build cache: list its models, or clean it.
    ///
    /// `lagc run` keeps each model's crate and binary in the cache and
    /// removes the least recently run ones when the cache outgrows
    /// `$LAGC_CACHE_MAX_BYTES` (default 4 GB).
    Cache(CacheArgs),
    /// Error against run time: every method at a ladder of tolerances.
    ///
    /// Builds the model's crate (cached, as `run`) and runs it for the
    /// field method, direct DOP853 and direct RODAS4 at each tolerance
    /// (rtol 1e-3 … 1e-12 by default, atol = rtol·1e-2); the time of a run
    /// is the smallest of --runs solves after a warm-up, measured inside
    /// the binary. The error is the largest over the samples against the
    /// model's `exact` lines, or, without them, against a run at rtol 1e-13
    /// by another method (direct DOP853; for direct DOP853 the field).
    /// Prints a table on stdout and writes a work-precision plot (SVG) and
    /// the data (CSV) into DIR. Runs that fail appear in the table as
    /// failed. Exit status: 0 on success, 1 when the model has errors or
    /// its crate does not build, 2 on bad usage.
    Report(ReportArgs),
}

/// Negative numbers are values, not flags: `--tolerances -1` gets lagc's
/// own message about tolerances rather than clap's "unexpected argument".
#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
struct ReportArgs {
    /// The `.lag` model.
    file: PathBuf,
    /// Where to write `<model>.work-precision.svg` and `.csv`.
    #[arg(long, value_name = "DIR", default_value = ".")]
    out: PathBuf,
    /// Timed solves per measurement (after one warm-up); the time is their
    /// minimum.
    #[arg(long, value_name = "N", default_value_t = 5)]
    runs: usize,
    /// Comma-separated relative tolerances (default 1e-3,1e-4,…,1e-12).
    #[arg(long, value_name = "LIST", allow_hyphen_values = true)]
    tolerances: Option<String>,
    /// Number of evenly spaced sample times; the error is the largest
    /// over them. Samples never change the steps (every method has
    /// dense output); more samples cost output time and look closer
    /// between the steps.
    #[arg(long, value_name = "N", default_value_t = 11)]
    samples: usize,
    /// Override a param: `--param NAME=VALUE` (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    params: Vec<String>,
}

#[derive(Debug, Args)]
struct BuildArgs {
    /// The `.lag` model.
    file: PathBuf,
    /// The directory to write the crate into (created when missing). It
    /// must be empty or hold an earlier `lagc build`'s output.
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    output: PathBuf,
    /// Write into DIR even when it holds files lagc did not write.
    #[arg(long)]
    force: bool,
    /// Where to write the runtime library the crate depends on (default:
    /// DIR/lagc-runtime). Give several models' crates one runtime to use
    /// them together in one program.
    #[arg(long, value_name = "RUNTIME_DIR")]
    runtime: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(disable_help_flag = true)]
struct RunArgs {
    /// The `.lag` model.
    file: PathBuf,
    /// The run's options, passed to the model's binary as they are
    /// (`lagc run FILE --help` lists them): `--method field|direct`,
    /// `--integrator auto|explicit|stiff|magnus`, `--param NAME=VALUE`,
    /// `--init NAME=VALUE`, `--rtol R`, `--atol A`, `--samples N`,
    /// `--times T1,T2,…`, `--estimate-error`, `--plot FILE.svg [--phase X,Y]`,
    /// `--ensemble K`, `--repeat N`, `--quiet`, `--summary text|json`, …
    #[arg(
        trailing_var_arg = true,
        allow_hyphen_values = true,
        value_name = "OPTIONS"
    )]
    args: Vec<String>,
}

#[derive(Debug, Args)]
struct CacheArgs {
    #[command(subcommand)]
    action: CacheAction,
}

#[derive(Debug, Subcommand)]
enum CacheAction {
    /// Every cached model: its file, size and when it last ran, least
    /// recently run first.
    List,
    /// Remove every cached model, binary and runtime (the next `lagc run`
    /// of a model rebuilds it).
    Clean,
}

#[derive(Debug, Args)]
struct DeriveArgs {
    /// The `.lag` model.
    file: PathBuf,
    /// The output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Format {
    /// Plain text.
    Text,
    /// A LaTeX `align*` block.
    Latex,
}

#[derive(Debug, Args)]
struct CheckArgs {
    /// The `.lag` model to check.
    file: PathBuf,
}

const EXIT_MODEL_ERRORS: u8 = 1;
const EXIT_USAGE: u8 = 2;

fn main() -> ExitCode {
    // clap exits with status 2 on a usage error, 0 for --help/--version.
    let cli = Cli::parse();
    match cli.command {
        Command::Check(args) => check(&args),
        Command::Derive(args) => derive(&args),
        Command::Build(args) => build(&args),
        Command::Run(args) => run(&args),
        Command::Cache(args) => cache(&args),
        Command::Report(args) => report(&args),
    }
}

/// Reads `file`, runs `stage` on its text (on the big stack, invalid UTF-8
/// a diagnostic) and renders what it reports on stderr: on success its
/// notes, after which `then` runs (still on the big stack); on failure the
/// diagnostics and a count. `Err` holds the exit status of a failure.
fn compile<T, R: Send>(
    file: &Path,
    stage: impl FnOnce(&str) -> Result<(T, Vec<Diagnostic>), Vec<Diagnostic>> + Send,
    then: impl FnOnce(T) -> R + Send,
) -> Result<R, ExitCode> {
    let file_name = file.display().to_string();
    let bytes = match cli::read_model_file(file) {
        Ok(bytes) => bytes,
        Err(message) => {
            eprintln!("error: cannot read `{file_name}`: {message}");
            return Err(ExitCode::from(EXIT_USAGE));
        }
    };
    let color = std::io::stderr().is_terminal();
    lagc::on_big_stack(|| {
        let (source, result) = lagc::decode_then(&bytes, stage);
        let warnings = lagc::literal_warnings(&source);
        match result {
            Ok((value, notes)) => {
                eprint!("{}", render(&warnings, &file_name, &source, color));
                eprint!("{}", render(&notes, &file_name, &source, color));
                Ok(then(value))
            }
            Err(mut diagnostics) => {
                diagnostics.extend(warnings);
                lagc::diagnostic::sort(&mut diagnostics);
                eprint!("{}", render(&diagnostics, &file_name, &source, color));
                let errors = diagnostics.iter().filter(|d| d.is_error()).count();
                eprintln!("error: `{file_name}` has {}", count(errors, "error"));
                Err(ExitCode::from(EXIT_MODEL_ERRORS))
            }
        }
    })
}

/// `Ok` or `Err`, both an exit status.
fn status(result: Result<ExitCode, ExitCode>) -> ExitCode {
    result.unwrap_or_else(|status| status)
}

fn check(args: &CheckArgs) -> ExitCode {
    let file_name = args.file.display().to_string();
    let stage = |source: &str| lagc::check_and_derive(source).map(|(model, _)| (model, Vec::new()));
    status(compile(&args.file, stage, |model| {
        let constraints = match model.constraint_order {
            Some(k) => format!(
                "{} of order {k}",
                count(model.constraints.len(), "constraint")
            ),
            None => "no constraints".to_string(),
        };
        let coords = count(model.coords.len(), "coordinate");
        eprintln!("{file_name}: ok ({coords}, {constraints})");
        ExitCode::SUCCESS
    }))
}

fn derive(args: &DeriveArgs) -> ExitCode {
    // The same derivation, cross-check included, as every other path: a
    // model whose equations (4) fail it is a model with errors (E0033).
    let stage = |source: &str| {
        let model = lagc::frontend(source)?;
        lagc::mechanics::derive_checked(&model).map(|checked| (checked, Vec::new()))
    };
    status(compile(&args.file, stage, |(derivation, check)| {
        match args.format {
            Format::Text => {
                print!("{}", derivation.text());
                let reduced = derivation.reduced.clone();
                let mut arena = derivation.arena.clone();
                let field = lagc::field::field_system(&mut arena, &reduced);
                print!("{}", field.text(&arena, &reduced.state));
            }
            Format::Latex => {
                let reduced = derivation.reduced.clone();
                let mut arena = derivation.arena.clone();
                let field = lagc::field::field_system(&mut arena, &reduced);
                print!(
                    "\\begin{{align*}}\n{}{}\\end{{align*}}\n",
                    derivation.latex_lines(),
                    field.latex_lines(&arena, &reduced.state)
                );
            }
        }
        eprintln!(
            "cross-check of (4) against the multiplier route: passed at {} points",
            check.points
        );
        ExitCode::SUCCESS
    }))
}

/// "1 constraint", "2 constraints".
fn count(n: usize, noun: &str) -> String {
    let plural = if n == 1 { "" } else { "s" };
    format!("{n} {noun}{plural}")
}

/// Reads, checks and generates the crate of `file`, printing diagnostics
/// and notes; `Err(status)` when that fails.
fn generate(
    file: &Path,
    runtime_path: &str,
    package_key: Option<String>,
) -> Result<lagc::emit::GeneratedCrate, ExitCode> {
    let model_name = file
        .file_stem()
        .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned());
    let stage = |source: &str| {
        let model = lagc::frontend(source)?;
        let options = lagc::emit::EmitOptions {
            model_name: model_name.clone(),
            source_hash: cli::source_hash(source),
            runtime_path: runtime_path.to_string(),
            package_key: package_key.clone(),
        };
        lagc::pipeline::generate_crate(&model, &options)
    };
    compile(file, stage, |generated| generated)
}

fn build(args: &BuildArgs) -> ExitCode {
    let runtime_dir = args
        .runtime
        .clone()
        .unwrap_or_else(|| args.output.join(cli::RUNTIME_IN_CRATE));
    // The crate's path to the runtime, relative where both can be placed.
    let runtime_path = match &args.runtime {
        None => cli::RUNTIME_IN_CRATE.to_string(),
        Some(dir) => {
            // The runtime's sources are written over whatever is there: a
            // folder lagc did not write (the runtime's own source tree, a
            // project) must not lose its files to them.
            if !args.force && !cli::may_write_into(dir) {
                eprintln!(
                    "error: `{}` is not empty and was not written by `lagc build`: refusing \
                     to write the runtime over it\n  = help: give --runtime an empty or new \
                     directory, or one an earlier `lagc build --runtime` wrote, or pass --force",
                    dir.display()
                );
                return ExitCode::from(EXIT_USAGE);
            }
            let made =
                std::fs::create_dir_all(dir).and_then(|()| std::fs::create_dir_all(&args.output));
            if let Err(error) = made {
                eprintln!("error: cannot create `{}`: {error}", dir.display());
                return ExitCode::from(EXIT_USAGE);
            }
            cli::relative_path(&args.output, dir)
        }
    };
    let generated = match generate(&args.file, &runtime_path, None) {
        Ok(generated) => generated,
        Err(status) => return status,
    };
    if !args.force && !cli::may_write_into(&args.output) {
        eprintln!(
            "error: `{}` is not empty and was not written by `lagc build`: refusing to \
             overwrite it\n  = help: choose an empty or new directory, or pass --force",
            args.output.display()
        );
        return ExitCode::from(EXIT_USAGE);
    }
    let marker = "written by `lagc build`; a later `lagc build` may overwrite this directory\n";
    let written = cli::write_crate(&generated, &args.output)
        .and_then(|()| cli::write_runtime(&runtime_dir))
        .and_then(|()| std::fs::write(args.output.join(cli::MARKER), marker))
        .and_then(|()| std::fs::write(runtime_dir.join(cli::MARKER), marker));
    match written {
        Ok(()) => {
            eprintln!(
                "wrote crate `{}` to {}",
                generated.package,
                args.output.display()
            );
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!(
                "error: cannot write to `{}`: {error}",
                args.output.display()
            );
            ExitCode::from(EXIT_USAGE)
        }
    }
}

fn run(args: &RunArgs) -> ExitCode {
    let generated = match generate(
        &args.file,
        &cli::runtime_path_from_cache(),
        Some(cli::path_key(&args.file)),
    ) {
        Ok(generated) => generated,
        Err(status) => return status,
    };
    // The model's binary parses its options; the same parser checks them
    // here first, so that bad usage is reported before anything is built.
    // They are passed on as they came.
    let params: Vec<&str> = generated.params.iter().map(String::as_str).collect();
    let state: Vec<&str> = generated.state.iter().map(String::as_str).collect();
    let parsed = lagc_runtime::cli::parse(&args.args, &params, &state, &[]);
    match parsed {
        Err(message) => {
            eprintln!("error: {message}\n\n{}", lagc_runtime::cli::USAGE);
            return ExitCode::from(EXIT_USAGE);
        }
        Ok(lagc_runtime::cli::Command::Help) => {
            println!("{}", lagc_runtime::cli::USAGE);
            return ExitCode::SUCCESS;
        }
        Ok(_) => {}
    }
    let binary = match build_cached(&generated, &args.file) {
        Ok(binary) => binary,
        Err(status) => return status,
    };
    match cli::run_binary(&binary, &args.args) {
        Ok(status) => match status.code() {
            Some(code) => ExitCode::from(u8::try_from(code).unwrap_or(1)),
            None => ExitCode::FAILURE,
        },
        Err(error) => {
            eprintln!("error: cannot run `{}`: {error}", binary.display());
            ExitCode::FAILURE
        }
    }
}

/// Writes the crate into the cache and builds it there; the binary's path.
fn build_cached(
    generated: &lagc::emit::GeneratedCrate,
    model_file: &Path,
) -> Result<PathBuf, ExitCode> {
    let Some(cache) = cli::cache_dir() else {
        eprintln!("error: no cache directory: set LAGC_CACHE_DIR (or XDG_CACHE_HOME or HOME)");
        return Err(ExitCode::from(EXIT_USAGE));
    };
    let crate_dir = cache.join("crates").join(&generated.package);
    let target_dir = cache.join("target");
    // Other lagc processes may run this model, or others, right now: the
    // runtime is written under its lock, and this crate is written, built
    // and checked under its own (held until this function returns).
    let runtime = cli::runtime_dir_name();
    let waiting = |what: String| {
        move || eprintln!("note: waiting for another lagc process that is building {what}")
    };
    let written =
        cli::cache::lock(&cache, &runtime, waiting("the runtime".to_string())).and_then(|_lock| {
            cli::cache::remove_temporaries(&cache.join(&runtime));
            cli::write_runtime(&cache.join(&runtime))
        });
    let locked = written.and_then(|()| {
        cli::cache::lock(
            &cache,
            &generated.package,
            waiting(format!("`{}`", generated.package)),
        )
    });
    let _lock = match locked {
        Ok(lock) => lock,
        Err(error) => {
            eprintln!("error: cannot write to `{}`: {error}", cache.display());
            return Err(ExitCode::from(EXIT_USAGE));
        }
    };
    cli::cache::remove_temporaries(&crate_dir);
    let source = model_file
        .canonicalize()
        .unwrap_or_else(|_| model_file.to_path_buf());
    let written = cli::write_crate(generated, &crate_dir)
        .and_then(|()| {
            cli::cache::write_if_changed(
                &crate_dir.join(cli::cache::SOURCE),
                source.display().to_string().as_bytes(),
            )
        })
        .and_then(|_| std::fs::write(crate_dir.join(cli::cache::LAST_RUN), ""));
    if let Err(error) = written {
        eprintln!("error: cannot write to `{}`: {error}", crate_dir.display());
        return Err(ExitCode::from(EXIT_USAGE));
    }
    match cli::cargo_build(&crate_dir, &target_dir) {
        Ok(build) if build.status.success() => {}
        Ok(build) => {
            // Not the model's fault (exit 1 says that): the machine's.
            eprintln!(
                "error: the generated crate could not be built ({}): {}",
                build.status,
                cli::cargo::explain(&build.tail, &cache)
            );
            return Err(ExitCode::from(EXIT_USAGE));
        }
        Err(error) => {
            eprintln!(
                "error: cannot run cargo ({error}); lagc needs Rust's cargo on the PATH (or in $CARGO)"
            );
            return Err(ExitCode::from(EXIT_USAGE));
        }
    }
    let binary = target_dir.join("release").join(format!(
        "{}{}",
        generated.package,
        std::env::consts::EXE_SUFFIX
    ));
    // The binary must be this model's: a binary copied in, damaged, or
    // left by another build is removed and built again (cargo rebuilds a
    // missing output), and refused if it still does not answer.
    for attempt in 0..2 {
        if cli::binary_hash(&binary).as_deref() == Some(generated.source_hash.as_str()) {
            let removed = cli::cache::evict(
                &cache,
                cache_bound(),
                &cli::runtime_dir_name(),
                &generated.package,
            );
            if !removed.is_empty() {
                eprintln!(
                    "note: the cache outgrew its bound; removed the {} least recently run model(s)",
                    removed.len()
                );
            }
            return Ok(binary);
        }
        if attempt == 0 {
            eprintln!(
                "note: `{}` is not this model's binary (damaged or replaced); rebuilding it",
                binary.display()
            );
            // The uplifted binary may share its inode with cargo's own
            // copy; a fresh source time makes cargo rebuild both.
            let _ = std::fs::remove_file(&binary);
            cli::touch(&crate_dir.join("src/main.rs"));
            match cli::cargo_build(&crate_dir, &target_dir) {
                Ok(build) if build.status.success() => {}
                _ => break,
            }
        }
    }
    eprintln!(
        "error: `{}` does not belong to this model even after a rebuild; remove the cache \
         directory `{}` and run again",
        binary.display(),
        cache.display()
    );
    Err(ExitCode::FAILURE)
}

fn report(args: &ReportArgs) -> ExitCode {
    let tolerances = match &args.tolerances {
        None => lagc::report::default_tolerances(),
        Some(text) => match lagc::report::parse_tolerances(text) {
            Ok(tolerances) => tolerances,
            Err(message) => {
                eprintln!("error: `--tolerances`: {message}");
                return ExitCode::from(EXIT_USAGE);
            }
        },
    };
    if args.runs == 0 {
        eprintln!("error: `--runs` must be at least 1");
        return ExitCode::from(EXIT_USAGE);
    }
    let generated = match generate(
        &args.file,
        &cli::runtime_path_from_cache(),
        Some(cli::path_key(&args.file)),
    ) {
        Ok(generated) => generated,
        Err(status) => return status,
    };
    let binary = match build_cached(&generated, &args.file) {
        Ok(binary) => binary,
        Err(status) => return status,
    };
    let mut common_args = Vec::new();
    for param in &args.params {
        common_args.extend(["--param".to_string(), param.clone()]);
    }
    common_args.extend(["--samples".to_string(), args.samples.to_string()]);
    let model = args
        .file
        .file_name()
        .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned());
    let plan = cli::report::Plan {
        binary: &binary,
        model: model.clone(),
        tolerances,
        runs: args.runs,
        common_args,
    };
    let measured = match cli::report::measure(&plan, std::io::stderr().is_terminal()) {
        Ok(measured) => measured,
        Err(message) => {
            eprintln!("error: {message}");
            return ExitCode::from(EXIT_USAGE);
        }
    };
    let svg = match lagc::report::work_precision_svg(&measured) {
        Ok(svg) => svg,
        Err(message) => {
            eprintln!("error: cannot draw the plot: {message}");
            return ExitCode::FAILURE;
        }
    };
    let stem = args
        .file
        .file_stem()
        .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned());
    let svg_path = args.out.join(format!("{stem}.work-precision.svg"));
    let csv_path = args.out.join(format!("{stem}.work-precision.csv"));
    let written = std::fs::create_dir_all(&args.out)
        .and_then(|()| std::fs::write(&svg_path, svg))
        .and_then(|()| std::fs::write(&csv_path, lagc::report::data_csv(&measured)));
    if let Err(error) = written {
        eprintln!("error: cannot write to `{}`: {error}", args.out.display());
        return ExitCode::from(EXIT_USAGE);
    }
    print!("{}", lagc::report::table(&measured));
    println!("work-precision plot: {}", svg_path.display());
    println!("data: {}", csv_path.display());
    ExitCode::SUCCESS
}

/// The cache's size bound: `$LAGC_CACHE_MAX_BYTES`, or the default.
fn cache_bound() -> u64 {
    std::env::var("LAGC_CACHE_MAX_BYTES")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(cli::cache::DEFAULT_MAX_BYTES)
}

fn cache(args: &CacheArgs) -> ExitCode {
    let Some(cache) = cli::cache_dir() else {
        eprintln!("error: no cache directory: set LAGC_CACHE_DIR (or XDG_CACHE_HOME or HOME)");
        return ExitCode::from(EXIT_USAGE);
    };
    match args.action {
        CacheAction::List => {
            let entries = cli::cache::entries(&cache);
            println!("cache: {}", cache.display());
            for e in entries.iter().rev() {
                println!(
                    "  {:<40} {:>9}  {:<14} {}",
                    e.package,
                    cli::cache::human(e.bytes),
                    cli::cache::age(e.last_run),
                    e.source.as_deref().unwrap_or("(model file not recorded)")
                );
            }
            println!(
                "{} model(s); {} in all (bound {})",
                entries.len(),
                cli::cache::human(cli::cache::size(&cache)),
                cli::cache::human(cache_bound())
            );
            ExitCode::SUCCESS
        }
        CacheAction::Clean => {
            let bytes = cli::cache::size(&cache);
            match std::fs::remove_dir_all(&cache) {
                Ok(()) => {
                    eprintln!("removed {} ({})", cache.display(), cli::cache::human(bytes));
                    ExitCode::SUCCESS
                }
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                    eprintln!("the cache {} is empty", cache.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: cannot remove `{}`: {e}", cache.display());
                    ExitCode::from(EXIT_USAGE)
                }
            }
        }
    }
}
