//! The Magnus integrator for LINEAR coefficient systems
//! `f' = A(t) f + g(t)` (`A = ∂F/∂f` independent of `f`, `g = F(t, 0)`),
//! together with their sensitivities `S' = A S`.
//!
//! One step is the fourth-order Magnus method with two Gauss points on the
//! augmented `(N+1) × (N+1)` matrix `Ã = [[A, g], [0, 0]]`:
//! `Ω = h/2 (Ã₁ + Ã₂) + (√3/12) h² [Ã₂, Ã₁]`, `(f, 1) ← exp(Ω) (f, 1)`, and
//! `S ← Φ S` with `Φ` the upper-left `N × N` block of `exp(Ω)` (`S` needs
//! nothing more: it obeys the homogeneous part of the same equation).
//!
//! Why: the coefficient system is the adjoint of the motion, so a fast
//! decaying mode of the motion is a fast GROWING mode here. An exponential
//! integrator follows `e^{+|λ|h}` exactly for constant `A`, whatever `h`,
//! so the step is limited by the variation of `A(t)` and by how much growth
//! the field may accumulate before it re-anchors (`growth_per_step`), not
//! by the integrator's own stability or accuracy on the fast mode.
//!
//! Error control by step doubling: one step of `h` against two of `h/2`;
//! their difference `/15` estimates the error of the two half steps, and
//! the accepted state is the Richardson combination (local order 6).

use super::error::Failure;
use super::stepper::{
    first_non_finite, rms_norm, step_toward, underflow_failure, underflows, Stats, Tolerance,
};
use super::system::CoefficientSystem;
use nalgebra::DMatrix;

const SAFETY: f64 = 0.9;
const MIN_SCALE: f64 = 0.2;
const MAX_SCALE: f64 = 5.0;

/// Offsets of the two Gauss–Legendre nodes from the midpoint, in units of `h`.
const GAUSS_OFFSET: f64 = 0.288_675_134_594_812_9; // √3/6
const COMMUTATOR_WEIGHT: f64 = 0.144_337_567_297_406_43; // √3/12

/// The Magnus integrator at time `t` with augmented state `y = (f, S)`
/// (the layout of [`super::sensitivity::Sensitized`]).
pub struct Magnus {
    tol: Tolerance,
    t: f64,
    y: Vec<f64>,
    h: f64,
    /// The most the sensitivities may grow in one step (`‖Φ‖∞`): the field
    /// re-anchors when they grow past its threshold, so a step that grows
    /// more than that would only be thrown away.
    growth_per_step: f64,
    stats: Stats,
}

impl Magnus {
    /// Starts at `(t0, y0)` with the first step `h0` (the field passes the
    /// step that worked before a re-anchoring, or a guess).
    pub fn new(t0: f64, y0: &[f64], tol: Tolerance, h0: f64, growth_per_step: f64) -> Self {
        Magnus {
            tol,
            t: t0,
            y: y0.to_vec(),
            h: h0,
            growth_per_step,
            stats: Stats::default(),
        }
    }

    pub fn time(&self) -> f64 {
        self.t
    }

    pub fn state(&self) -> &[f64] {
        &self.y
    }

    pub fn stats(&self) -> Stats {
        self.stats
    }

    pub fn proposed_step(&self) -> f64 {
        self.h
    }

    pub fn propose_step(&mut self, h: f64) {
        if h.is_finite() && h > 0.0 {
            self.h = h;
        }
    }

    /// The augmented matrix `Ã(t)`.
    fn augmented<C: CoefficientSystem + ?Sized>(
        &mut self,
        coefficients: &C,
        t: f64,
    ) -> Result<DMatrix<f64>, Failure> {
        let n = coefficients.dim();
        let zero = vec![0.0; n];
        let mut a = DMatrix::zeros(n, n);
        coefficients.jacobian(t, &zero, &mut a)?;
        let mut g = vec![0.0; n];
        coefficients.rhs(t, &zero, &mut g)?;
        self.stats.rhs_evaluations += 1;
        self.stats.jacobian_evaluations += 1;
        let mut augmented = DMatrix::zeros(n + 1, n + 1);
        augmented.view_mut((0, 0), (n, n)).copy_from(&a);
        for (i, value) in g.iter().enumerate() {
            augmented[(i, n)] = *value;
        }
        Ok(augmented)
    }

