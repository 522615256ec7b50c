//! The IO of `lagc report`: runs the built model binary for every method
//! and tolerance (and the references when the model has no exact
//! solution) and collects a [`Report`]; the table and plot are built by
//! `lagc::report` from it.

use super::progress::Progress;
use lagc::report::{
    atol_for, largest_difference, parse_csv, parse_summary, reference_for, Measurement, Method,
    Outcome, Report, REFERENCE_RTOL,
};
use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

/// What to measure.
pub struct Plan<'a> {
    pub binary: &'a Path,
    pub model: String,
    pub tolerances: Vec<f64>,
    pub runs: usize,
    /// Passed to every run: `--param`, `--samples`.
    pub common_args: Vec<String>,
}

/// Exit status of a generated binary on a numerical failure.
const FAILURE_EXIT_STATUS: i32 = 3;

/// One run: `Ok(Ok((csv rows, summary)))`, `Ok(Err(message))` for a
/// numerical failure (exit 3), `Err` when the binary could not run or
/// rejected its arguments.
type RunResult = Result<Result<(Vec<Vec<f64>>, lagc::report::RunSummary), String>, String>;

fn run_once(plan: &Plan<'_>, method: Method, rtol: f64, runs: usize) -> RunResult {
    let output = Command::new(plan.binary)
        .args(&plan.common_args)
        .args(method.binary_args())
        .args([
            "--rtol",
            &format!("{rtol:e}"),
            "--atol",
            &format!("{:e}", atol_for(rtol)),
        ])
        .args(["--repeat", &runs.to_string(), "--summary", "json"])
        .output()
        .map_err(|e| format!("cannot run `{}`: {e}", plan.binary.display()))?;
    let stderr = String::from_utf8_lossy(&output.stderr);
    match output.status.code() {
        Some(0) => {
            let summary = parse_summary(&stderr)?;
            let rows = parse_csv(&String::from_utf8_lossy(&output.stdout))?;
            Ok(Ok((rows, summary)))
        }
        Some(FAILURE_EXIT_STATUS) => Ok(Err(parse_summary(&stderr)
            .err()
            .unwrap_or_else(|| stderr.trim().to_string()))),
        _ => Err(format!(
            "the model binary failed ({}): {}",
            output.status,
            stderr.trim()
        )),
    }
}

/// Runs every method at every tolerance, `plan.runs` timed solves each.
pub fn measure(plan: &Plan<'_>, progress_shown: bool) -> Result<Report, String> {
    let total = Method::ALL.len() * plan.tolerances.len();
    let mut progress = Progress::new(total, progress_shown);
    let mut references: HashMap<Method, Result<Vec<Vec<f64>>, String>> = HashMap::new();
    let mut measurements = Vec::new();
    let mut has_exact = None;
    for method in Method::ALL {
        for &rtol in &plan.tolerances {
            progress.start(&format!("{} rtol {rtol:e}", method.label()));
            let outcome = match run_once(plan, method, rtol, plan.runs)? {
                Err(message) => Outcome::Failed { message },
                Ok((rows, summary)) => {
                    let error = match summary.exact_error {
                        Some(error) => {
                            has_exact = Some(true);
                            Some(error)
                        }
                        None => {
                            has_exact = Some(false);
                            let reference_method = reference_for(method);
                            let reference = match references.get(&reference_method) {
                                Some(reference) => reference.clone(),
                                None => {
                                    progress.start(&format!(
                                        "reference: {} rtol {REFERENCE_RTOL:e}",
                                        reference_method.label()
                                    ));
                                    let reference = match run_once(
                                        plan,
                                        reference_method,
                                        REFERENCE_RTOL,
                                        1,
                                    )? {
                                        Ok((rows, _)) => Ok(rows),
                                        Err(message) => Err(message),
                                    };
                                    references.insert(reference_method, reference.clone());
                                    reference
                                }
                            };
                            reference
                                .ok()
                                .and_then(|r| largest_difference(&rows, &r).ok())
                        }
                    };
                    Outcome::Solved { summary, error }
                }
            };
            measurements.push(Measurement {
                method,
                rtol,
                atol: atol_for(rtol),
                outcome,
            });
            progress.finish_step();
        }
    }
    progress.clear();
    let failed_references: Vec<String> = references
        .iter()
        .filter_map(|(m, r)| {
            r.as_ref()
                .err()
                .map(|e| format!("{} failed: {e}", m.label()))
        })
        .collect();
    let error_basis = match has_exact {
        Some(true) => "the model's exact solution".to_string(),
        Some(false) => {
            let mut basis = format!(
                "a reference at rtol {REFERENCE_RTOL:e} by another method \
                 (direct DOP853; the field for direct DOP853)"
            );
            for failure in failed_references {
                basis.push_str(&format!("; reference {failure}"));
            }
            basis
        }
        None => "none (no run succeeded)".to_string(),
    };
    Ok(Report {
        model: plan.model.clone(),
        error_basis,
        runs: plan.runs,
        measurements,
    })
}
