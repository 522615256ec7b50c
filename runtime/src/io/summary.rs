//! The run summary on stderr: what the method did, in words a user of the
//! field method can read (see the README for what each figure means), or
//! as one JSON object line (`--summary json`) for scripts.

use crate::method::solver::GlobalErrorEstimate;
use crate::run::options::{Ending, Outcome};
use std::fmt::Write as _;
use std::time::Duration;

/// Everything the summary line reports.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    pub outcome: Outcome,
    /// The smallest wall time of the solves (`--repeat`).
    pub wall_time: Duration,
    pub runs: usize,
    /// The largest error against the model's `exact` lines over the samples
    /// (relative to `max(|exact|, 1)`).
    pub exact_error: Option<f64>,
    /// `--estimate-error`: the largest difference from a run at a 100×
    /// tighter tolerance.
    pub estimated_error: Option<f64>,
}

impl Summary {
    /// The text form (several `key: value` parts on one line, then notes).
    pub fn text(&self) -> String {
        let r = &self.outcome.report;
        let mut s = format!(
            "method: {}; steps: {} (+{} rejected); right-side evaluations: {}",
            r.method, r.stats.accepted_steps, r.stats.rejected_steps, r.stats.rhs_evaluations
        );
        if let (Some(windows), Some(predictor)) = (r.windows, r.predictor) {
            let _ = write!(
                s,
                "; windows: {windows}; linearisations: {}; predictor steps: {}",
                r.linearizations, predictor.accepted_steps
            );
        }
        if let Some(condition) = r.largest_condition {
            let _ = write!(s, "; largest condition number: {condition:.3e}");
        }
        if let Some(count) = r.reanchorings {
            let _ = write!(s, "; re-anchorings: {count}");
        }
        if self.outcome.events > 0 {
            let _ = write!(s, "; events: {}", self.outcome.events);
        }
        let _ = write!(
            s,
            "; wall time: {:.3} ms",
            self.wall_time.as_secs_f64() * 1e3
        );
        match self.outcome.ending {
            Ending::End => {}
            // A `stop when` that holds at the start (and not only on its
            // boundary there) ends the run before any step: the one row is
            // the start, and the summary says the condition held there
            // rather than that it became true.
            Ending::Stopped(t) if r.stats.accepted_steps == 0 && self.outcome.events == 0 => {
                let _ = write!(
                    s,
                    "\nstopped at t = {t} (`stop when` already holds at the start: the run \
                     ends there; start on the condition's other side to integrate)"
                );
            }
            Ending::Stopped(t) => {
                let _ = write!(s, "\nstopped at t = {t} (`stop when` became true)");
            }
            Ending::Rest {
                impact,
                at,
                accumulation: Some(limit),
            } => {
                let _ = write!(
                    s,
                    "\nstopped at t = {at} (the impacts of `when {impact}` accumulate at \
                     t ≈ {limit}: the motion stays on its boundary from there, a contact \
                     the equations of motion do not describe)"
                );
            }
            Ending::Rest {
                impact,
                at,
                accumulation: None,
            } => {
                let _ = write!(
                    s,
                    "\nstopped at t = {at} (after the impact of `when {impact}` the motion \
                     stays on its boundary, a contact the equations of motion do not \
                     describe)"
                );
            }
        }
        for note in &r.notes {
            let _ = write!(s, "\nnote: {note}");
        }
        if let Some(kept) = &self.outcome.kept {
            let _ = write!(
                s,
                "\nconstraints kept: largest residual {:.3e} ({:.2} of the tolerance{}), \
                 {} projections after steps",
                kept.largest_absolute,
                kept.largest,
                if kept.largest_at.is_finite() {
                    format!(", at t = {:e}", kept.largest_at)
                } else {
                    String::new()
                },
                kept.projections
            );
        }
        if let Some(error) = self.exact_error {
            let _ = write!(s, "\nlargest error against the exact solution: {error:.3e}");
        }
        if let Some(estimate) = &r.global_error {
            s.push('\n');
            s.push_str(&global_error_line(estimate));
        }
        if let Some(error) = self.estimated_error {
            let _ = write!(
                s,
                "\nestimated global error (against a run at a 100× tighter tolerance): \
                 {error:.3e}"
            );
        }
        s
    }

