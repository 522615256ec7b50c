//! The conditioned solution (the paper's (11)–(13), done numerically):
//! from the coefficients `f(t)`, their sensitivities `S = ∂f/∂c` and the
//! anchor state `x0`, the conditions `∂Φ̄/∂c_A = 0` (with `c_1` eliminated
//! by (12)) are `N−1` linear equations for `x_2..x_N`:
//!
//! `Σ_B (S_BA − S_B1 x_A0) x_B = −(S_1A − S_11 x_A0)`,  A, B = 2..N,
//!
//! and then `x_1 = f_1 + Σ_A f_A x_A`.

use super::error::{Failure, FailureKind};
use nalgebra::{DMatrix, DMatrixView, DVector};

/// The state recovered from the field, and how trustworthy it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Conditioned {
    pub state: Vec<f64>,
    /// 2-norm condition number of the condition matrix (1 when `N = 1`).
    pub condition: f64,
    /// `max |S_ij|`: how far the sensitivities grew since the anchor
    /// (`S = I` there); large values mean the field is near a blow-up.
    pub growth: f64,
}

/// Solves the conditions at time `t` (for failure messages).
pub fn solve_conditions(
    t: f64,
    f: &[f64],
    s: DMatrixView<'_, f64>,
    x_anchor: &[f64],
) -> Result<Conditioned, Failure> {
    let n = f.len();
    let growth = s.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let singular =
        |condition: f64| Failure::new(t, FailureKind::SingularConditionMatrix { condition });
    if n == 1 {
        return Ok(Conditioned {
            state: vec![f[0]],
            condition: 1.0,
            growth,
        });
    }
    let m = n - 1;
    let matrix = DMatrix::from_fn(m, m, |row, col| {
        let (a, b) = (row + 1, col + 1);
        s[(b, a)] - s[(b, 0)] * x_anchor[a]
    });
    let right = DVector::from_fn(m, |row, _| {
        let a = row + 1;
        -(s[(0, a)] - s[(0, 0)] * x_anchor[a])
    });
    if matrix.iter().chain(right.iter()).any(|v| !v.is_finite()) {
        return Err(singular(f64::INFINITY));
    }
    let singular_values = matrix.clone().singular_values();
    let largest = singular_values.max();
    let smallest = singular_values.min();
    let condition = if smallest > 0.0 {
        largest / smallest
    } else {
        f64::INFINITY
    };
    let solution = matrix
        .lu()
        .solve(&right)
        .ok_or_else(|| singular(condition))?;
    let mut state = Vec::with_capacity(n);
    let x1 = f[0] + (1..n).map(|a| f[a] * solution[a - 1]).sum::<f64>();
    state.push(x1);
    state.extend(solution.iter());
    if state.iter().any(|v| !v.is_finite()) {
        return Err(singular(condition));
    }
    Ok(Conditioned {
        state,
        condition,
        growth,
    })
}
