//! The dense linear algebra the methods need, for the small matrices of
//! mechanics (a few to a few dozen rows): a column-major [`Matrix`], LU
//! with partial pivoting (solve, determinant, a cheap condition estimate),
//! `L D Lᵀ` (Cholesky without square roots) for symmetric positive definite
//! mass matrices, fixed-size
//! solves on the stack for generated code, products and the matrix
//! exponential.

use std::ops::{Index, IndexMut};

/// A dense column-major matrix: entry `(i, j)` is `data[j * rows + i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Matrix {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

impl Matrix {
    pub fn zeros(rows: usize, cols: usize) -> Matrix {
        Matrix {
            rows,
            cols,
            data: vec![0.0; rows * cols],
        }
    }

    pub fn identity(n: usize) -> Matrix {
        let mut m = Matrix::zeros(n, n);
        for i in 0..n {
            m[(i, i)] = 1.0;
        }
        m
    }

    /// A matrix from its entries, row by row (for tests and small literals).
    pub fn from_rows(rows: &[&[f64]]) -> Matrix {
        let r = rows.len();
        let c = rows.first().map_or(0, |row| row.len());
        let mut m = Matrix::zeros(r, c);
        for (i, row) in rows.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                m[(i, j)] = v;
            }
        }
        m
    }

    /// A matrix from a fixed-size array of rows.
    pub fn from_array<const N: usize>(rows: &[[f64; N]; N]) -> Matrix {
        let mut m = Matrix::zeros(N, N);
        for (i, row) in rows.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                m[(i, j)] = v;
            }
        }
        m
    }

    /// A matrix over column-major `data`.
    pub fn from_column_major(rows: usize, cols: usize, data: Vec<f64>) -> Matrix {
        assert_eq!(data.len(), rows * cols, "matrix data of the wrong length");
        Matrix { rows, cols, data }
    }

    pub fn rows(&self) -> usize {
        self.rows
    }

    pub fn cols(&self) -> usize {
        self.cols
    }

    pub fn as_slice(&self) -> &[f64] {
        &self.data
    }

    pub fn as_mut_slice(&mut self) -> &mut [f64] {
        &mut self.data
    }

    pub fn fill(&mut self, value: f64) {
        self.data.fill(value);
    }

    /// Column `j` as a slice.
    pub fn column(&self, j: usize) -> &[f64] {
        &self.data[j * self.rows..(j + 1) * self.rows]
    }

    pub fn column_mut(&mut self, j: usize) -> &mut [f64] {
        &mut self.data[j * self.rows..(j + 1) * self.rows]
    }

    /// `out = self · x`. Square matrices of the small models' sizes with
    /// their size known at compile time (the field method forms `A x` at
    /// every stage: at N = 4 the general loop's counting and checks were
    /// 210 instructions a product); the same operations in the same
    /// order, so the same bits.
    pub fn mul_vec(&self, x: &[f64], out: &mut [f64]) {
        match (self.rows, self.cols) {
            (2, 2) => return mul_vec_square::<2>(&self.data, x, out),
            (3, 3) => return mul_vec_square::<3>(&self.data, x, out),
            (4, 4) => return mul_vec_square::<4>(&self.data, x, out),
            (6, 6) => return mul_vec_square::<6>(&self.data, x, out),
            _ => {}
        }
        out[..self.rows].fill(0.0);
        for j in 0..self.cols {
            let xj = x[j];
            if xj == 0.0 {
                continue;
            }
            for (o, a) in out.iter_mut().zip(self.column(j)) {
                *o += a * xj;
            }
        }
    }

    /// `out = selfᵀ · x`.
    pub fn mul_transpose_vec(&self, x: &[f64], out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate().take(self.cols) {
            *o = self.column(j).iter().zip(x).map(|(a, b)| a * b).sum();
        }
    }

    /// `out = self · other`.
    pub fn mul_to(&self, other: &Matrix, out: &mut Matrix) {
        debug_assert_eq!(self.cols, other.rows);
        out.fill(0.0);
        for j in 0..other.cols {
            for k in 0..self.cols {
                let b = other[(k, j)];
                if b == 0.0 {
                    continue;
                }
                let column = self.column(k);
                let target = &mut out.data[j * self.rows..(j + 1) * self.rows];
                for (t, a) in target.iter_mut().zip(column) {
                    *t += a * b;
                }
            }
        }
    }

    pub fn mul(&self, other: &Matrix) -> Matrix {
        let mut out = Matrix::zeros(self.rows, other.cols);
        self.mul_to(other, &mut out);
        out
    }

    /// The largest column sum of absolute values.
    pub fn one_norm(&self) -> f64 {
        (0..self.cols)
            .map(|j| self.column(j).iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max)
    }

    /// The largest absolute entry.
    pub fn max_abs(&self) -> f64 {
        self.data.iter().fold(0.0_f64, |m, v| m.max(v.abs()))
    }

    /// Every entry finite: `0·v` is ±0 for a finite `v` and NaN for an
    /// infinite or NaN one, so the sum of them is 0 exactly when all are
    /// (a loop without a branch per entry: the field method checks a
    /// Jacobian at every stage).
    pub fn is_finite(&self) -> bool {
        // The Jacobians of two and three degrees of freedom, checked at
        // every linearisation: the length known, the loop unrolled (about
        // 76 instructions a call for 4 × 4 in the general loop).
        match self.data.len() {
            16 => return all_finite_sized::<16>(&self.data),
            36 => return all_finite_sized::<36>(&self.data),
            _ => {}
        }
        // Four running sums, not one: the same answer in any order (a sum
        // of zeros is zero, and a NaN anywhere makes it NaN), and the
        // additions no longer wait on each other.
        let mut chunks = self.data.chunks_exact(4);
        let mut sums = [0.0_f64; 4];
        for chunk in &mut chunks {
            for (s, v) in sums.iter_mut().zip(chunk) {
                *s += 0.0 * v;
            }
        }
        let rest = chunks.remainder().iter().fold(0.0, |sum, v| sum + 0.0 * v);
        (sums[0] + sums[1]) + (sums[2] + sums[3]) + rest == 0.0
    }
}

