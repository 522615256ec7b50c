//! Solving for the highest derivatives `z = q^(u)` of a reduced system
//! given implicitly by `G(t, x, z) = 0` (SPEC §1.4): one LU solve when `G`
//! is affine in `z` (the mass matrix `G_z`), Newton with the exact `G_z`
//! otherwise; and the exact Jacobians of `z(t, x)` by implicit
//! differentiation, `∂z/∂x = −G_z⁻¹ G_x`, `∂z/∂t = −G_z⁻¹ G_t`, with the
//! same factors.

use crate::failure::{Failure, FailureKind};
use crate::linalg::{condition_estimate, Lu, Matrix};

pub mod fixed;
pub use fixed::{solve_linear_fixed, MassLu};

/// A mass matrix whose pivots fall below this fraction of the largest is
/// treated as singular: beyond it the accelerations carry no digits.
const SINGULAR_PIVOT_RATIO: f64 = 1e-14;

/// `z` from `G_z z = −g` (a residual affine in `z`: `G = G_z z + g`), with
/// the factors of `G_z` for the Jacobians. A singular mass matrix stops the
/// run.
pub fn solve_linear(t: f64, mass: Matrix, free: &[f64]) -> Result<(Vec<f64>, Lu), Failure> {
    let lu = Lu::in_place(mass);
    check_pivots(t, lu.is_singular(), lu.pivot_ratio())?;
    let mut z: Vec<f64> = free.iter().map(|v| -v).collect();
    lu.solve_in_place(&mut z);
    check_finite(t, &z)?;
    Ok((z, lu))
}

/// A factored mass matrix that is singular, or whose pivots spread past
/// [`SINGULAR_PIVOT_RATIO`], stops the run, its condition the inverse
/// ratio (shared by the heap and the stack solves, so both name it alike).
fn check_pivots(t: f64, singular: bool, pivot_ratio: f64) -> Result<(), Failure> {
    if singular || pivot_ratio < SINGULAR_PIVOT_RATIO {
        let condition = if singular {
            f64::INFINITY
        } else {
            1.0 / pivot_ratio
        };
        return Err(Failure::new(
            t,
            FailureKind::SingularMassMatrix { condition },
        ));
    }
    Ok(())
}

/// Accelerations that are not finite come from a mass matrix singular in
/// all but its pivots.
fn check_finite(t: f64, z: &[f64]) -> Result<(), Failure> {
    if z.iter().any(|v| !v.is_finite()) {
        return Err(Failure::new(
            t,
            FailureKind::SingularMassMatrix {
                condition: f64::INFINITY,
            },
        ));
    }
    Ok(())
}

/// `z` from `A z = −g` for a fixed-size mass matrix on the stack (the
/// right side's hot path); a singular or nearly singular `A` stops the run.
pub fn solve_fixed_checked<const N: usize>(
    t: f64,
    a: [[f64; N]; N],
    g: [f64; N],
) -> Result<[f64; N], Failure> {
    // The pivots' spread, as `Lu::pivot_ratio` measures it, from the
    // diagonal after elimination: `solve_fixed` fails only on an exact zero.
    let scale = a.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
    let minus_g = g.map(|v| -v);
    match crate::linalg::solve_fixed(a, minus_g) {
        Some(z) if scale > 0.0 => {
            // Residual check of conditioning: a tiny pivot shows as a huge z
            // relative to the data.
            let size = z.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let data = g.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            if size * scale * SINGULAR_PIVOT_RATIO > data.max(f64::MIN_POSITIVE) * 1e2 {
                let condition = size * scale / data.max(f64::MIN_POSITIVE);
                return Err(Failure::new(
                    t,
                    FailureKind::SingularMassMatrix { condition },
                ));
            }
            Ok(z)
        }
        _ => Err(Failure::new(
            t,
            FailureKind::SingularMassMatrix {
                condition: f64::INFINITY,
            },
        )),
    }
}

/// An `L D Lᵀ` solve whose pivots spread more than this is handed to
/// [`solve_fixed_checked`], which decides whether the matrix is singular.
const LDLT_PIVOT_RATIO: f64 = 1e-10;

