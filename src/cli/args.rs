//! The command line's arguments (clap): one struct per subcommand.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

/// lagc compiles a `.lag` model of a mechanical system with variable mass
/// and non-holonomic constraints into the generalized Lagrange equations of
/// the second kind, and integrates them with the field method.
#[derive(Debug, Parser)]
#[command(name = "lagc", version, about, long_about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
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
    /// Linearize the reduced system (7) at a state: A = ∂f/∂x, ∂f/∂p, the
    /// eigenvalues, the residual f.
    ///
    /// A is the exact symbolic Jacobian of the reduced system evaluated at
    /// the point (never differenced). Its state is the one the generated
    /// crate integrates, without two kinds of components: those the
    /// constraints fix (the dependent velocities: functions of the rest,
    /// eliminated, so that a perturbation moves them along the
    /// constraints) and the ignorable coordinates (positions no remaining
    /// right side contains, such as a rolling disk's heading: left out, so
    /// that a steady motion linearizes to a constant A and residual 0).
    /// Components --at does not give take the model's initial values.
    /// ∂f/∂p is the total derivative (the params declared after one
    /// recomputed from it, as --param does). An implicit constraint with
    /// several candidates: the reduced system whose free state holds every
    /// component --at gives. The dependent positions of holonomic
    /// constraints are eliminated too (put on the constraints by Newton
    /// from the values given). Each eigenvalue is shown with its frequency |Im λ|, natural
    /// frequency |λ| and damping ratio −Re λ/|λ|; the residual says
    /// whether the point is an equilibrium (or a steady motion). Exit
    /// status: 0 on success, 1 when the model has errors, 2 on bad usage
    /// (an unknown name, a malformed value), 3 where A is not defined (a
    /// division by zero, a function outside its domain, a singular mass
    /// matrix).
    Linearize(LinearizeArgs),
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct LinearizeArgs {
    /// The `.lag` model.
    pub file: PathBuf,
    /// The state: `--at "th=0.1,th'=0,psi'=-4"` (repeatable); components
    /// not given take the model's initial values, and those the
    /// constraints fix are computed from the rest (a value given for one
    /// must agree with them).
    #[arg(long, value_name = "NAME=VALUE,…", allow_hyphen_values = true)]
    pub at: Vec<String>,
    /// Override params: `--param g=9.81,l=2` (repeatable); the params
    /// declared after one are recomputed from it.
    #[arg(
        long = "param",
        value_name = "NAME=VALUE,…",
        allow_hyphen_values = true
    )]
    pub params: Vec<String>,
    /// The inputs' values at the point: `--input F=0.5` (repeatable; default:
    /// each input's default). Inputs are held there (their rates zero), and
    /// ∂f/∂u is printed beside ∂f/∂p.
    #[arg(
        long = "input",
        value_name = "NAME=VALUE,…",
        allow_hyphen_values = true
    )]
    pub inputs: Vec<String>,
    /// The time, for rheonomic models (default: the start of the model's span).
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub t: Option<String>,
    /// The output format (json: `{"state", "ignorable", "A", "eigenvalues",
    /// "residual", …}` on one line).
    #[arg(long, value_enum, default_value_t = LinearizeFormat::Text)]
    pub format: LinearizeFormat,
    /// A as expressions (printed as `lagc derive` prints): the values given
    /// with --at, --param and --t substituted, every other param and state
    /// component a symbol. An implicit system's highest rows as the parts
    /// of G_z ∂z/∂x = −G_x.
    #[arg(long)]
    pub symbolic: bool,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum LinearizeFormat {
    /// Plain text.
    Text,
    /// One JSON object.
    Json,
    /// A LaTeX `align*` block.
    Latex,
}