/// [`Matrix::is_finite`] of `K` entries (a multiple of 4): the same sums
/// (`0 · v` is 0 exactly for a finite `v`, NaN otherwise), unrolled.
#[inline(always)]
fn all_finite_sized<const K: usize>(data: &[f64]) -> bool {
    let data: &[f64; K] = data.try_into().expect("K entries");
    let mut sums = [0.0_f64; 4];
    for chunk in data.chunks_exact(4) {
        for (s, v) in sums.iter_mut().zip(chunk) {
            *s += 0.0 * v;
        }
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3]) == 0.0
}

/// [`Matrix::mul_vec`] of an `N × N` matrix stored column by column: the
/// general loop's operations (columns in order, a zero `x_j` skipped).
#[inline(always)]
fn mul_vec_square<const N: usize>(data: &[f64], x: &[f64], out: &mut [f64]) {
    let (data, x, out) = (&data[..N * N], &x[..N], &mut out[..N]);
    out.fill(0.0);
    for j in 0..N {
        let xj = x[j];
        if xj == 0.0 {
            continue;
        }
        let column = &data[j * N..(j + 1) * N];
        for i in 0..N {
            out[i] += column[i] * xj;
        }
    }
}

impl Index<(usize, usize)> for Matrix {
    type Output = f64;
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        debug_assert!(i < self.rows && j < self.cols);
        &self.data[j * self.rows + i]
    }
}

impl IndexMut<(usize, usize)> for Matrix {
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut f64 {
        debug_assert!(i < self.rows && j < self.cols);
        &mut self.data[j * self.rows + i]
    }
}

/// `PA = LU` of a square matrix, with partial pivoting.
#[derive(Clone, Debug)]
pub struct Lu {
    factors: Matrix,
    pivots: Vec<usize>,
    /// +1 or −1: the sign of the row permutation.
    sign: f64,
    /// An exactly zero pivot was met (the factors are then incomplete).
    singular: bool,
}

impl Lu {
    /// Factors `a` (a copy).
    pub fn new(a: &Matrix) -> Lu {
        Lu::in_place(a.clone())
    }

    /// Factors `a`, reusing its storage.
    pub fn in_place(a: Matrix) -> Lu {
        let n = a.rows;
        let mut lu = Lu {
            factors: a,
            pivots: Vec::with_capacity(n),
            sign: 1.0,
            singular: false,
        };
        lu.factor();
        lu
    }

    /// An empty factorisation, whose storage [`Lu::refactor`] reuses.
    pub fn empty() -> Lu {
        Lu {
            factors: Matrix::zeros(0, 0),
            pivots: Vec::new(),
            sign: 1.0,
            singular: false,
        }
    }

    /// Factors the `n × n` matrix that `fill` writes (into zeros), in this
    /// factorisation's storage: no allocation once it has held one of that
    /// size (the field method factors its conditions at every step).
    pub fn refactor(&mut self, n: usize, fill: impl FnOnce(&mut Matrix)) {
        let a = &mut self.factors;
        a.rows = n;
        a.cols = n;
        a.data.clear();
        a.data.resize(n * n, 0.0);
        fill(a);
        self.factor();
    }

    /// [`Lu::refactor`] of the `1 × 1` matrix `a`: what the loops do for
    /// one entry (no pivoting; singular where `|a|` is 0 or infinite, not
    /// where it is NaN, as the pivot search decides), without the fill's
    /// closure and the loops (the field's conditions of one degree of
    /// freedom, at every step).
    pub fn refactor_scalar(&mut self, a: f64) {
        let m = &mut self.factors;
        m.rows = 1;
        m.cols = 1;
        m.data.clear();
        m.data.push(a);
        self.pivots.clear();
        self.pivots.push(0);
        self.sign = 1.0;
        // The pivot search's fold from −1 (`c.1 > best.1`): NaN stays −1.
        let largest = if a.abs() > -1.0 { a.abs() } else { -1.0 };
        self.singular = largest == 0.0 || !largest.is_finite();
    }

