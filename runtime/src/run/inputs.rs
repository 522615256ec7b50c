//! Inputs (SPEC §2.3): signals set from outside the model — a CSV given
//! with `--input`, a Python caller, an FMU importer.
//!
//! The generated model holds its inputs' current values ([`Inputs`], read
//! by the right side like its params: one load and one multiply-add, no
//! argument threaded through every integrator) and the run changes them
//! only between segments. On each segment an input is a line in `t`
//! (constant when held), so the right side is smooth there and its time
//! partial (`∂X/∂u · u'`, emitted by lagc) exact; a change of value or of
//! slope is a discontinuity, and the integration restarts there, like at
//! an event ([`run_driven`], `Integration::set_inputs`).

use crate::failure::Failure;
use crate::model::{DynModel, Inputs};
use crate::run::integration::{Advance, Integration};
use crate::run::options::{Ending, Options, Outcome};

/// How a signal goes between its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Each value holds until the next sample's time (the default).
    Hold,
    /// A straight line between samples.
    Linear,
}

/// One input's samples `(t_k, v_k)`, times strictly increasing. Before the
/// first sample the first value holds, after the last the last one.
#[derive(Clone, Debug, PartialEq)]
pub struct Signal {
    times: Vec<f64>,
    values: Vec<f64>,
    interpolation: Interpolation,
}

impl Signal {
    /// A signal from its samples: at least one, finite, times strictly
    /// increasing (an error in words otherwise).
    pub fn new(
        times: Vec<f64>,
        values: Vec<f64>,
        interpolation: Interpolation,
    ) -> Result<Signal, String> {
        if times.is_empty() || times.len() != values.len() {
            return Err("a signal needs at least one row `t,value`".to_string());
        }
        if let Some(v) = times.iter().chain(&values).find(|v| !v.is_finite()) {
            return Err(format!("{v} is not a finite number"));
        }
        if let Some(w) = times.windows(2).find(|w| w[1] <= w[0]) {
            return Err(format!(
                "the times must increase: {} follows {}",
                w[1], w[0]
            ));
        }
        Ok(Signal {
            times,
            values,
            interpolation,
        })
    }

    /// Reads a CSV with a header naming the columns `t` and `name` (other
    /// columns are ignored).
    pub fn from_csv(
        text: &str,
        name: &str,
        interpolation: Interpolation,
    ) -> Result<Signal, String> {
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        let header: Vec<&str> = lines
            .next()
            .ok_or("the file is empty")?
            .split(',')
            .map(str::trim)
            .collect();
        let column = |wanted: &str| {
            header
                .iter()
                .position(|h| h.trim_matches('"') == wanted)
                .ok_or_else(|| format!("no column `{wanted}` in the header `{}`", header.join(",")))
        };
        let (ct, cv) = (column("t")?, column(name)?);
        let (mut times, mut values) = (Vec::new(), Vec::new());
        for (row, line) in lines.enumerate() {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            let cell = |c: usize| -> Result<f64, String> {
                let text = cells
                    .get(c)
                    .ok_or_else(|| format!("row {} has no column {}", row + 2, c + 1))?;
                text.parse::<f64>()
                    .map_err(|_| format!("row {}: `{text}` is not a number", row + 2))
            };
            times.push(cell(ct)?);
            values.push(cell(cv)?);
        }
        Signal::new(times, values, interpolation)
    }

    /// The value just after `t` and the rate on the piece that starts at
    /// `t` (0 when held).
    fn after(&self, t: f64) -> (f64, f64) {
        // The last sample at or before t.
        let k = self.times.partition_point(|&s| s <= t);
        if k == 0 {
            return (self.values[0], 0.0);
        }
        let k = k - 1;
        match self.interpolation {
            Interpolation::Hold => (self.values[k], 0.0),
            Interpolation::Linear if k + 1 < self.times.len() => {
                let rate =
                    (self.values[k + 1] - self.values[k]) / (self.times[k + 1] - self.times[k]);
                (self.values[k] + rate * (t - self.times[k]), rate)
            }
            Interpolation::Linear => (self.values[k], 0.0),
        }
    }

    /// The times in `(t0, t1)` where the value (held) or the slope
    /// (linear) changes.
    fn breaks(&self, t0: f64, t1: f64) -> impl Iterator<Item = f64> + '_ {
        let hold = self.interpolation == Interpolation::Hold;
        self.times
            .iter()
            .enumerate()
            .filter(move |&(k, &t)| {
                t > t0 && t < t1 && (!hold || (k > 0 && self.values[k] != self.values[k - 1]))
            })
            .map(|(_, &t)| t)
    }
}

