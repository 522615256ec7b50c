//! What a run prints: the trajectory as CSV on stdout (SPEC §3), streamed
//! row by row as the samples are produced (constant memory whatever the
//! number of samples).

use std::io::{self, Write};

/// `count` evenly spaced sample times over `[t0, t1]`, computed as
/// `t0 + i (t1 − t0)/(count − 1)` so that they print as the decimals one
/// expects (`0.15`, not `0.15000000000000002`), the last one `t1` exactly.
/// One sample is the final time alone.
pub fn sample_times(t0: f64, t1: f64, count: usize) -> Vec<f64> {
    match count {
        0 => Vec::new(),
        1 => vec![t1],
        _ => {
            let last = count - 1;
            (0..count)
                .map(|i| {
                    if i == last {
                        t1
                    } else {
                        t0 + i as f64 * (t1 - t0) / last as f64
                    }
                })
                .collect()
        }
    }
}

/// The CSV header `t,q1,q2,…,q1',q2',…` and any output columns.
pub fn write_header(out: &mut impl Write, state: &[&str], outputs: &[&str]) -> io::Result<()> {
    write!(out, "t")?;
    for name in state.iter().chain(outputs) {
        write!(out, ",{name}")?;
    }
    writeln!(out)
}

/// One CSV row; each number is the shortest decimal that reads back to the
/// same `f64`.
pub fn write_row(out: &mut impl Write, t: f64, state: &[f64], outputs: &[f64]) -> io::Result<()> {
    write_number(out, t)?;
    for &value in state.iter().chain(outputs) {
        write!(out, ",")?;
        write_number(out, value)?;
    }
    writeln!(out)
}

/// Plain notation for moderate magnitudes, scientific otherwise (`{}`
/// would print 1e-300 with 300 zeros); both shortest round-trip.
pub fn write_number(out: &mut impl Write, value: f64) -> io::Result<()> {
    let magnitude = value.abs();
    if value == 0.0 || !value.is_finite() || (1e-4..1e15).contains(&magnitude) {
        write!(out, "{value}")
    } else {
        write!(out, "{value:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_times_print_as_exact_decimals_and_end_on_t1() {
        let times = sample_times(0.0, 5.0, 101);
        assert_eq!(times[3].to_string(), "0.15");
        assert_eq!(times[7].to_string(), "0.35");
        assert_eq!(times[100], 5.0);
        assert_eq!(sample_times(0.0, 5.0, 1), vec![5.0]);
        let odd = sample_times(0.1, 0.7, 7);
        let printed: Vec<String> = odd.iter().map(|t| t.to_string()).collect();
        assert_eq!(printed, ["0.1", "0.2", "0.3", "0.4", "0.5", "0.6", "0.7"]);
    }

    #[test]
    fn rows_are_shortest_round_trip() {
        let mut out = Vec::new();
        write_row(&mut out, 0.1, &[1e-300, -2.5], &[3.0]).unwrap();
        assert_eq!(String::from_utf8(out).unwrap(), "0.1,1e-300,-2.5,3\n");
    }
}