    /// The warning the text form holds when the estimated global error
    /// passes 10·rtol or leaves steps out, for the JSON form's stderr (on a line of its own
    /// before the object).
    pub fn global_error_warning(&self) -> Option<String> {
        let g = self.outcome.report.global_error.as_ref()?;
        (g.largest > GLOBAL_ERROR_BOUND * g.rtol || !g.complete).then(|| global_error_line(g))
    }

    /// One JSON object (written by hand: the runtime has no dependencies).
    pub fn json(&self) -> String {
        let r = &self.outcome.report;
        let (stopped, accumulation) = match self.outcome.ending {
            Ending::End => ("null".to_string(), "null".to_string()),
            Ending::Stopped(t) => (json_number(Some(t)), "null".to_string()),
            Ending::Rest {
                at, accumulation, ..
            } => (json_number(Some(at)), json_number(accumulation)),
        };
        format!(
            "{{\"method\":{},\"steps\":{},\"rejected_steps\":{},\"rhs_evaluations\":{},\
             \"jacobian_evaluations\":{},\"linearizations\":{},\"windows\":{},\
             \"predictor_steps\":{},\"largest_condition\":{},\"reanchorings\":{},\
             \"events\":{},\"stopped_at\":{},\"impacts_accumulate_at\":{},\"budget_used\":{},\"wall_time_s\":{},\
             \"runs\":{},\"exact_error\":{},\"estimated_error\":{},\
             \"constraint_residual\":{},\"projections\":{},\"global_error_estimate\":{},\
             \"global_error_partial\":{}}}",
            json_string(&r.method),
            r.stats.accepted_steps,
            r.stats.rejected_steps,
            r.stats.rhs_evaluations,
            r.stats.jacobian_evaluations,
            r.linearizations,
            r.windows.map_or("null".to_string(), |w| w.to_string()),
            r.predictor
                .map_or("null".to_string(), |p| p.accepted_steps.to_string()),
            json_number(r.largest_condition),
            r.reanchorings.map_or("null".to_string(), |c| c.to_string()),
            self.outcome.events,
            stopped,
            accumulation,
            self.outcome.budget_used,
            json_number(Some(self.wall_time.as_secs_f64())),
            self.runs,
            json_number(self.exact_error),
            json_number(self.estimated_error),
            json_number(self.outcome.kept.map(|k| k.largest_absolute)),
            self.outcome
                .kept
                .map_or("null".to_string(), |k| k.projections.to_string()),
            json_number(r.global_error.map(|g| g.largest)),
            r.global_error
                .map_or("null".to_string(), |g| (!g.complete).to_string()),
        )
    }
}

/// The bound the summary holds a run's estimated global error to, in
/// units of its relative tolerance.
pub use crate::ode::dop853::global_error::BOUND as GLOBAL_ERROR_BOUND;

// A carried global error estimate at least this large (relative) is
// reported as amplification, not as a number.
use crate::ode::dop853::global_error::AMPLIFIED;