/// A model's inputs over a run: a signal for some, the default for the
/// others.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Schedule {
    /// `signals[i]`: input `i`'s signal, `None` for its default.
    pub signals: Vec<Option<Signal>>,
}

impl Schedule {
    /// The inputs on the segment that starts at `t`.
    pub fn at(&self, defaults: &[f64], t: f64) -> Inputs {
        let (mut values, mut rates) = (defaults.to_vec(), vec![0.0; defaults.len()]);
        for (i, signal) in self.signals.iter().enumerate().take(defaults.len()) {
            if let Some(signal) = signal {
                (values[i], rates[i]) = signal.after(t);
            }
        }
        Inputs::lines(&values, &rates, t)
    }

    /// Every time in `(t0, t1)` where an input changes, ascending.
    pub fn breaks(&self, t0: f64, t1: f64) -> Vec<f64> {
        let mut all: Vec<f64> = self
            .signals
            .iter()
            .flatten()
            .flat_map(|s| s.breaks(t0, t1))
            .collect();
        all.sort_by(f64::total_cmp);
        all.dedup();
        all
    }
}

/// What a driven run did: the run's outcome, and the number of restarts
/// at input changes.
#[derive(Clone, Debug, PartialEq)]
pub struct Driven {
    pub outcome: Outcome,
    pub restarts: usize,
}

/// Integrates `model` from `(t0, x0)` to `t1` with its inputs following
/// `schedule`: one [`Integration`] advanced to every change of an input,
/// where the new values are set and it restarts
/// ([`Integration::set_inputs`]: the components the constraints fix
/// recomputed, the others carried over), and to every time of `times`,
/// where `sample(t, x)` is called (a sample at a change time sees the new
/// inputs), as [`crate::run::run`] samples. The work budget is one for
/// the whole run.
#[allow(clippy::too_many_arguments)]
pub fn run_driven(
    model: &mut dyn DynModel,
    options: &Options,
    schedule: &Schedule,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
    mut sample: impl FnMut(&dyn DynModel, f64, &[f64]) -> Result<(), Failure>,
) -> Result<Driven, Failure> {
    let defaults = model.input_defaults().to_vec();
    let breaks = schedule.breaks(t0, t1);
    // The state at t0 under the inputs there (a no-op for one made under
    // them, `cli::prepare_driven`).
    model.set_inputs(&schedule.at(&defaults, t0));
    let mut x = x0.to_vec();
    model.constrained(t0, x0, &mut x)?;
    let mut integration = Integration::new(model, options, t0, t1, &x);
    let mut last: Option<f64> = None;
    let mut restarts = 0;
    let mut next_break = 0;
    // Every change (those past the last sample too), then the samples at
    // or after it; at one time the change comes first.
    let mut samples = times.iter().copied().peekable();
    loop {
        let change = breaks.get(next_break).copied();
        let at_sample = samples.peek().copied();
        let (t, is_change) = match (change, at_sample) {
            (Some(c), Some(s)) if c <= s => (c, true),
            (Some(c), None) => (c, true),
            (_, Some(s)) => (s, false),
            (None, None) => break,
        };
        match integration.advance_to(t)? {
            Advance::Reached(_) => {}
            Advance::Ended(_) => break,
        }
        if is_change {
            next_break += 1;
            integration.set_inputs(&schedule.at(&defaults, t))?;
            restarts += 1;
        } else {
            samples.next();
            sample(integration.model(), t, integration.state())?;
            last = Some(t);
        }
    }
    let outcome = integration.finish()?;
    if let Ending::Stopped(at) | Ending::Rest { at, .. } = outcome.ending {
        if last != Some(at) {
            sample(integration.model(), at, integration.state())?;
        }
    }
    Ok(Driven { outcome, restarts })
}

/// A run as every caller makes it (`lagc run`, the Python module's
/// `solve`): without a schedule, [`crate::run::run`]; with one (a
/// model with inputs, signals given or not), [`run_driven`], its restarts
/// counted in the outcome's notes. One function, so that the CSV and the
/// Python rows of a driven run are the same steps, bit for bit.
#[allow(clippy::too_many_arguments)]
pub fn drive(
    model: &mut dyn DynModel,
    options: &Options,
    schedule: Option<&Schedule>,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
    sample: impl FnMut(&dyn DynModel, f64, &[f64]) -> Result<(), Failure>,
) -> Result<Outcome, Failure> {
    let mut spare = crate::run::integration::Spare::default();
    drive_reusing(
        model, options, schedule, t0, t1, x0, times, sample, &mut spare,
    )
}

