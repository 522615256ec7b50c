//! One step's continuous extension as a value detached from its
//! integrator (DOP853's order-7 and RODAS4's order-3 polynomials), so that
//! a solution can keep its steps; the integrators make them and
//! `stepper` only hands them on (it imported both integrators, which
//! import it).

/// One step's continuous extension, detached from its integrator.
#[derive(Clone, Debug)]
pub struct DenseStep {
    pub t_old: f64,
    pub t_new: f64,
    pub(crate) h: f64,
    pub(crate) kind: DenseKind,
}

#[derive(Clone, Debug)]
pub(crate) enum DenseKind {
    /// DOP853's order-7 extension (Hairer's `contd8` coefficients).
    Dop853 { cont: Vec<f64> },
    /// RODAS4's order-3 extension.
    Rodas4 {
        y_old: Vec<f64>,
        y: Vec<f64>,
        d2: Vec<f64>,
        d3: Vec<f64>,
    },
}

impl DenseStep {
    /// The state at `t` (clamped to the step).
    pub fn eval(&self, t: f64, out: &mut [f64]) {
        let s = if self.h > 0.0 {
            ((t - self.t_old) / self.h).clamp(0.0, 1.0)
        } else {
            1.0
        };
        match &self.kind {
            DenseKind::Dop853 { cont } => contd8(cont, cont.len() / 8, s, out),
            DenseKind::Rodas4 { y_old, y, d2, d3 } => rodas4_dense(y_old, y, d2, d3, s, out),
        }
    }
}

/// Hairer's `contd8`: the continuous extension at `θ = (t − t_old)/h`.
pub(crate) fn contd8(c: &[f64], n: usize, s: f64, out: &mut [f64]) {
    let s1 = 1.0 - s;
    for (i, o) in out.iter_mut().enumerate().take(n) {
        let conf1 = c[4 * n + i] + s * (c[5 * n + i] + s1 * (c[6 * n + i] + s * c[7 * n + i]));
        *o = c[i] + s * (c[n + i] + s1 * (c[2 * n + i] + s * (c[3 * n + i] + s1 * conf1)));
    }
}

/// RODAS4's continuous extension at `θ`.
pub(crate) fn rodas4_dense(
    y_old: &[f64],
    y: &[f64],
    d2: &[f64],
    d3: &[f64],
    s: f64,
    out: &mut [f64],
) {
    let s1 = 1.0 - s;
    for (i, o) in out.iter_mut().enumerate() {
        *o = y_old[i] * s1 + s * (y[i] + s1 * (d2[i] + s * d3[i]));
    }
}