    /// Factors `self.factors` in place.
    fn factor(&mut self) {
        let a = &mut self.factors;
        let n = a.rows;
        debug_assert_eq!(n, a.cols);
        let pivots = &mut self.pivots;
        pivots.clear();
        // The conditions of two, three and five degrees of freedom are
        // factored at every field step, and an implicit model's Jacobian
        // (a ball on a turntable: 3 × 3, a solve a column, h-stiff2) at
        // every linearisation: their sizes known, the same operations.
        let (sign, singular) = match n {
            // The 1 × 1 conditions of one degree of freedom, at every
            // field step and every sample between steps.
            1 => factor_sized::<1>(&mut a.data, n, pivots),
            2 => factor_sized::<2>(&mut a.data, n, pivots),
            3 => factor_sized::<3>(&mut a.data, n, pivots),
            4 => factor_sized::<4>(&mut a.data, n, pivots),
            5 => factor_sized::<5>(&mut a.data, n, pivots),
            6 => factor_sized::<6>(&mut a.data, n, pivots),
            _ => factor_sized::<0>(&mut a.data, n, pivots),
        };
        self.sign = sign;
        self.singular = singular;
    }

    pub fn dim(&self) -> usize {
        self.factors.rows
    }

    /// An exactly zero (or non-finite) pivot was met.
    pub fn is_singular(&self) -> bool {
        self.singular
    }

    pub fn determinant(&self) -> f64 {
        if self.singular {
            return 0.0;
        }
        (0..self.dim()).fold(self.sign, |d, k| d * self.factors[(k, k)])
    }

    /// The smallest over the largest absolute pivot: a cheap lower bound
    /// on `1/κ` up to growth, computed for free with the factors.
    pub fn pivot_ratio(&self) -> f64 {
        let n = self.dim();
        if n == 0 {
            return 1.0;
        }
        let (mut small, mut large) = (f64::INFINITY, 0.0_f64);
        for k in 0..n {
            let u = self.factors[(k, k)].abs();
            small = small.min(u);
            large = large.max(u);
        }
        if large > 0.0 {
            small / large
        } else {
            0.0
        }
    }

    /// Solves `A x = b` in place; `false` when `A` is singular.
    /// [`Lu::solve_in_place`] of every column of `b` (`self.dim()`
    /// numbers each, one after another): the same operations on each,
    /// the size matched once rather than at every column (a mass-matrix
    /// model's implicit Jacobian, six columns at every linearisation).
    /// `false` when `A` is singular (`b` unchanged).
    pub fn solve_columns_in_place(&self, b: &mut [f64]) -> bool {
        let n = self.dim();
        if self.singular || n == 0 || !b.len().is_multiple_of(n) {
            // Nothing to solve for, or not whole columns: untouched.
            return n == 0 && !self.singular;
        }
        let (f, pivots) = (&self.factors.data, &self.pivots);
        match n {
            1 => b.iter_mut().for_each(|v| *v /= f[0]),
            2 => b
                .chunks_exact_mut(2)
                .for_each(|c| lu_solve_sized::<2>(f, n, pivots, c)),
            3 => b
                .chunks_exact_mut(3)
                .for_each(|c| lu_solve_sized::<3>(f, n, pivots, c)),
            4 => b
                .chunks_exact_mut(4)
                .for_each(|c| lu_solve_sized::<4>(f, n, pivots, c)),
            5 => b
                .chunks_exact_mut(5)
                .for_each(|c| lu_solve_sized::<5>(f, n, pivots, c)),
            6 => b
                .chunks_exact_mut(6)
                .for_each(|c| lu_solve_sized::<6>(f, n, pivots, c)),
            _ => b
                .chunks_exact_mut(n)
                .for_each(|c| lu_solve_sized::<0>(f, n, pivots, c)),
        }
        true
    }

    pub fn solve_in_place(&self, b: &mut [f64]) -> bool {
        if self.singular {
            return false;
        }
        let n = self.dim();
        let f = &self.factors;
        match n {
            1 => {
                // What the loops below do for one unknown (the conditions
                // of one degree of freedom, three solves a field step).
                b[0] /= f.data[0];
                return true;
            }
            // The conditions of two, three and five degrees of freedom
            // (N = 3, 4, 6), at every field step and in every condition
            // estimate: the same loops with their bounds known.
            2 => lu_solve_sized::<2>(&f.data, n, &self.pivots, b),
            3 => lu_solve_sized::<3>(&f.data, n, &self.pivots, b),
            4 => lu_solve_sized::<4>(&f.data, n, &self.pivots, b),
            5 => lu_solve_sized::<5>(&f.data, n, &self.pivots, b),
            6 => lu_solve_sized::<6>(&f.data, n, &self.pivots, b),
            _ => lu_solve_sized::<0>(&f.data, n, &self.pivots, b),
        }
        true
    }

