//! The report as a text table (stdout) and as CSV (for scripts).

use super::{Outcome, Report};
use std::fmt::Write;

/// `1e-3`, `2.50e-7`: one digit when that is the value (to rounding, so
/// that `1e-4 · 1e-2` prints as `1e-6`), three otherwise.
fn short(v: f64) -> String {
    let one = format!("{v:.0e}");
    match one.parse::<f64>() {
        Ok(back) if (back - v).abs() <= 1e-12 * v.abs() => one,
        _ => format!("{v:.2e}"),
    }
}

/// The table: one row per measurement, in the order measured. Failed runs
/// are rows too, with their message.
pub fn table(report: &Report) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}: error = largest |x − truth| / max(|truth|, 1) over the samples, truth = {}; \
         time = smallest of {} solves",
        report.model, report.error_basis, report.runs
    );
    let _ = writeln!(
        out,
        "{:<15} {:>6} {:>6} {:>11} {:>10} {:>9} {:>7}  notes",
        "method", "rtol", "atol", "time [ms]", "error", "RHS evals", "steps"
    );
    for m in &report.measurements {
        let head = format!(
            "{:<15} {:>6} {:>6}",
            m.method.label(),
            short(m.rtol),
            short(m.atol)
        );
        let _ = match &m.outcome {
            Outcome::Solved { summary, error } => {
                let error = error.map_or("—".to_string(), |e| format!("{e:.2e}"));
                let mut notes = summary.method.clone();
                if let Some(c) = summary.largest_condition {
                    let _ = write!(notes, "; condition ≤ {c:.1e}");
                }
                if let Some(r) = summary.reanchorings.filter(|&r| r > 0) {
                    let _ = write!(notes, "; {r} re-anchorings");
                }
                writeln!(
                    out,
                    "{head} {:>11.4} {:>10} {:>9} {:>7}  {notes}",
                    summary.wall_time_s * 1e3,
                    error,
                    summary.rhs_evaluations,
                    summary.steps
                )
            }
            Outcome::Failed { message } => writeln!(out, "{head} {:>11}  failed: {message}", "—"),
        };
    }
    out
}

/// CSV with one row per measurement:
/// `method,rtol,atol,time_s,error,rhs_evaluations,steps,status,message`
/// (empty fields where a run failed).
pub fn data_csv(report: &Report) -> String {
    let mut out =
        String::from("method,rtol,atol,time_s,error,rhs_evaluations,steps,status,message\n");
    for m in &report.measurements {
        let _ = match &m.outcome {
            Outcome::Solved { summary, error } => writeln!(
                out,
                "{},{:e},{:e},{:e},{},{},{},ok,",
                m.method.label(),
                m.rtol,
                m.atol,
                summary.wall_time_s,
                error.map_or(String::new(), |e| format!("{e:e}")),
                summary.rhs_evaluations,
                summary.steps
            ),
            Outcome::Failed { message } => writeln!(
                out,
                "{},{:e},{:e},,,,,failed,\"{}\"",
                m.method.label(),
                m.rtol,
                m.atol,
                message.replace('"', "\"\"")
            ),
        };
    }
    out
}