/// [`solve_fixed_checked`] for a symmetric mass matrix (a Lagrangian's,
/// positive definite): `L D Lᵀ` (Cholesky without square roots), and the
/// LU path when that fails or its pivots spread too far (a singular or
/// indefinite matrix then stops the run exactly as there).
pub fn solve_symmetric_fixed_checked<const N: usize>(
    t: f64,
    a: [[f64; N]; N],
    g: [f64; N],
) -> Result<[f64; N], Failure> {
    match crate::linalg::ldlt_fixed(a, g.map(|v| -v)) {
        Some((z, ratio)) if ratio >= LDLT_PIVOT_RATIO => Ok(z),
        _ => solve_fixed_checked(t, a, g),
    }
}

/// Newton's method on `G(z) = 0` from `z`: `residual(z, g, g_z)` writes `G`
/// and `G_z` (zeroed). Returns `z` and the factors of `G_z` at it.
///
/// A step that leaves the equations' domain (a residual or a `z` not
/// finite: `x''/√(A² − x''²)` past `|x''| = A`) is halved until it stays
/// inside: from `z = 0` the first full step of `k x − m g x''/√(A² −
/// x''²) = 0` lands on the boundary exactly where `k x ≥ m g`, and the run
/// stopped there although the root is regular.
pub fn newton(
    t: f64,
    mut z: Vec<f64>,
    mut residual: impl FnMut(&[f64], &mut [f64], &mut Matrix) -> Result<(), Failure>,
) -> Result<(Vec<f64>, Lu), Failure> {
    const MAX_ITERATIONS: usize = 50;
    /// Halvings of one step before the domain is given up.
    const MAX_HALVINGS: usize = 30;
    let m = z.len();
    let mut g = vec![0.0; m];
    let mut g_z = Matrix::zeros(m, m);
    let mut norm = f64::INFINITY;
    let mut trial = z.clone();
    // Whether `g`, `g_z` hold the residual at `z` (after an accepted step).
    let mut evaluated = false;
    let fails = |norm: f64, iterations: usize| {
        Failure::new(
            t,
            FailureKind::NewtonNonConvergence {
                residual: norm,
                iterations,
            },
        )
    };
    for iteration in 0..MAX_ITERATIONS {
        if !evaluated {
            g_z.fill(0.0);
            residual(&z, &mut g, &mut g_z)?;
        }
        norm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
        let lu = Lu::new(&g_z);
        if lu.is_singular() {
            // A singular Jacobian at the start point says nothing about a
            // root: step aside once before giving up.
            if iteration == 0 {
                z.iter_mut().for_each(|v| *v += 1e-3 * v.abs().max(1.0));
                evaluated = false;
                continue;
            }
            return Err(fails(norm, iteration));
        }
        let mut step: Vec<f64> = g.iter().map(|v| -v).collect();
        lu.solve_in_place(&mut step);
        let step_norm = step.iter().map(|v| v * v).sum::<f64>().sqrt();
        let z_norm = z.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !step_norm.is_finite() {
            return Err(fails(norm, iteration));
        }
        let mut fraction = 1.0;
        let mut halvings = 0;
        loop {
            for ((zt, zi), s) in trial.iter_mut().zip(&z).zip(&step) {
                *zt = zi + fraction * s;
            }
            g_z.fill(0.0);
            let inside = trial.iter().all(|v| v.is_finite())
                && residual(&trial, &mut g, &mut g_z).is_ok()
                && g.iter().all(|v| v.is_finite());
            if inside {
                break;
            }
            halvings += 1;
            if halvings > MAX_HALVINGS {
                return Err(fails(norm, iteration + 1));
            }
            fraction *= 0.5;
        }
        std::mem::swap(&mut z, &mut trial);
        evaluated = true;
        // Quadratic convergence: after a full step of 1e-12 (relative)
        // the error left is at rounding level.
        if halvings == 0 && step_norm <= 1e-12 * z_norm.max(1.0) {
            return Ok((z, Lu::new(&g_z)));
        }
    }
    Err(fails(norm, MAX_ITERATIONS))
}