    /// Solves `Aᵀ x = b` in place; `false` when `A` is singular.
    pub fn solve_transpose_in_place(&self, b: &mut [f64]) -> bool {
        if self.singular {
            return false;
        }
        let n = self.dim();
        let f = &self.factors;
        // As `solve_in_place`: the small conditions' sizes known.
        match n {
            2 => lu_solve_transpose_sized::<2>(&f.data, n, &self.pivots, b),
            3 => lu_solve_transpose_sized::<3>(&f.data, n, &self.pivots, b),
            4 => lu_solve_transpose_sized::<4>(&f.data, n, &self.pivots, b),
            5 => lu_solve_transpose_sized::<5>(&f.data, n, &self.pivots, b),
            6 => lu_solve_transpose_sized::<6>(&f.data, n, &self.pivots, b),
            _ => lu_solve_transpose_sized::<0>(&f.data, n, &self.pivots, b),
        }
        true
    }

    /// Hager's (Higham's) estimate of `‖A⁻¹‖₁` from the factors: a few
    /// solves instead of an inverse. A lower bound, exact in most cases.
    pub fn inverse_one_norm_estimate(&self) -> f64 {
        let n = self.dim();
        if n == 1 && !self.singular {
            // The iteration on a 1 × 1 matrix ends after its first solve
            // with |1/a| (the field's conditions for one degree of freedom,
            // at every step).
            let norm = (1.0 / self.factors[(0, 0)]).abs();
            return if norm.is_finite() {
                norm
            } else {
                f64::INFINITY
            };
        }
        if n <= 8 {
            let mut scratch = [0.0; 24];
            self.inverse_one_norm_estimate_in(&mut scratch[..3 * n])
        } else {
            self.inverse_one_norm_estimate_in(&mut vec![0.0; 3 * n])
        }
    }

    /// [`Lu::inverse_one_norm_estimate`] in `3 n` numbers of scratch (on
    /// the stack for small `n`: the estimate runs at every field step).
    fn inverse_one_norm_estimate_in(&self, scratch: &mut [f64]) -> f64 {
        if self.singular {
            return f64::INFINITY;
        }
        let n = self.dim();
        if n == 0 {
            return 0.0;
        }
        let (x, rest) = scratch.split_at_mut(n);
        let (y, z) = rest.split_at_mut(n);
        x.fill(1.0 / n as f64);
        let mut estimate = 0.0;
        for _ in 0..5 {
            y.copy_from_slice(x);
            self.solve_in_place(y);
            let norm: f64 = y.iter().map(|v| v.abs()).sum();
            if !norm.is_finite() {
                return f64::INFINITY;
            }
            if norm <= estimate {
                break;
            }
            estimate = norm;
            for (z, &v) in z.iter_mut().zip(y.iter()) {
                *z = if v >= 0.0 { 1.0 } else { -1.0 };
            }
            self.solve_transpose_in_place(z);
            let (j, largest) = z
                .iter()
                .enumerate()
                .map(|(j, v)| (j, v.abs()))
                .fold((0, -1.0), |b, c| if c.1 > b.1 { c } else { b });
            let zx: f64 = z.iter().zip(x.iter()).map(|(a, b)| a * b).sum();
            if largest <= zx {
                break;
            }
            x.fill(0.0);
            x[j] = 1.0;
        }
        estimate
    }

    /// The inverse, column by column.
    pub fn inverse(&self) -> Option<Matrix> {
        if self.singular {
            return None;
        }
        let n = self.dim();
        let mut inv = Matrix::identity(n);
        for j in 0..n {
            self.solve_in_place(inv.column_mut(j));
        }
        Some(inv)
    }
}

/// [`Lu::factor`] of the `n × n` matrix `a` (column by column) in place,
/// with `n = N` known at compile time (`N = 0`: read at run time): the
/// pivots into `pivots`; returns the permutation's sign and whether a
/// pivot was zero.
#[inline(always)]
fn factor_sized<const N: usize>(a: &mut [f64], n: usize, pivots: &mut Vec<usize>) -> (f64, bool) {
    let n = if N == 0 { n } else { N };
    let a = &mut a[..n * n];
    let mut sign = 1.0;
    let mut singular = false;
    for k in 0..n {
        let (p, largest) = (k..n)
            .map(|i| (i, a[k * n + i].abs()))
            .fold((k, -1.0), |best, c| if c.1 > best.1 { c } else { best });
        pivots.push(p);
        if p != k {
            sign = -sign;
            for j in 0..n {
                a.swap(j * n + k, j * n + p);
            }
        }
        if largest == 0.0 || !largest.is_finite() {
            singular = true;
            continue;
        }
        let pivot = a[k * n + k];
        for i in k + 1..n {
            a[k * n + i] /= pivot;
        }
        for j in k + 1..n {
            let u = a[j * n + k];
            if u == 0.0 {
                continue;
            }
            for i in k + 1..n {
                let l = a[k * n + i];
                a[j * n + i] -= l * u;
            }
        }
    }
    (sign, singular)
}

