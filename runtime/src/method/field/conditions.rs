//! The conditioned solution (the paper's (11)–(13), done numerically):
//! from the coefficients `f(t)`, their sensitivities `S = ∂f/∂c` and the
//! anchor state `x0`, the conditions `∂Φ̄/∂c_A = 0` (with `c_1` eliminated
//! by (12)) are `N−1` linear equations for `x_2..x_N` (SPEC §1.5):
//!
//! `Σ_B (S_BA − S_B1 x_A0) x_B = −(S_1A − S_11 x_A0)`,  A, B = 2..N,
//!
//! and then `x_1 = f_1 + Σ_A f_A x_A`. The same factors map an error of
//! `(f, S)` to the error of the recovered state, which is what the field
//! method's step control measures.
//!
//! Layout: `S` is column-major, `s[j·N + i] = S_ij = ∂f_i/∂c_j`.

use crate::linalg::{condition_estimate, Lu, Matrix};

/// The state recovered from a field, and how trustworthy it is.
#[derive(Clone, Debug)]
pub struct Recovered {
    pub state: Vec<f64>,
    /// 1-norm condition number of the condition matrix `M` equilibrated
    /// (rows and columns scaled to a largest entry of about 1; Hager's
    /// estimate; 1 when `N = 1`). Equilibrated, because the raw number
    /// depends on the units of the state's components: a stiff joint's
    /// conditions (a first column of 120 against entries of 1) measured
    /// 4·10⁴ raw and 2.7 equilibrated, and ended every window after one
    /// or two steps.
    pub condition: f64,
    /// `det M` (1 at every anchor, where `M = I`): a sign change between
    /// two steps means `M` passed through singularity in between.
    pub determinant: f64,
    /// `max |S_ij|`: how far the sensitivities grew since the anchor.
    pub growth: f64,
    /// How much rounding the forming of the conditions from `S` amplifies:
    /// their entries `S_BA − S_B1 x_A0` are differences, which cancel when
    /// the field's sensitivities align (the adjoint of a fast decaying
    /// mode), and the condition number of the result cannot see that.
    pub formation: f64,
    /// The factors of `M` (for mapping errors); `None` when `N = 1`.
    lu: Option<EquilibratedLu>,
}

/// The factors of `R M C`, with `R`, `C` diagonal scalings by powers of 2
/// (exact) that bring every row's and column's largest entry near 1
/// (LAPACK's `dgeequb`): `M x = z` is `(R M C)(C⁻¹ x) = R z`.
#[derive(Clone, Debug)]
struct EquilibratedLu {
    lu: Lu,
    rows: Vec<f64>,
    columns: Vec<f64>,
}

impl EquilibratedLu {
    /// Factors `m` equilibrated; its condition number when `estimate`.
    fn new(mut m: Matrix, estimate: bool) -> (EquilibratedLu, f64) {
        let size = m.rows();
        let power_of_two = |largest: f64| {
            if largest > 0.0 && largest.is_finite() {
                (-largest.log2().round()).exp2()
            } else {
                1.0
            }
        };
        let rows: Vec<f64> = (0..size)
            .map(|r| power_of_two((0..size).fold(0.0_f64, |a, c| a.max(m[(r, c)].abs()))))
            .collect();
        let columns: Vec<f64> = (0..size)
            .map(|c| {
                power_of_two((0..size).fold(0.0_f64, |a, r| a.max((rows[r] * m[(r, c)]).abs())))
            })
            .collect();
        for c in 0..size {
            for r in 0..size {
                m[(r, c)] *= rows[r] * columns[c];
            }
        }
        let lu = Lu::new(&m);
        let condition = if estimate && !lu.is_singular() {
            condition_estimate(&m, &lu)
        } else {
            1.0
        };
        (EquilibratedLu { lu, rows, columns }, condition)
    }

    /// `det M`: `det(R M C)` over the scalings' (exact) product.
    fn determinant(&self) -> f64 {
        let scalings: f64 = self.rows.iter().chain(&self.columns).product();
        if scalings.is_normal() {
            self.lu.determinant() / scalings
        } else {
            // Out of range: the sign, which is what the windows use, is
            // still that of det(R M C).
            self.lu.determinant()
        }
    }

    fn solve_in_place(&self, z: &mut [f64]) {
        for (v, r) in z.iter_mut().zip(&self.rows) {
            *v *= r;
        }
        self.lu.solve_in_place(z);
        for (v, c) in z.iter_mut().zip(&self.columns) {
            *v *= c;
        }
    }
}

/// The condition matrix `M` at `(S, x0)`.
fn condition_matrix(s: &[f64], n: usize, x0: &[f64]) -> Matrix {
    let m = n - 1;
    let mut matrix = Matrix::zeros(m, m);
    for col in 0..m {
        let b = col + 1;
        for row in 0..m {
            let a = row + 1;
            // S_BA − S_B1 x_A0: column A of S holds ∂f/∂c_A.
            matrix[(row, col)] = s[a * n + b] - s[b] * x0[a];
        }
    }
    matrix
}

/// Solves the conditions for the state; `None` when they are singular or
/// the result is not finite.
pub fn recover(f: &[f64], s: &[f64], x0: &[f64]) -> Option<Recovered> {
    solve_conditions(f, s, x0, true)
}

/// The state alone, for output between steps whose conditions were
/// checked: no condition estimate (about a third of the solve's cost).
pub fn recover_state(f: &[f64], s: &[f64], x0: &[f64]) -> Option<Vec<f64>> {
    solve_conditions(f, s, x0, false).map(|recovered| recovered.state)
}

