//! The factored solve of a mass matrix of a size known at compile time,
//! on the stack: what [`super::solve_linear`] and
//! [`super::implicit_derivatives`] compute — the same operations in the
//! same order as [`crate::linalg::Lu`]'s (partial pivoting, column-major
//! factors), so the same bits — without their four allocations (the
//! matrix, its pivots, `z`, `G_x`). The field linearises a mass-matrix
//! model at every stage of every step (a triple pendulum: 34,000 times a
//! run at rtol 1e-9), and the allocations were a quarter of it.

use super::{check_finite, check_pivots};
use crate::failure::Failure;

/// `PA = LU` of an `M × M` matrix, `factors[j][i]` the entry of row `i`,
/// column `j` (as [`crate::linalg::Lu`] holds them).
#[derive(Clone, Copy, Debug)]
pub struct MassLu<const M: usize> {
    factors: [[f64; M]; M],
    pivots: [usize; M],
    singular: bool,
}

impl<const M: usize> MassLu<M> {
    /// Factors `a` (rows `a[i]`): `Lu::factor`'s loops.
    pub fn new(a: &[[f64; M]; M]) -> MassLu<M> {
        let mut f = [[0.0; M]; M];
        for (i, row) in a.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                f[j][i] = v;
            }
        }
        let mut pivots = [0; M];
        let mut singular = false;
        for k in 0..M {
            let (p, largest) = (k..M)
                .map(|i| (i, f[k][i].abs()))
                .fold((k, -1.0), |best, c| if c.1 > best.1 { c } else { best });
            pivots[k] = p;
            if p != k {
                for column in f.iter_mut() {
                    column.swap(k, p);
                }
            }
            if largest == 0.0 || !largest.is_finite() {
                singular = true;
                continue;
            }
            let pivot = f[k][k];
            for i in k + 1..M {
                f[k][i] /= pivot;
            }
            for j in k + 1..M {
                let u = f[j][k];
                if u == 0.0 {
                    continue;
                }
                for i in k + 1..M {
                    let l = f[k][i];
                    f[j][i] -= l * u;
                }
            }
        }
        MassLu {
            factors: f,
            pivots,
            singular,
        }
    }

    /// An exactly zero (or non-finite) pivot was met.
    pub fn is_singular(&self) -> bool {
        self.singular
    }

    /// `Lu::pivot_ratio`: the smallest over the largest absolute pivot.
    pub fn pivot_ratio(&self) -> f64 {
        if M == 0 {
            return 1.0;
        }
        let (mut small, mut large) = (f64::INFINITY, 0.0_f64);
        for k in 0..M {
            let u = self.factors[k][k].abs();
            small = small.min(u);
            large = large.max(u);
        }
        if large > 0.0 {
            small / large
        } else {
            0.0
        }
    }

    /// `Lu::solve_in_place` of regular factors (`b ← A⁻¹ b`).
    fn solve(&self, b: &mut [f64; M]) {
        let f = &self.factors;
        for k in 0..M {
            b.swap(k, self.pivots[k]);
        }
        for j in 0..M {
            let bj = b[j];
            if bj != 0.0 {
                for i in j + 1..M {
                    b[i] -= f[j][i] * bj;
                }
            }
        }
        for j in (0..M).rev() {
            b[j] /= f[j][j];
            let bj = b[j];
            if bj != 0.0 {
                for i in 0..j {
                    b[i] -= f[j][i] * bj;
                }
            }
        }
    }

    /// [`super::implicit_derivatives`] of the columns `partials[c]`:
    /// `−G_z⁻¹` times each (only negated when the factors are singular, as
    /// there).
    pub fn implicit_derivatives<const K: usize>(&self, partials: &mut [[f64; M]; K]) {
        for column in partials.iter_mut() {
            if !self.singular {
                self.solve(column);
            }
            column.iter_mut().for_each(|v| *v = -*v);
        }
    }
}