/// [`Lu::solve_in_place`] of the regular factors `f` (column by column) of
/// an `n × n` matrix, with `n = N` known at compile time (`N = 0`: read at
/// run time): the same operations in the same order either way, so the
/// same bits.
#[inline(always)]
fn lu_solve_sized<const N: usize>(f: &[f64], n: usize, pivots: &[usize], b: &mut [f64]) {
    let n = if N == 0 { n } else { N };
    let (f, pivots, b) = (&f[..n * n], &pivots[..n], &mut b[..n]);
    for k in 0..n {
        b.swap(k, pivots[k]);
    }
    for j in 0..n {
        let bj = b[j];
        if bj != 0.0 {
            for i in j + 1..n {
                b[i] -= f[j * n + i] * bj;
            }
        }
    }
    for j in (0..n).rev() {
        b[j] /= f[j * n + j];
        let bj = b[j];
        if bj != 0.0 {
            for i in 0..j {
                b[i] -= f[j * n + i] * bj;
            }
        }
    }
}

/// [`Lu::solve_transpose_in_place`] as [`lu_solve_sized`]: `Aᵀ = Uᵀ Lᵀ P`,
/// solve `Uᵀ y = b`, `Lᵀ z = y`, then `x = Pᵀ z`.
#[inline(always)]
fn lu_solve_transpose_sized<const N: usize>(f: &[f64], n: usize, pivots: &[usize], b: &mut [f64]) {
    let n = if N == 0 { n } else { N };
    let (f, pivots, b) = (&f[..n * n], &pivots[..n], &mut b[..n]);
    for j in 0..n {
        let mut s = b[j];
        for i in 0..j {
            s -= f[j * n + i] * b[i];
        }
        b[j] = s / f[j * n + j];
    }
    for j in (0..n).rev() {
        let mut s = b[j];
        for i in j + 1..n {
            s -= f[j * n + i] * b[i];
        }
        b[j] = s;
    }
    for k in (0..n).rev() {
        b.swap(k, pivots[k]);
    }
}

/// The 1-norm condition number of `a` estimated from its factors.
pub fn condition_estimate(a: &Matrix, lu: &Lu) -> f64 {
    let estimate = a.one_norm() * lu.inverse_one_norm_estimate();
    if estimate.is_finite() {
        estimate.max(1.0)
    } else {
        f64::INFINITY
    }
}

/// Solves `A z = b` for a fixed-size system on the stack (generated code:
/// the mass matrix of the highest derivatives). `None` when a pivot is
/// zero or the result is not finite. LU with partial pivoting: the rows of
/// (4) may be scaled differently, so `A` need not be symmetric.
pub fn solve_fixed<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    for k in 0..N {
        let mut p = k;
        for i in k + 1..N {
            if a[i][k].abs() > a[p][k].abs() {
                p = i;
            }
        }
        if a[p][k] == 0.0 || !a[p][k].is_finite() {
            return None;
        }
        a.swap(k, p);
        b.swap(k, p);
        let pivot = a[k][k];
        for i in k + 1..N {
            let l = a[i][k] / pivot;
            if l != 0.0 {
                for j in k + 1..N {
                    a[i][j] -= l * a[k][j];
                }
                b[i] -= l * b[k];
            }
        }
    }
    for k in (0..N).rev() {
        let mut s = b[k];
        for j in k + 1..N {
            s -= a[k][j] * b[j];
        }
        b[k] = s / a[k][k];
    }
    b.iter().all(|v| v.is_finite()).then_some(b)
}

/// Solves `A z = b` for a fixed-size symmetric `A` by the square-root-free
/// Cholesky factorisation `A = L D Lᵀ` (only the lower triangle is read):
/// about half the work of [`solve_fixed`], no pivot search and no square
/// root, for the mass matrix of a Lagrangian, which is symmetric positive
/// definite. Returns `z` and the ratio of the smallest to the largest
/// pivot `d_k`; `None` when a pivot is not positive (`A` is not positive
/// definite: use [`solve_fixed`]) or the result is not finite.
pub fn ldlt_fixed<const N: usize>(
    mut a: [[f64; N]; N],
    mut b: [f64; N],
) -> Option<([f64; N], f64)> {
    let mut d = [0.0; N];
    let mut inverse = [0.0; N];
    // `w[k] = l_jk d_k` for the column `j` being factored.
    let mut w = [0.0; N];
    let (mut small, mut large) = (f64::INFINITY, 0.0_f64);
    for j in 0..N {
        let mut pivot = a[j][j];
        for k in 0..j {
            let v = a[j][k] * d[k];
            w[k] = v;
            pivot -= a[j][k] * v;
        }
        // Also false for NaN.
        if !(pivot > 0.0) || !pivot.is_finite() {
            return None;
        }
        small = small.min(pivot);
        large = large.max(pivot);
        d[j] = pivot;
        let r = 1.0 / pivot;
        inverse[j] = r;
        for i in j + 1..N {
            let mut s = a[i][j];
            for k in 0..j {
                s -= a[i][k] * w[k];
            }
            a[i][j] = s * r;
        }
    }
    for i in 0..N {
        let mut s = b[i];
        for k in 0..i {
            s -= a[i][k] * b[k];
        }
        b[i] = s;
    }
    for i in 0..N {
        b[i] *= inverse[i];
    }
    for i in (0..N).rev() {
        let mut s = b[i];
        for k in i + 1..N {
            s -= a[k][i] * b[k];
        }
        b[i] = s;
    }
    b.iter()
        .all(|v| v.is_finite())
        .then_some((b, small / large))
}