/// [`recover`], with the condition estimate only when `estimate` (else
/// `condition` is 1).
fn solve_conditions(f: &[f64], s: &[f64], x0: &[f64], estimate: bool) -> Option<Recovered> {
    let n = f.len();
    let growth = s.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if !growth.is_finite() || f.iter().any(|v| !v.is_finite()) {
        return None;
    }
    if n == 1 {
        return Some(Recovered {
            state: vec![f[0]],
            condition: 1.0,
            determinant: 1.0,
            growth,
            formation: 1.0,
            lu: None,
        });
    }
    let m = n - 1;
    let matrix = condition_matrix(s, n, x0);
    let mut z: Vec<f64> = (0..m)
        .map(|row| {
            let a = row + 1;
            -(s[a * n] - s[0] * x0[a])
        })
        .collect();
    // Magnitudes of the terms of each entry against the entries.
    let (mut terms, mut entries) = (0.0_f64, 0.0_f64);
    for col in 0..m {
        let b = col + 1;
        for row in 0..m {
            let a = row + 1;
            terms = terms.max(s[a * n + b].abs() + (s[b] * x0[a]).abs());
            entries = entries.max(matrix[(row, col)].abs());
        }
    }
    for (row, &value) in z.iter().enumerate() {
        let a = row + 1;
        terms = terms.max(s[a * n].abs() + (s[0] * x0[a]).abs());
        entries = entries.max(value.abs());
    }
    let formation = if entries > 0.0 {
        (terms / entries).max(1.0)
    } else {
        f64::INFINITY
    };
    let (lu, condition) = EquilibratedLu::new(matrix, estimate);
    if lu.lu.is_singular() {
        return None;
    }
    let determinant = lu.determinant();
    lu.solve_in_place(&mut z);
    let mut state = Vec::with_capacity(n);
    state.push(f[0] + (1..n).map(|a| f[a] * z[a - 1]).sum::<f64>());
    state.extend_from_slice(&z);
    if state.iter().any(|v| !v.is_finite()) || !condition.is_finite() {
        return None;
    }
    Some(Recovered {
        state,
        condition,
        determinant,
        growth,
        formation,
        lu: Some(lu),
    })
}

impl Recovered {
    /// The state of another initial state (an ensemble member) through the
    /// same field: its coefficients `f` and sensitivities `S` differ from
    /// these only in the free term's (its `c_1` differs), so the condition
    /// matrix and its factors are shared (SPEC §1.5's `S_B1 = 0` for
    /// `B ≥ 2`): one `O(N²)` solve per member.
    pub fn member(&self, f: &[f64], s: &[f64], x0: &[f64]) -> Vec<f64> {
        let n = f.len();
        let Some(lu) = &self.lu else {
            return vec![f[0]];
        };
        let mut z: Vec<f64> = (1..n).map(|a| -(s[a * n] - s[0] * x0[a])).collect();
        lu.solve_in_place(&mut z);
        let mut state = Vec::with_capacity(n);
        state.push(f[0] + (1..n).map(|a| f[a] * z[a - 1]).sum::<f64>());
        state.extend_from_slice(&z);
        state
    }

    /// The first-order change of the recovered state when `(f, S)` change
    /// by `(df, ds)` (same layouts), into `dx`.
    pub fn map_error(&self, f: &[f64], x0: &[f64], df: &[f64], ds: &[f64], dx: &mut [f64]) {
        let n = f.len();
        let Some(lu) = &self.lu else {
            dx[0] = df[0];
            return;
        };
        let z = &self.state[1..];
        // δz = M⁻¹ (δr − δM z), δr_A = −(δS_1A − δS_11 x_A0),
        // (δM z)_A = Σ_B (δS_BA − δS_B1 x_A0) z_B.
        let mut dz: Vec<f64> = (1..n)
            .map(|a| {
                let dr = -(ds[a * n] - ds[0] * x0[a]);
                let dm_z: f64 = (1..n)
                    .map(|b| (ds[a * n + b] - ds[b] * x0[a]) * z[b - 1])
                    .sum();
                dr - dm_z
            })
            .collect();
        lu.solve_in_place(&mut dz);
        dx[0] = df[0]
            + (1..n)
                .map(|a| df[a] * z[a - 1] + f[a] * dz[a - 1])
                .sum::<f64>();
        dx[1..n].copy_from_slice(&dz);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The field of `x' = a x` (constant a) from the anchor: the recovered
    /// state must be `exp(a t) x0` for every anchor, and the mapped error
    /// must match a finite difference of `recover`.
    #[test]
    fn recovery_and_error_map_agree_with_finite_differences() {
        // Random-ish f, S, x0 with a well-conditioned M.
        let n = 3;
        let f = [0.3, -0.7, 1.1];
        let s = [1.2, 0.1, -0.3, 0.2, 0.9, 0.4, -0.1, 0.3, 1.3];
        let x0 = [0.5, -1.0, 2.0];
        let base = recover(&f, &s, &x0).unwrap();
        let df = [1e-7, -2e-7, 3e-7];
        let ds = [
            2e-7, -1e-7, 0.5e-7, 1e-7, 3e-7, -2e-7, 0.7e-7, -0.4e-7, 1e-7,
        ];
        let mut dx = [0.0; 3];
        base.map_error(&f, &x0, &df, &ds, &mut dx);
        let f2: Vec<f64> = f.iter().zip(&df).map(|(a, b)| a + b).collect();
        let s2: Vec<f64> = s.iter().zip(&ds).map(|(a, b)| a + b).collect();
        let moved = recover(&f2, &s2, &x0).unwrap();
        for i in 0..n {
            let fd = moved.state[i] - base.state[i];
            assert!((fd - dx[i]).abs() < 1e-12, "{i}: {fd} vs {}", dx[i]);
        }
    }
}
