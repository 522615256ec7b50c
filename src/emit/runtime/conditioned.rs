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
    /// 1-norm condition number `‖M‖₁‖M⁻¹‖₁` of the condition matrix `M`
    /// (1 when `N = 1`); within a factor `N − 1` of the 2-norm one.
    pub condition: f64,
    /// `det M` (1 when `N = 1`, and at every anchor, where `M = I`): a
    /// change of its sign between two steps means `M` passed through
    /// singularity in between, where no step looked.
    pub determinant: f64,
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
            determinant: 1.0,
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
    // One LU gives the solution, the determinant and the exact inverse for
    // the 1-norm condition number: for the sizes of mechanics (N − 1 ≲ 20)
    // that costs a few `m³` flops, against the iterative SVD that made the
    // condition number the most expensive part of a field step.
    let norm = one_norm(&matrix);
    let lu = matrix.lu();
    let determinant = lu.determinant();
    let condition = match lu.try_inverse() {
        Some(inverse) if determinant != 0.0 => norm * one_norm(&inverse),
        _ => f64::INFINITY,
    };
    let condition = if condition.is_finite() {
        condition
    } else {
        f64::INFINITY
    };
    let solution = lu.solve(&right).ok_or_else(|| singular(condition))?;
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
        determinant,
        growth,
    })
}

/// The largest column sum of absolute values.
fn one_norm(matrix: &DMatrix<f64>) -> f64 {
    matrix
        .column_iter()
        .map(|column| column.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}