/// [`solve_fixed`] for a size known only at run time (large systems):
/// `a` is row-major `n × n`, overwritten; `b` becomes the solution.
pub fn solve_dense(n: usize, a: &mut [f64], b: &mut [f64]) -> bool {
    let mut m = Matrix::zeros(n, n);
    for i in 0..n {
        for j in 0..n {
            m[(i, j)] = a[i * n + j];
        }
    }
    let lu = Lu::in_place(m);
    lu.solve_in_place(b) && b.iter().all(|v| v.is_finite())
}

/// `exp(a)` by scaling and squaring with the diagonal Padé approximant of
/// degree 6 (Moler and Van Loan's method 3): accurate to rounding for
/// `‖a‖/2^s ≤ 1/2`.
pub fn expm(a: &Matrix) -> Matrix {
    let n = a.rows;
    let norm = a.one_norm();
    let squarings = if norm > 0.5 {
        (norm / 0.5).log2().ceil().max(0.0) as u32
    } else {
        0
    };
    let scale = 0.5_f64.powi(squarings as i32);
    let mut x = a.clone();
    x.data.iter_mut().for_each(|v| *v *= scale);
    // Padé(6,6): c_k = (2q−k)! q! / ((2q)! k! (q−k)!), q = 6.
    const C: [f64; 7] = [
        1.0,
        0.5,
        5.0 / 44.0,
        1.0 / 66.0,
        1.0 / 792.0,
        1.0 / 15840.0,
        1.0 / 665280.0,
    ];
    let mut power = Matrix::identity(n);
    let mut numerator = Matrix::identity(n);
    let mut denominator = Matrix::identity(n);
    for (k, &c) in C.iter().enumerate().skip(1) {
        power = power.mul(&x);
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        for (idx, &p) in power.data.iter().enumerate() {
            numerator.data[idx] += c * p;
            denominator.data[idx] += sign * c * p;
        }
    }
    let lu = Lu::in_place(denominator);
    let mut result = numerator;
    for j in 0..n {
        lu.solve_in_place(result.column_mut(j));
    }
    for _ in 0..squarings {
        result = result.mul(&result);
    }
    result
}

#[cfg(test)]
mod tests {
    /// The `1 × 1` factors set directly are the loops' factors, bit for
    /// bit: singular or not, determinant, solve, inverse's norm estimate.
    #[test]
    fn scalar_refactor_is_the_loops() {
        use super::Lu;
        let values = [
            0.0,
            -0.0,
            1.0,
            -3.5,
            1e-310,
            5e-324,
            f64::MAX,
            1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let (mut fast, mut slow) = (Lu::empty(), Lu::empty());
        for &a in &values {
            fast.refactor_scalar(a);
            slow.refactor(1, |m| m.as_mut_slice()[0] = a);
            assert_eq!(fast.is_singular(), slow.is_singular(), "{a:e}");
            assert_eq!(fast.determinant().to_bits(), slow.determinant().to_bits());
            assert_eq!(fast.pivots, slow.pivots);
            assert_eq!(fast.sign.to_bits(), slow.sign.to_bits());
            let (mut x, mut y) = ([0.7], [0.7]);
            assert_eq!(fast.solve_in_place(&mut x), slow.solve_in_place(&mut y));
            assert_eq!(x[0].to_bits(), y[0].to_bits());
            let (e, f) = (
                fast.inverse_one_norm_estimate(),
                slow.inverse_one_norm_estimate(),
            );
            assert_eq!(e.to_bits(), f.to_bits(), "{a:e}");
        }
    }

    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + b.abs())
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// A matrix with pivoting, zeros (the skipped updates) and rounding.
    fn awkward(n: usize) -> Matrix {
        let data = (0..n * n)
            .map(|k| {
                if k % (n + 2) == 1 {
                    0.0
                } else {
                    ((k * 7 + 3) % 11) as f64 / 3.0 - 1.7 + (k as f64 * 0.31).sin()
                }
            })
            .collect();
        Matrix::from_column_major(n, n, data)
    }

