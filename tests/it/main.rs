//! The one integration-test binary.

mod between_steps;
mod bit_identity;
mod cache;
mod candidate_resets;
mod chains;
mod check_build;
mod cli;
mod collisions;
mod coupled_nonlinear;
mod depth;
mod early_errors;
mod ensemble;
mod errors;
mod examples;
mod expect;
mod failure_rows;
mod field;
mod fmu;
mod generated;
mod holonomic;
mod honest_summaries;
mod impacts;
mod inputs;
mod ir;
mod kernel;
mod language_v2;
mod latex;
mod linearize;
mod mass_law_forms;
mod mechanics;
mod nonlinear;
mod parser;
mod poor_pivots;
mod python;
mod raised_estimates;
mod readme_program;
mod reference_runs;
mod released_level;
mod report;
mod robustness;
mod rolling_bodies;
mod runtime_failures;
mod sensitivity;
mod settling;
mod source_text;
mod stages;
mod stiff_extreme;
mod stiff_joint;
mod textbook_constraints;
mod textbook_events;
mod textbook_long;
mod textbook_loops;
mod textbook_mass_impacts;
mod textbook_motion;
mod textbook_rolling;
mod turning_points;

use lagc::diagnostic::{self, Diagnostic};

/// Runs the front end and the derivation on a file's bytes exactly as
/// `lagc check` does, and renders its diagnostics without colour under
/// `file_name`.
pub fn check_bytes(bytes: &[u8], file_name: &str) -> Result<lagc::check::model::Model, String> {
    lagc::on_big_stack(|| {
        let (source, result) = lagc::check_and_derive_bytes(bytes);
        result
            .map(|(model, _)| model)
            .map_err(|diagnostics: Vec<Diagnostic>| {
                diagnostic::render(&diagnostics, file_name, &source, false)
            })
    })
}

/// The repository root, for reading examples and test data.
pub fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The error against the model's `exact` lines that a generated binary's
/// summary reports on stderr.
pub fn exact_error(stderr: &str) -> f64 {
    stderr
        .lines()
        .find_map(|l| l.strip_prefix("largest error against the exact solution: "))
        .unwrap_or_else(|| panic!("no exact error in {stderr}"))
        .trim()
        .parse()
        .unwrap()
}

/// The largest difference of two states (or rows), each component relative
/// to the second's size (at least 1).
pub fn largest_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / y.abs().max(1.0))
        .fold(0.0, f64::max)
}