/// [`super::solve_linear`] on the stack: `z` from `a z = −g` with the
/// factors of `a`; the same failures (a singular or nearly singular mass
/// matrix, a `z` not finite) with the same conditions.
pub fn solve_linear_fixed<const M: usize>(
    t: f64,
    a: &[[f64; M]; M],
    free: &[f64; M],
) -> Result<([f64; M], MassLu<M>), Failure> {
    let lu = MassLu::new(a);
    check_pivots(t, lu.is_singular(), lu.pivot_ratio())?;
    let mut z = free.map(|v| -v);
    lu.solve(&mut z);
    check_finite(t, &z)?;
    Ok((z, lu))
}

#[cfg(test)]
mod tests {
    use super::super::{implicit_derivatives, solve_linear};
    use super::*;
    use crate::linalg::Matrix;

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|v| v.to_bits()).collect()
    }

    /// Matrices that pivot, one with an exact zero where a pivot would
    /// be, one nearly singular, one singular: `z`, the failures and the
    /// implicit derivatives bit for bit the heap path's.
    fn same_as_the_heap_path<const M: usize, const K: usize>() {
        let (mut solved, mut failed) = (0, 0);
        for case in 0..5 {
            let mut a = [[0.0; M]; M];
            for (r, row) in a.iter_mut().enumerate() {
                for (c, v) in row.iter_mut().enumerate() {
                    *v = ((r * 7 + c * 3 + case) as f64 * 0.61).sin()
                        + if r == c && case != 1 { 0.3 } else { 0.0 };
                }
            }
            match case {
                2 => a[0][0] = 0.0,
                3 if M > 1 => a[M - 1] = a[0].map(|v| v * (1.0 + 1e-15)),
                4 if M > 1 => a[M - 1] = a[0],
                _ => {}
            }
            let g: [f64; M] = std::array::from_fn(|r| ((r * 5 + case) as f64 * 0.37).cos());
            let heap = solve_linear(0.5, Matrix::from_array(&a), &g);
            let stack = solve_linear_fixed(0.5, &a, &g);
            match (heap, stack) {
                (Ok((z, lu)), Ok((zs, lus))) => {
                    solved += 1;
                    assert_eq!(bits(&z), bits(&zs), "M = {M}, case {case}");
                    let mut partials = Matrix::zeros(M, K);
                    let mut columns = [[0.0; M]; K];
                    for (c, column) in columns.iter_mut().enumerate() {
                        for (r, v) in column.iter_mut().enumerate() {
                            *v = ((r * 11 + c * 5 + case) as f64 * 0.29).sin();
                            partials[(r, c)] = *v;
                        }
                    }
                    implicit_derivatives(&lu, &mut partials);
                    lus.implicit_derivatives(&mut columns);
                    assert_eq!(
                        bits(partials.as_slice()),
                        bits(columns.as_flattened()),
                        "M = {M}, case {case}"
                    );
                }
                (Err(e), Err(es)) => {
                    failed += 1;
                    assert_eq!(format!("{e:?}"), format!("{es:?}"), "M = {M}, case {case}");
                }
                (h, s) => panic!(
                    "M = {M}, case {case}: heap {:?}, stack {:?}",
                    h.map(|r| r.0),
                    s.map(|r| r.0)
                ),
            }
        }
        // Both outcomes compared (one unknown cannot be made singular
        // by a repeated row).
        assert!(solved > 0 && (failed > 0 || M == 1), "M = {M}");
    }

    #[test]
    fn the_stack_solve_is_the_heap_solve_bit_for_bit() {
        same_as_the_heap_path::<1, 2>();
        same_as_the_heap_path::<2, 4>();
        same_as_the_heap_path::<3, 6>();
        same_as_the_heap_path::<4, 8>();
        same_as_the_heap_path::<5, 10>();
        same_as_the_heap_path::<7, 14>();
    }
}