/// `out = −G_z⁻¹ · partials` column by column (`partials` is `m × k`): the
/// derivatives of the implicitly defined `z`.
pub fn implicit_derivatives(lu: &Lu, partials: &mut Matrix) {
    if partials.rows() == lu.dim() {
        // All columns in one call, then negated: each column's solve and
        // sign as below, the columns being independent (the field
        // linearises a mass-matrix model at every stage: a triple
        // pendulum's six columns cost about 870 instructions a call one
        // by one).
        let data = partials.as_mut_slice();
        lu.solve_columns_in_place(data);
        data.iter_mut().for_each(|v| *v = -*v);
        return;
    }
    for j in 0..partials.cols() {
        let column = partials.column_mut(j);
        lu.solve_in_place(column);
        column.iter_mut().for_each(|v| *v = -*v);
    }
}

/// The condition number of a mass matrix (for naming a singular mass
/// matrix as the cause of a failure; not for every evaluation).
pub fn mass_condition(mass: &Matrix) -> f64 {
    let lu = Lu::new(mass);
    condition_estimate(mass, &lu)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newton_and_the_implicit_jacobian_match_a_closed_form() {
        // G(z) = z³ + z − x = 0 at x = 10: z = 2; dz/dx = 1/(3z² + 1) = 1/13.
        let x = 10.0;
        let (z, lu) = newton(0.0, vec![0.0], |z, g, g_z| {
            g[0] = z[0].powi(3) + z[0] - x;
            g_z[(0, 0)] = 3.0 * z[0] * z[0] + 1.0;
            Ok(())
        })
        .unwrap();
        assert!((z[0] - 2.0).abs() < 1e-14);
        let mut g_x = Matrix::from_rows(&[&[-1.0]]);
        implicit_derivatives(&lu, &mut g_x);
        assert!((g_x[(0, 0)] - 1.0 / 13.0).abs() < 1e-15);
    }

    /// All columns at once are each column's solve and sign, to the bit,
    /// at every size the solves are unrolled for and beyond; a singular
    /// matrix leaves the partials negated only, as before.
    #[test]
    fn implicit_derivatives_are_the_column_by_column_solves() {
        for m in 1..=7 {
            for singular in [false, true] {
                let mut g_z = Matrix::zeros(m, m);
                for c in 0..m {
                    for r in 0..m {
                        g_z[(r, c)] = if singular && c == 0 {
                            0.0
                        } else {
                            ((r * 7 + c * 3) as f64 * 0.61).sin() + if r == c { 2.5 } else { 0.0 }
                        };
                    }
                }
                let lu = Lu::new(&g_z);
                let k = 2 * m + 1;
                let mut partials = Matrix::zeros(m, k);
                for c in 0..k {
                    for r in 0..m {
                        partials[(r, c)] = ((r * 5 + c * 11) as f64 * 0.37).cos();
                    }
                }
                let mut expected = partials.clone();
                for j in 0..k {
                    let column = expected.column_mut(j);
                    lu.solve_in_place(column);
                    column.iter_mut().for_each(|v| *v = -*v);
                }
                implicit_derivatives(&lu, &mut partials);
                let bits =
                    |a: &Matrix| a.as_slice().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(
                    bits(&partials),
                    bits(&expected),
                    "m = {m}, singular {singular}"
                );
            }
        }
    }

    #[test]
    fn a_step_out_of_the_domain_is_halved() {
        // G(z) = k − z/√(A² − z²) with k = 2, A = 1.5: z = A k/√(1 + k²).
        // From 0 the full step is z = A k = 3, outside |z| < A.
        let (k, a) = (2.0_f64, 1.5_f64);
        let (z, _) = newton(0.0, vec![0.0], |z, g, g_z| {
            let r = (a * a - z[0] * z[0]).sqrt();
            g[0] = k - z[0] / r;
            g_z[(0, 0)] = -a * a / (r * r * r);
            Ok(())
        })
        .unwrap();
        let exact = a * k / (1.0 + k * k).sqrt();
        assert!((z[0] - exact).abs() < 1e-14, "{} against {exact}", z[0]);
    }

    #[test]
    fn a_singular_mass_matrix_is_a_failure_naming_it() {
        let mass = Matrix::from_rows(&[&[1.0, 2.0], &[2.0, 4.0]]);
        let failure = solve_linear(1.5, mass, &[1.0, 1.0]).unwrap_err();
        assert!(matches!(
            failure.kind,
            FailureKind::SingularMassMatrix { .. }
        ));
        assert_eq!(failure.time, 1.5);
    }
}