/// Negative numbers are values, not flags: `--tolerances -1` gets lagc's
/// own message about tolerances rather than clap's "unexpected argument".
#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct ReportArgs {
    /// The `.lag` model.
    pub file: PathBuf,
    /// Where to write `<model>.work-precision.svg` and `.csv`.
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub out: PathBuf,
    /// Timed solves per measurement (after one warm-up); the time is their
    /// minimum.
    #[arg(long, value_name = "N", default_value_t = 5)]
    pub runs: usize,
    /// Comma-separated relative tolerances (default 1e-3,1e-4,…,1e-12).
    #[arg(long, value_name = "LIST", allow_hyphen_values = true)]
    pub tolerances: Option<String>,
    /// Number of evenly spaced sample times; the error is the largest
    /// over them. Samples never change the steps (every method has
    /// dense output); more samples cost output time and look closer
    /// between the steps.
    #[arg(long, value_name = "N", default_value_t = 11)]
    pub samples: usize,
    /// Override a param: `--param NAME=VALUE` (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
    /// Time the methods without their global-error estimates (each run's
    /// `--no-global-error`): the integrators' own cost, as compiled peers
    /// that estimate nothing measure theirs.
    #[arg(long)]
    pub no_global_error: bool,
}

#[derive(Debug, Args)]
pub struct BuildArgs {
    /// The `.lag` model.
    pub file: PathBuf,
    /// The directory to write the crate into (created when missing). It
    /// must be empty or hold an earlier `lagc build`'s output.
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub output: PathBuf,
    /// Write into DIR even when it holds files lagc did not write.
    #[arg(long)]
    pub force: bool,
    /// Where to write the runtime library the crate depends on (default:
    /// DIR/lagc-runtime). Give several models' crates one runtime to use
    /// them together in one program.
    #[arg(long, value_name = "RUNTIME_DIR")]
    pub runtime: Option<PathBuf>,
    /// Build an FMI 2.0 co-simulation FMU for Linux x86-64 instead: `-o`
    /// names the `.fmu` file (the model's own integrators run inside
    /// fmi2DoStep; cargo builds it in the cache).
    #[arg(long, conflicts_with_all = ["runtime", "python"])]
    pub fmu: bool,
    /// Write a Python project instead: `pip install DIR` builds (with
    /// maturin) and installs the module named after FILE (`paper.lag` →
    /// `import paper`). It needs Rust and pip; pyo3 and numpy come from
    /// crates.io.
    #[arg(long)]
    pub python: bool,
    /// With --python: where to write the `lagc-python` library the project
    /// depends on (default: DIR/lagc-python). Several models' projects may
    /// share one, with one --runtime, and one CARGO_TARGET_DIR.
    #[arg(long, value_name = "PYTHON_LIB_DIR", requires = "python")]
    pub python_lib: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(disable_help_flag = true)]
pub struct RunArgs {
    /// The `.lag` model.
    pub file: PathBuf,
    /// The run's options, passed to the model's binary as they are
    /// (`lagc run FILE --help` lists them): `--method field|direct`,
    /// `--integrator auto|explicit|stiff|magnus`, `--param NAME=VALUE`,
    /// `--init NAME=VALUE`, `--rtol R`, `--atol A`, `--samples N`,
    /// `--times T1,T2,…`, `--step-to-times`, `--no-global-error`,
    /// `--estimate-error`,
    /// `--plot FILE.svg [--phase X,Y]`, `--ensemble K`, `--sensitivity`,
    /// `--repeat N`, `--quiet`, `--summary text|json`, …;
    /// and lagc's own `--verbose`: the model's notes (N0001) on every run,
    /// not only when lagc builds its crate.
    #[arg(
        trailing_var_arg = true,
        allow_hyphen_values = true,
        value_name = "OPTIONS"
    )]
    pub args: Vec<String>,
}

#[derive(Debug, Args)]
pub struct CacheArgs {
    #[command(subcommand)]
    pub action: CacheAction,
}

#[derive(Debug, Subcommand)]
pub enum CacheAction {
    /// Every cached model: its file, size and when it last ran, least
    /// recently run first.
    List,
    /// Remove every cached model, binary and runtime (the next `lagc run`
    /// of a model rebuilds it).
    Clean,
}

#[derive(Debug, Args)]
pub struct DeriveArgs {
    /// The `.lag` model.
    pub file: PathBuf,
    /// The output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum Format {
    /// Plain text.
    Text,
    /// A LaTeX `align*` block.
    Latex,
}

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The `.lag` model to check.
    pub file: PathBuf,
}
