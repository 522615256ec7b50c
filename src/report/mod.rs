//! `lagc report`: error against run time (SPEC §5), as pure functions from
//! measurements to text and SVG. The runs themselves (building the crate,
//! timing the binary) are IO and live in `src/cli/report.rs`.
//!
//! | file | what |
//! |---|---|
//! | `ladder.rs` | the tolerance ladder, `atol` from `rtol`, the reference runs |
//! | `summary.rs` | the generated binary's `--summary json` line, parsed |
//! | `samples.rs` | its CSV, parsed, and the largest difference of two |
//! | `table.rs` | the table on stdout and the machine-readable CSV |
//! | `plot.rs` | the work-precision plot (SVG, plotters) |

pub mod ladder;
pub mod plot;
pub mod samples;
pub mod summary;
pub mod table;

pub use ladder::{atol_for, default_tolerances, parse_tolerances, reference_for, REFERENCE_RTOL};
pub use plot::work_precision_svg;
pub use samples::{largest_difference, parse_csv};
pub use summary::{parse_summary, RunSummary};
pub use table::{data_csv, table};

/// A way of integrating the model, as `lagc report` compares them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// The field method (its coefficient system by DOP853, or the local
    /// field for non-affine systems).
    Field,
    /// Direct integration of (7) by DOP853.
    Explicit,
    /// Direct integration of (7) by RODAS4.
    Stiff,
}

impl Method {
    pub const ALL: [Method; 3] = [Method::Field, Method::Explicit, Method::Stiff];

    pub fn label(self) -> &'static str {
        match self {
            Method::Field => "field",
            Method::Explicit => "direct DOP853",
            Method::Stiff => "direct RODAS4",
        }
    }

    /// The generated binary's arguments that select this method. The
    /// integrator is pinned, so that neither the model's `integrator`
    /// statement nor the automatic switch to RODAS4 changes what a line of
    /// the report measures.
    pub fn binary_args(self) -> &'static [&'static str] {
        match self {
            Method::Field => &["--method", "field", "--integrator", "explicit"],
            Method::Explicit => &["--method", "direct", "--integrator", "explicit"],
            Method::Stiff => &["--method", "direct", "--integrator", "stiff"],
        }
    }
}

/// One run of one method at one tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    pub method: Method,
    pub rtol: f64,
    pub atol: f64,
    pub outcome: Outcome,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    Solved {
        summary: RunSummary,
        /// The largest error over the samples (relative to
        /// `max(|truth|, 1)`); `None` when there was nothing to compare
        /// with (the reference run failed).
        error: Option<f64>,
    },
    /// The run stopped (exit status 3) with this message.
    Failed { message: String },
}

/// Everything `lagc report` measured on one model.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// The model's file name, for titles.
    pub model: String,
    /// How the errors were measured, in words (exact solution, or which
    /// reference).
    pub error_basis: String,
    /// Timed solves per measurement (the time is their minimum).
    pub runs: usize,
    pub measurements: Vec<Measurement>,
}
