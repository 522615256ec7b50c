//! What a run prints: the trajectory as CSV on stdout (SPEC §3) and a
//! summary of the work on stderr.

use std::fmt;
use std::io::{self, Write};
use std::time::Duration;

/// `count` evenly spaced sample times over `[t0, t1]`, both ends included
/// exactly (`count = 1` gives `[t0]`).
pub fn sample_times(t0: f64, t1: f64, count: usize) -> Vec<f64> {
    match count {
        0 => Vec::new(),
        1 => vec![t0],
        _ => {
            let last = count - 1;
            (0..count)
                .map(|i| {
                    if i == last {
                        t1
                    } else {
                        t0 + (t1 - t0) * (i as f64 / last as f64)
                    }
                })
                .collect()
        }
    }
}

/// The CSV header `t,q1,q2,…,q1',q2',…`: the state names in the order of
/// the state (6), as given by the generated code.
pub fn write_header(out: &mut impl Write, state_names: &[&str]) -> io::Result<()> {
    write!(out, "t")?;
    for name in state_names {
        write!(out, ",{name}")?;
    }
    writeln!(out)
}

/// One CSV row. Each number is the shortest decimal that reads back to the
/// same `f64`, so no digit is lost.
pub fn write_row(out: &mut impl Write, t: f64, state: &[f64]) -> io::Result<()> {
    write_number(out, t)?;
    for &value in state {
        write!(out, ",")?;
        write_number(out, value)?;
    }
    writeln!(out)
}

/// Plain notation for moderate magnitudes, scientific otherwise (Rust's
/// `{}` would print 1e-300 with 300 zeros).
fn write_number(out: &mut impl Write, value: f64) -> io::Result<()> {
    let magnitude = value.abs();
    if value == 0.0 || !value.is_finite() || (1e-4..1e15).contains(&magnitude) {
        write!(out, "{value}")
    } else {
        write!(out, "{value:e}")
    }
}

/// The work of one run, printed to stderr.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// e.g. `field (DOP853)` or `direct (RODAS4)`.
    pub method: String,
    pub steps: usize,
    pub rejected_steps: usize,
    pub rhs_evaluations: usize,
    /// Field method only: the largest condition number of the conditions.
    pub largest_condition: Option<f64>,
    /// Field method only: how many times the field was re-anchored.
    pub reanchorings: Option<usize>,
    pub wall_time: Duration,
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "method: {}; steps: {} (+{} rejected); right-side evaluations: {}",
            self.method, self.steps, self.rejected_steps, self.rhs_evaluations
        )?;
        if let Some(condition) = self.largest_condition {
            write!(f, "; largest condition number: {condition:.3e}")?;
        }
        if let Some(count) = self.reanchorings {
            write!(f, "; re-anchorings: {count}")?;
        }
        write!(
            f,
            "; wall time: {:.3} ms",
            self.wall_time.as_secs_f64() * 1e3
        )
    }
}