    /// The factors and both solves compiled for a size (n = 2, 3, 5) are
    /// the loops that read the size at run time, bit for bit.
    #[test]
    fn lu_compiled_for_a_size_is_the_general_lu_bit_for_bit() {
        for n in 1..=7 {
            let a = awkward(n);
            let lu = Lu::new(&a);
            let mut general = a.data.clone();
            let mut pivots = Vec::new();
            let (sign, singular) = factor_sized::<0>(&mut general, n, &mut pivots);
            assert_eq!(bits(&lu.factors.data), bits(&general), "n = {n}");
            assert_eq!(
                (lu.pivots.clone(), lu.sign, lu.singular),
                (pivots, sign, singular)
            );
            assert!(!singular, "n = {n}");
            let rhs: Vec<f64> = (0..n)
                .map(|i| if i == 1 { 0.0 } else { 1.0 / (i + 1) as f64 })
                .collect();
            let (mut fast, mut slow) = (rhs.clone(), rhs.clone());
            assert!(lu.solve_in_place(&mut fast));
            lu_solve_sized::<0>(&general, n, &lu.pivots, &mut slow);
            assert_eq!(bits(&fast), bits(&slow), "n = {n}");
            let (mut fast, mut slow) = (rhs.clone(), rhs);
            assert!(lu.solve_transpose_in_place(&mut fast));
            lu_solve_transpose_sized::<0>(&general, n, &lu.pivots, &mut slow);
            assert_eq!(bits(&fast), bits(&slow), "n = {n}");
        }
    }

    /// The product compiled for a square size is the general loop's, bit
    /// for bit: an extra zero column (skipped, as zero entries of `x`
    /// are) sends the same numbers through the general loop.
    #[test]
    fn mul_vec_compiled_for_a_size_is_the_general_product_bit_for_bit() {
        for n in 1..=7 {
            let a = awkward(n);
            let mut wide = a.data.clone();
            wide.extend(std::iter::repeat_n(5.0, n));
            let wide = Matrix::from_column_major(n, n + 1, wide);
            let x: Vec<f64> = (0..n)
                .map(|i| if i == 2 { 0.0 } else { 0.3 - i as f64 })
                .collect();
            let mut x_wide = x.clone();
            x_wide.push(0.0);
            let (mut fast, mut slow) = (vec![0.0; n], vec![0.0; n]);
            a.mul_vec(&x, &mut fast);
            wide.mul_vec(&x_wide, &mut slow);
            assert_eq!(bits(&fast), bits(&slow), "n = {n}");
        }
    }