/// [`drive`] in the storage of an earlier run on the same model
/// ([`crate::run::run_reusing`]; a driven run, with a schedule, makes its
/// own): the same run. Solves repeated on one model go through it.
#[allow(clippy::too_many_arguments)]
pub fn drive_reusing(
    model: &mut dyn DynModel,
    options: &Options,
    schedule: Option<&Schedule>,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
    sample: impl FnMut(&dyn DynModel, f64, &[f64]) -> Result<(), Failure>,
    spare: &mut crate::run::integration::Spare,
) -> Result<Outcome, Failure> {
    let Some(schedule) = schedule else {
        return crate::run::run_reusing(model, options, t0, t1, x0, times, sample, spare);
    };
    let driven = run_driven(model, options, schedule, t0, t1, x0, times, sample)?;
    let mut outcome = driven.outcome;
    if driven.restarts > 0 {
        outcome.report.notes.push(format!(
            "inputs: restarted at {} change{}",
            driven.restarts,
            if driven.restarts == 1 { "" } else { "s" }
        ));
    }
    Ok(outcome)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signal(rows: &[(f64, f64)], interpolation: Interpolation) -> Signal {
        let (t, v) = rows.iter().copied().unzip();
        Signal::new(t, v, interpolation).unwrap()
    }

    #[test]
    fn a_held_signal_changes_only_where_its_value_does() {
        let s = signal(
            &[(0.0, 1.0), (1.0, 2.0), (2.0, 2.0), (3.0, 0.0)],
            Interpolation::Hold,
        );
        let schedule = Schedule {
            signals: vec![None, Some(s)],
        };
        assert_eq!(schedule.breaks(0.0, 10.0), vec![1.0, 3.0]);
        // Changes at or past the span's ends are no restarts.
        assert_eq!(schedule.breaks(1.0, 3.0), Vec::<f64>::new());
        let at = schedule.at(&[7.0, 9.0], 1.0);
        assert_eq!((at.at(0, 5.0), at.at(1, 1.5), at.rate(1)), (7.0, 2.0, 0.0));
        // Before the first row the first value holds.
        let early = Schedule {
            signals: vec![Some(signal(&[(1.0, 4.0)], Interpolation::Hold))],
        };
        assert_eq!(early.at(&[0.0], -1.0).at(0, -1.0), 4.0);
    }

    #[test]
    fn a_linear_signal_is_a_line_on_each_piece_and_holds_outside() {
        let s = signal(&[(0.0, 0.0), (2.0, 4.0), (3.0, 1.0)], Interpolation::Linear);
        let schedule = Schedule {
            signals: vec![Some(s)],
        };
        assert_eq!(schedule.breaks(-1.0, 5.0), vec![0.0, 2.0, 3.0]);
        let first = schedule.at(&[0.0], 0.5);
        assert_eq!(
            (first.at(0, 0.5), first.at(0, 1.5), first.rate(0)),
            (1.0, 3.0, 2.0)
        );
        let second = schedule.at(&[0.0], 2.0);
        assert_eq!((second.at(0, 2.5), second.rate(0)), (2.5, -3.0));
        let after = schedule.at(&[0.0], 3.0);
        assert_eq!((after.at(0, 7.0), after.rate(0)), (1.0, 0.0));
    }

    #[test]
    fn malformed_signals_are_refused_in_words() {
        let hold = Interpolation::Hold;
        let read = |text: &str| Signal::from_csv(text, "u", hold).unwrap_err();
        assert!(read("").contains("empty"));
        assert!(read("t,v\n0,1\n").contains("no column `u`"));
        assert!(read("t,u\n0,1\n0,2\n").contains("must increase"));
        assert!(read("t,u\n0,x\n").contains("`x` is not a number"));
        assert!(read("t,u\n0\n").contains("no column 2"));
        assert!(read("t,u\n0,inf\n").contains("not a finite number"));
        assert!(read("t,u\n").contains("at least one row"));
        let quoted = Signal::from_csv("\"t\",\"u\"\n0,1\n", "u", hold).unwrap();
        assert_eq!(quoted.after(5.0), (1.0, 0.0));
    }
}
