//! The motion over one step as a value that outlives the method's solver
//! (a [`crate::run::solution::Solution`] keeps one per step): the state's own
//! continuous extension, or the field's coefficients with their anchor.

use crate::method::field::conditions::recover_state;
use crate::ode::stepper::DenseStep;

/// The motion over one step, from its continuous extension.
#[derive(Clone, Debug)]
pub enum Segment {
    /// The state itself (direct integration).
    State(DenseStep),
    /// The field's coefficients and sensitivities `y = (f, S)` with the
    /// window's anchor state: the state by the conditions (13).
    Coefficients { y: DenseStep, anchor: Vec<f64> },
    /// The field's projective form `y = (w, P)` (see
    /// `field::coefficients::ProjectiveCoefficients`).
    Projective { y: DenseStep, anchor: Vec<f64> },
    /// The state at Chebyshev points of the step (integrators without a
    /// continuous extension of their own: Magnus), interpolated.
    Points { t: Vec<f64>, x: Vec<Vec<f64>> },
}

impl Segment {
    pub fn t_old(&self) -> f64 {
        match self {
            Segment::State(d)
            | Segment::Coefficients { y: d, .. }
            | Segment::Projective { y: d, .. } => d.t_old,
            Segment::Points { t, .. } => t[0],
        }
    }

    pub fn t_new(&self) -> f64 {
        match self {
            Segment::State(d)
            | Segment::Coefficients { y: d, .. }
            | Segment::Projective { y: d, .. } => d.t_new,
            Segment::Points { t, .. } => *t.last().unwrap_or(&t[0]),
        }
    }

    /// The state at `t` (clamped to the step); `false` where the field's
    /// conditions are singular.
    pub fn eval(&self, t: f64, out: &mut [f64]) -> bool {
        let n = out.len();
        match self {
            Segment::State(d) => {
                d.eval(t, out);
                true
            }
            Segment::Coefficients { y, anchor } => {
                let mut v = vec![0.0; n + n * n];
                y.eval(t, &mut v);
                let (f, s) = v.split_at(n);
                match recover_state(f, s, anchor) {
                    Some(state) => {
                        out.copy_from_slice(&state);
                        true
                    }
                    None => false,
                }
            }
            Segment::Projective { y, anchor } => {
                let mut v = vec![0.0; n * (n + 1)];
                y.eval(t, &mut v);
                let (mut f, mut s) = (vec![0.0; n], vec![0.0; n * n]);
                if !crate::method::field::coefficients::projective_field(&v, &mut f, &mut s) {
                    return false;
                }
                match recover_state(&f, &s, anchor) {
                    Some(state) => {
                        out.copy_from_slice(&state);
                        true
                    }
                    None => false,
                }
            }
            Segment::Points { t: ts, x } => {
                barycentric(ts, x, t, out);
                true
            }
        }
    }
}

/// The polynomial through `(ts[i], xs[i])` at `t` (barycentric form, for
/// Chebyshev points).
fn barycentric(ts: &[f64], xs: &[Vec<f64>], t: f64, out: &mut [f64]) {
    let m = ts.len();
    if let Some(i) = ts.iter().position(|&s| s == t) {
        out.copy_from_slice(&xs[i]);
        return;
    }
    let weights: Vec<f64> = (0..m)
        .map(|j| {
            let p: f64 = (0..m).filter(|&k| k != j).map(|k| ts[j] - ts[k]).product();
            1.0 / p
        })
        .collect();
    let mut denominator = 0.0;
    out.fill(0.0);
    for j in 0..m {
        let c = weights[j] / (t - ts[j]);
        denominator += c;
        for (o, v) in out.iter_mut().zip(&xs[j]) {
            *o += c * v;
        }
    }
    out.iter_mut().for_each(|o| *o /= denominator);
}