    /// Finite exactly when every entry is, at every length.
    #[test]
    fn is_finite_finds_a_non_finite_entry_anywhere() {
        // 4 and 6: the unrolled lengths 16 and 36.
        for n in 1..=6 {
            let a = awkward(n);
            assert!(a.is_finite());
            for k in 0..n * n {
                for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                    let mut b = a.clone();
                    b.data[k] = bad;
                    assert!(!b.is_finite(), "n = {n}, entry {k}, {bad}");
                }
            }
        }
    }

    #[test]
    fn lu_solves_and_transposed_solves_match_the_definition() {
        let a = Matrix::from_rows(&[&[2.0, 1.0, 1.0], &[4.0, -6.0, 0.0], &[-2.0, 7.0, 2.0]]);
        let lu = Lu::new(&a);
        let x = [1.0, -2.0, 3.0];
        let mut b = vec![0.0; 3];
        a.mul_vec(&x, &mut b);
        assert!(lu.solve_in_place(&mut b));
        for i in 0..3 {
            assert!(close(b[i], x[i], 1e-14), "{b:?}");
        }
        let mut bt = vec![0.0; 3];
        a.mul_transpose_vec(&x, &mut bt);
        assert!(lu.solve_transpose_in_place(&mut bt));
        for i in 0..3 {
            assert!(close(bt[i], x[i], 1e-14), "{bt:?}");
        }
        // det = 2(−12 − 0) − 1(8 − 0) + 1(28 − 12) = −16
        assert!(close(lu.determinant(), -16.0, 1e-14));
    }

    #[test]
    fn ldlt_solves_a_symmetric_positive_definite_system_and_refuses_others() {
        // A pendulum-like mass matrix: symmetric, positive definite.
        let a = [[3.0, 2.0, 1.0], [2.0, 2.0, 0.5], [1.0, 0.5, 1.0]];
        let x = [1.0, -2.0, 3.0];
        let b: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| a[i][j] * x[j]).sum());
        let (z, ratio) = ldlt_fixed(a, b).expect("positive definite");
        let lu = solve_fixed(a, b).expect("regular");
        for i in 0..3 {
            assert!(close(z[i], x[i], 1e-14), "{z:?}");
            assert!(close(z[i], lu[i], 1e-14), "{z:?} {lu:?}");
        }
        assert!(ratio > 0.0 && ratio <= 1.0, "{ratio}");
        // Indefinite (a negative pivot) and singular (a zero pivot): None.
        assert!(ldlt_fixed([[1.0, 2.0], [2.0, 1.0]], [1.0, 1.0]).is_none());
        assert!(ldlt_fixed([[1.0, 1.0], [1.0, 1.0]], [1.0, 1.0]).is_none());
        // Nearly singular: the pivot ratio says so.
        let (_, ratio) = ldlt_fixed([[1.0, 1.0], [1.0, 1.0 + 1e-12]], [1.0, 1.0]).unwrap();
        assert!(ratio < 1e-11, "{ratio}");
    }

    #[test]
    fn condition_estimate_is_exact_on_a_diagonal_and_large_near_singular() {
        let a = Matrix::from_rows(&[&[1.0, 0.0], &[0.0, 1e-6]]);
        let lu = Lu::new(&a);
        assert!(close(condition_estimate(&a, &lu), 1e6, 1e-12));
        let b = Matrix::from_rows(&[&[1.0, 1.0], &[1.0, 1.0 + 1e-12]]);
        let lu = Lu::new(&b);
        assert!(condition_estimate(&b, &lu) > 1e11);
        let c = Matrix::from_rows(&[&[1.0, 2.0], &[2.0, 4.0]]);
        assert!(Lu::new(&c).is_singular() || condition_estimate(&c, &Lu::new(&c)) > 1e15);
    }

    #[test]
    fn is_finite_finds_every_infinity_and_nan() {
        let finite = [0.0, -0.0, 1.0, -f64::MAX, f64::MAX, 5e-324, -1e-310];
        assert!(Matrix::from_column_major(7, 1, finite.to_vec()).is_finite());
        for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -f64::NAN] {
            for at in 0..7 {
                let mut data = finite.to_vec();
                data[at] = bad;
                assert!(
                    !Matrix::from_column_major(7, 1, data).is_finite(),
                    "{bad} at {at}"
                );
            }
        }
    }

    /// The 1 × 1 shortcut and the stack's scratch give the iteration's
    /// own estimate, to the bit; `refactor` the factors of `new`.
    #[test]
    fn inverse_norm_estimate_shortcuts_are_the_iteration() {
        for a in [3.0, -0.7, 1e-300, -2.5e300, 1.0 / 3.0, 5e-324] {
            let lu = Lu::new(&Matrix::from_rows(&[&[a]]));
            let iteration = lu.inverse_one_norm_estimate_in(&mut [0.0; 3]);
            assert_eq!(
                lu.inverse_one_norm_estimate().to_bits(),
                iteration.to_bits(),
                "{a:e}"
            );
        }
        let rows = [[3.0, 1.0, 0.5], [-1.0, 4.0, 1.0], [0.5, 1.0, 5.0]];
        let a = Matrix::from_rows(&[&rows[0], &rows[1], &rows[2]]);
        let fresh = Lu::new(&a);
        let mut reused = Lu::new(&Matrix::from_rows(&[&[2.0, 1.0], &[1.0, 0.0]]));
        reused.refactor(3, |m| m.as_mut_slice().copy_from_slice(a.as_slice()));
        assert_eq!(
            reused.determinant().to_bits(),
            fresh.determinant().to_bits()
        );
        let iteration = fresh.inverse_one_norm_estimate_in(&mut [0.0; 9]);
        assert_eq!(
            reused.inverse_one_norm_estimate().to_bits(),
            iteration.to_bits()
        );
    }

    #[test]
    fn fixed_and_dense_solves_agree_with_lu() {
        let rows = [[3.0, 1.0, 0.5], [1.0, 4.0, 1.0], [0.5, 1.0, 5.0]];
        let b = [1.0, 2.0, 3.0];
        let fixed = solve_fixed(rows, b).unwrap();
        let mut flat: Vec<f64> = rows.iter().flatten().copied().collect();
        let mut dense = b.to_vec();
        assert!(solve_dense(3, &mut flat, &mut dense));
        let a = Matrix::from_rows(&[&rows[0], &rows[1], &rows[2]]);
        let mut check = vec![0.0; 3];
        a.mul_vec(&fixed, &mut check);
        for i in 0..3 {
            assert!(close(fixed[i], dense[i], 1e-14));
            assert!(close(check[i], b[i], 1e-14));
        }
        assert!(solve_fixed([[1.0, 2.0], [2.0, 4.0]], [1.0, 1.0]).is_none());
    }

    #[test]
    fn expm_of_a_rotation_generator_and_a_nilpotent_matrix() {
        let w = 3.0;
        let a = Matrix::from_rows(&[&[0.0, w], &[-w, 0.0]]);
        let e = expm(&a);
        assert!(close(e[(0, 0)], w.cos(), 1e-13));
        assert!(close(e[(0, 1)], w.sin(), 1e-13));
        assert!(close(e[(1, 0)], -w.sin(), 1e-13));
        let n = Matrix::from_rows(&[&[0.0, 1.0, 0.0], &[0.0, 0.0, 1.0], &[0.0, 0.0, 0.0]]);
        let e = expm(&n);
        assert!(close(e[(0, 2)], 0.5, 1e-15) && close(e[(0, 1)], 1.0, 1e-15));
    }
}