/// The summary's line on the global error the method carried (direct
/// integration and the quasilinear field): within `10·rtol`, or a warning
/// past it (see `dop853::global_error` and its `growth`).
fn global_error_line(g: &GlobalErrorEstimate) -> String {
    let bound = GLOBAL_ERROR_BOUND * g.rtol;
    let partial = if g.complete {
        ""
    } else {
        " (partial: RODAS4's steps, and the field's stiff and Magnus windows', are not \
         accounted for)"
    };
    // Carried past the state's own size (relative to max(|x|, 1)), the
    // linear estimate means nothing as a number: a chaotic double
    // pendulum over 100 s gave 1e49. Two motions get here, and the line
    // cannot tell them apart, so it names both: a chaotic one, which a
    // tighter tolerance helps only logarithmically, and a regular one run
    // long enough for its phase to drift by a whole swing (a pendulum at
    // 1 rad over 1000 periods, direct DOP853 at rtol 1e-5: 2.2 off at the
    // end), which a tighter tolerance helps in proportion (1e-6: 0.20,
    // 1e-9: 2.1e-5). Saying "only logarithmically" alone sent that user
    // away from the remedy that works.
    if g.largest >= AMPLIFIED {
        return format!(
            "warning: the motion amplifies the steps' errors past the state's own size \
             (estimated global error above {AMPLIFIED:.0e}, relative{partial}): the state \
             after some time is not determined by the tolerance. A chaotic motion's is \
             not at any tolerance (a tighter --rtol moves that time later only \
             logarithmically; invariants, an energy, and statistics are what such a run \
             can give); a regular motion's phase drifts over a long run, and a tighter \
             --rtol shrinks the drift in proportion. --estimate-error measures the \
             difference"
        );
    }
    if !g.complete && g.largest <= bound {
        // Steps that carry no estimate (RODAS4's, the field's stiff and
        // Magnus windows') may hold the run's whole error: a stiff spring
        // losing mass (examples/mass_loss_stiff_spring.lag) by RODAS4 at
        // rtol 1e-6 ended 1.5e-2 off while this line said "within
        // 10·rtol (estimated 0.0e0 (partial …))". What the other steps
        // sum to bounds nothing, so the line says so, and it is a warning.
        return format!(
            "warning: global error not estimated: RODAS4's steps, and the field's stiff and \
             Magnus windows', carry no estimate of their error (the other steps' errors sum \
             to {:.1e}, under 10·rtol = {bound:.1e}), so the run may be further off than its \
             tolerance says; --estimate-error measures it",
            g.largest
        );
    }
    if g.largest <= bound {
        // The estimate is the state's at the steps' ends; a sample
        // between them is read from a continuous extension, whose own
        // error comes on top: the samples' largest error passed the ends'
        // by up to 3.0 rtol for the field and 6.7 rtol for direct DOP853's
        // order-7 extension (32 models × 4 tolerances at 1001 samples,
        // docs/BENCHMARKS.md §10p), 10–50× the ends' error on short runs.
        // Said here, so that the estimate is not read as the samples'.
        format!(
            "global error: within 10·rtol = {bound:.1e} (estimated {:.1e}{partial} at the \
             steps' ends, their local errors summed, and read in each component's swing where \
             it passes zero; samples between steps add the continuous extension's error, up to \
             a few rtol)",
            g.largest
        )
    } else {
        format!(
            "warning: estimated global error {:.1e} passes 10·rtol = {bound:.1e}{partial}: \
             the steps' local errors add up over the run (past the bound, each step's error \
             measured and carried along the motion, which may amplify it; not counting the \
             output between steps); a tighter --rtol brings it down, \
             --estimate-error measures it",
            g.largest
        )
    }
}

/// A JSON number (`{:e}` reads back exactly), `null` when absent or not
/// finite.
pub fn json_number(value: Option<f64>) -> String {
    match value {
        Some(v) if v.is_finite() => format!("{v:e}"),
        _ => "null".to_string(),
    }
}

pub fn json_string(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_estimate_past_the_states_size_is_reported_as_amplification() {
        let at = |largest: f64| {
            global_error_line(&GlobalErrorEstimate {
                largest,
                rtol: 1e-10,
                complete: true,
            })
        };
        assert!(
            at(1e-10).starts_with("global error: within"),
            "{}",
            at(1e-10)
        );
        assert!(at(1e-6).starts_with("warning: estimated global error 1.0e-6"));
        let amplified = at(1.1e49);
        assert!(
            amplified.contains("amplifies") && !amplified.contains("e49"),
            "{amplified}"
        );
    }

    /// An estimate that leaves steps out (RODAS4's) cannot say the run
    /// is within its bound, however small the rest sums to.
    #[test]
    fn a_partial_estimate_under_the_bound_is_a_warning_not_within() {
        let line = global_error_line(&GlobalErrorEstimate {
            largest: 0.0,
            rtol: 1e-6,
            complete: false,
        });
        assert!(
            line.starts_with("warning: global error not estimated"),
            "{line}"
        );
        assert!(!line.contains("within"), "{line}");
        let past = global_error_line(&GlobalErrorEstimate {
            largest: 1e-3,
            rtol: 1e-6,
            complete: false,
        });
        assert!(
            past.starts_with("warning: estimated global error 1.0e-3"),
            "{past}"
        );
    }

    /// The line cannot tell a chaotic motion from a regular one whose phase
    /// drifted by a whole swing over a long run (a pendulum over 1000
    /// periods at rtol 1e-5): it must not tell the second that a tighter
    /// tolerance helps only logarithmically, and must name the drift.
    #[test]
    fn the_amplification_line_names_a_drifting_phase_as_well_as_chaos() {
        let line = global_error_line(&GlobalErrorEstimate {
            largest: 2.0,
            rtol: 1e-5,
            complete: true,
        });
        assert!(line.contains("chaotic"), "{line}");
        assert!(
            line.contains("phase drifts") && line.contains("in proportion"),
            "{line}"
        );
    }
}