    /// `exp(Ω)` for the step `[t, t + h]`.
    fn propagator<C: CoefficientSystem + ?Sized>(
        &mut self,
        coefficients: &C,
        t: f64,
        h: f64,
    ) -> Result<DMatrix<f64>, Failure> {
        let mid = t + 0.5 * h;
        let first = self.augmented(coefficients, mid - GAUSS_OFFSET * h)?;
        let second = self.augmented(coefficients, mid + GAUSS_OFFSET * h)?;
        let commutator = &second * &first - &first * &second;
        let omega = (&first + &second) * (0.5 * h) + commutator * (COMMUTATOR_WEIGHT * h * h);
        self.stats.matrix_exponentials += 1;
        if omega.iter().any(|v| !v.is_finite()) {
            return Ok(omega);
        }
        Ok(omega.exp())
    }

    /// Applies `exp(Ω)` to the augmented state `y = (f, S)`.
    fn apply(propagator: &DMatrix<f64>, y: &[f64], out: &mut [f64]) {
        let n = propagator.nrows() - 1;
        for i in 0..n {
            out[i] = propagator[(i, n)] + (0..n).map(|k| propagator[(i, k)] * y[k]).sum::<f64>();
        }
        for j in 0..n {
            let column = &y[n + j * n..n + (j + 1) * n];
            for i in 0..n {
                out[n + j * n + i] = (0..n).map(|k| propagator[(i, k)] * column[k]).sum::<f64>();
            }
        }
    }

    /// `‖Φ‖∞` of the propagator's upper-left block.
    fn growth(propagator: &DMatrix<f64>) -> f64 {
        let n = propagator.nrows() - 1;
        (0..n)
            .map(|i| (0..n).map(|k| propagator[(i, k)].abs()).sum::<f64>())
            .fold(0.0, f64::max)
    }

    /// Takes one accepted step that does not pass `t_limit`.
    pub fn step<C: CoefficientSystem + ?Sized>(
        &mut self,
        coefficients: &C,
        t_limit: f64,
    ) -> Result<(), Failure> {
        let size = self.y.len();
        let (mut full, mut half, mut twice) = (vec![0.0; size], vec![0.0; size], vec![0.0; size]);
        let mut last_rejected = false;
        loop {
            let (h, reaches_limit) = step_toward(self.t, self.h, t_limit);
            if underflows(self.t, h) && !reaches_limit {
                return Err(underflow_failure(self.t, h));
            }
            let whole = self.propagator(coefficients, self.t, h)?;
            let growth = Self::growth(&whole);
            if !growth.is_finite() || growth > self.growth_per_step {
                // Too much growth for one step: shorten so that the
                // predicted growth `growth^{h'/h}` is within the budget.
                self.stats.rejected_steps += 1;
                let shrink = if growth.is_finite() && growth > 1.0 {
                    (0.9 * self.growth_per_step.ln() / growth.ln()).clamp(0.01, 0.9)
                } else {
                    0.1
                };
                self.h = h * shrink;
                last_rejected = true;
                continue;
            }
            Self::apply(&whole, &self.y, &mut full);
            let first = self.propagator(coefficients, self.t, 0.5 * h)?;
            Self::apply(&first, &self.y, &mut half);
            let second = self.propagator(coefficients, self.t + 0.5 * h, 0.5 * h)?;
            Self::apply(&second, &half, &mut twice);
            let difference: Vec<f64> = twice.iter().zip(&full).map(|(a, b)| a - b).collect();
            let error = rms_norm(&difference, &self.y, &twice, self.tol) / 15.0;
            if !error.is_finite() || first_non_finite(&twice).is_some() {
                self.stats.rejected_steps += 1;
                self.h = h * 0.25;
                last_rejected = true;
                continue;
            }
            let scale = if error == 0.0 {
                MAX_SCALE
            } else {
                (SAFETY * error.powf(-0.2)).clamp(MIN_SCALE, MAX_SCALE)
            };
            if error > 1.0 {
                self.stats.rejected_steps += 1;
                self.h = h * scale;
                last_rejected = true;
                continue;
            }
            for (value, d) in twice.iter_mut().zip(&difference) {
                *value += d / 15.0;
            }
            std::mem::swap(&mut self.y, &mut twice);
            self.t = if reaches_limit { t_limit } else { self.t + h };
            // Never plan a step that would grow past the budget.
            let growth_cap = if growth > 1.0 {
                h * (0.9 * self.growth_per_step.ln() / growth.ln())
            } else {
                f64::INFINITY
            };
            let h_next = if last_rejected {
                h * scale.min(1.0)
            } else {
                h * scale
            };
            let h_next = h_next.min(growth_cap.max(h * MIN_SCALE));
            self.h = if reaches_limit {
                h_next.max(self.h.min(growth_cap))
            } else {
                h_next
            };
            self.stats.accepted_steps += 1;
            return Ok(());
        }
    }
}
