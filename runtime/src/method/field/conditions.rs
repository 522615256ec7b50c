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

use crate::linalg::Lu;

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
    /// The pivot of regular `1 × 1` factors
    /// ([`EquilibratedLu::refactor_scalar`]): their solve and determinant
    /// then skip the loops (the same operations on one number).
    scalar: Option<f64>,
}

/// `2^(−round(log2 largest))`, the power of two that brings `largest` near
/// 1 (1 for zero or non-finite). From the exponent's bits where the
/// mantissa is clear of √2 (where the rounding turns) and the result is
/// normal, else by `log2` — the same number either way, at the cost of a
/// few integer operations instead of `log2`, `round` and `exp2` per row
/// and column at every step (3 % of an oscillator's field).
fn power_of_two(largest: f64) -> f64 {
    if !(largest > 0.0 && largest.is_finite()) {
        return 1.0;
    }
    if largest.is_normal() {
        let bits = largest.to_bits();
        let exponent = ((bits >> 52) & 0x7ff) as i64 - 1023;
        let mantissa = f64::from_bits((bits & ((1 << 52) - 1)) | (1023 << 52));
        if (mantissa - std::f64::consts::SQRT_2).abs() > 1e-12 {
            let k = if mantissa < std::f64::consts::SQRT_2 {
                exponent
            } else {
                exponent + 1
            };
            if (-1022..=1022).contains(&k) {
                return f64::from_bits(((1023 - k) as u64) << 52);
            }
        }
    }
    (-largest.log2().round()).exp2()
}

impl EquilibratedLu {
    fn empty() -> EquilibratedLu {
        EquilibratedLu {
            lu: Lu::empty(),
            rows: Vec::new(),
            columns: Vec::new(),
            scalar: None,
        }
    }

    /// Factors the condition matrix `M(S, x0)` equilibrated, in this
    /// factorisation's storage (no allocation at every step); its
    /// condition number when `estimate` (else 1).
    fn refactor(&mut self, s: &[f64], n: usize, x0: &[f64], estimate: bool) -> f64 {
        if n == 2 {
            // The condition matrix's one entry (as `refactor_sized` forms it).
            return self.refactor_scalar(s[3] - s[1] * x0[1], estimate);
        }
        self.refactor_general(s, n, x0, estimate)
    }

    /// [`EquilibratedLu::refactor`] of the `1 × 1` conditions of one
    /// degree of freedom, `m`: what the general loops compute for one
    /// entry, bit for bit (a fold from 0 with `max`, a sum of one term),
    /// without their closures, vectors and index checks (590 instructions
    /// a call, at every step and every output between steps).
    fn refactor_scalar(&mut self, m: f64, estimate: bool) -> f64 {
        let row = power_of_two(0.0_f64.max(m.abs()));
        let column = power_of_two(0.0_f64.max((row * m).abs()));
        let scaled = m * (row * column);
        self.rows.clear();
        self.rows.push(row);
        self.columns.clear();
        self.columns.push(column);
        self.lu.refactor_scalar(scaled);
        self.scalar = (!self.lu.is_singular()).then_some(scaled);
        if !estimate || self.lu.is_singular() {
            return 1.0;
        }
        let norm = 0.0_f64.max(scaled.abs());
        let condition = norm * self.lu.inverse_one_norm_estimate();
        if condition.is_finite() {
            condition.max(1.0)
        } else {
            f64::INFINITY
        }
    }

    /// [`EquilibratedLu::refactor`] of any size: the conditions of three
    /// and four degrees of freedom (N = 4, 6: 2 and 3 unknowns, at every
    /// field step) with their size known at compile time, the same
    /// operations in the same order.
    fn refactor_general(&mut self, s: &[f64], n: usize, x0: &[f64], estimate: bool) -> f64 {
        self.scalar = None;
        match n {
            4 => self.refactor_sized::<3>(s, n, x0, estimate),
            6 => self.refactor_sized::<5>(s, n, x0, estimate),
            _ => self.refactor_sized::<0>(s, n, x0, estimate),
        }
    }

    /// [`EquilibratedLu::refactor_general`] for `M = n − 1` unknowns
    /// (`M = 0`: read at run time).
    #[inline(always)]
    fn refactor_sized<const M: usize>(
        &mut self,
        s: &[f64],
        n: usize,
        x0: &[f64],
        estimate: bool,
    ) -> f64 {
        let size = if M == 0 { n - 1 } else { M };
        let n = size + 1;
        let (s, x0) = (&s[..n * n], &x0[..n]);
        let (rows, columns) = (&mut self.rows, &mut self.columns);
        let mut norm = 0.0;
        self.lu.refactor(size, |m| {
            let data = &mut m.as_mut_slice()[..size * size];
            // The condition matrix `M` at `(S, x0)`, entry (row, col) at
            // col·size + row: `S_BA − S_B1 x_A0` (column A of S holds
            // ∂f/∂c_A), A = row + 1, B = col + 1.
            for col in 0..size {
                let b = col + 1;
                for row in 0..size {
                    let a = row + 1;
                    data[col * size + row] = s[a * n + b] - s[b] * x0[a];
                }
            }
            rows.clear();
            rows.extend((0..size).map(|r| {
                power_of_two((0..size).fold(0.0_f64, |a, c| a.max(data[c * size + r].abs())))
            }));
            columns.clear();
            columns.extend((0..size).map(|c| {
                power_of_two(
                    (0..size).fold(0.0_f64, |a, r| a.max((rows[r] * data[c * size + r]).abs())),
                )
            }));
            let (rows, columns) = (&rows[..size], &columns[..size]);
            for c in 0..size {
                for r in 0..size {
                    data[c * size + r] *= rows[r] * columns[c];
                }
            }
            if estimate {
                norm = m.one_norm();
            }
        });
        if !estimate || self.lu.is_singular() {
            return 1.0;
        }
        // `condition_estimate` of the equilibrated matrix, from its norm
        // taken before the factors overwrote it.
        let condition = norm * self.lu.inverse_one_norm_estimate();
        if condition.is_finite() {
            condition.max(1.0)
        } else {
            f64::INFINITY
        }
    }

    /// `det M`: `det(R M C)` over the scalings' (exact) product.
    fn determinant(&self) -> f64 {
        let scalings: f64 = if let ([row], [column]) = (&self.rows[..], &self.columns[..]) {
            // The 1 × 1 conditions: the product from 1 as `product` forms
            // it, without its iterator's call.
            1.0 * row * column
        } else {
            self.rows.iter().chain(&self.columns).product()
        };
        // The factors' determinant: of regular 1 × 1 factors, the sign's
        // (1) product with the pivot, as `Lu::determinant` folds it.
        let factors = match self.scalar {
            Some(pivot) => 1.0 * pivot,
            None => self.lu.determinant(),
        };
        if scalings.is_normal() {
            factors / scalings
        } else {
            // Out of range: the sign, which is what the windows use, is
            // still that of det(R M C).
            factors
        }
    }

    /// [`EquilibratedLu::solve_in_place`] of the 1 × 1 conditions
    /// (factored by [`EquilibratedLu::refactor_scalar`]): the same
    /// operations on one number.
    #[inline(always)]
    fn solve_scalar(&self, z: &mut f64) {
        let mut one = [*z];
        self.solve_in_place(&mut one);
        *z = one[0];
    }

    fn solve_in_place(&self, z: &mut [f64]) {
        if let (Some(pivot), [row], [column], [v]) =
            (self.scalar, &self.rows[..], &self.columns[..], &mut z[..])
        {
            // Regular 1 × 1 factors: the loops' three operations.
            *v = *v * row / pivot * column;
            return;
        }
        for (v, r) in z.iter_mut().zip(&self.rows) {
            *v *= r;
        }
        self.lu.solve_in_place(z);
        for (v, c) in z.iter_mut().zip(&self.columns) {
            *v *= c;
        }
    }
}

/// Solves the conditions for the state; `None` when they are singular or
/// the result is not finite.
pub fn recover(f: &[f64], s: &[f64], x0: &[f64]) -> Option<Recovered> {
    let mut out = Recovered::empty();
    recover_into(f, s, x0, &mut out).then_some(out)
}

/// [`recover`] into `out`, reusing its storage (the field's windows
/// recover a state at every step); `false` where `recover` gives `None`
/// (`out` then holds nothing of use).
pub fn recover_into(f: &[f64], s: &[f64], x0: &[f64], out: &mut Recovered) -> bool {
    solve_conditions(f, s, x0, true, out)
}

/// The state alone, for output between steps whose conditions were
/// checked: no condition estimate (about a third of the solve's cost).
pub fn recover_state(f: &[f64], s: &[f64], x0: &[f64]) -> Option<Vec<f64>> {
    let mut out = Recovered::empty();
    solve_conditions(f, s, x0, false, &mut out).then_some(out.state)
}

/// [`recover_state`] into `out`'s storage (its `state`; `condition` is 1).
pub fn recover_state_into(f: &[f64], s: &[f64], x0: &[f64], out: &mut Recovered) -> bool {
    solve_conditions(f, s, x0, false, out)
}

/// [`recover`] into `out`, with the condition estimate only when
/// `estimate` (else `condition` is 1).
fn solve_conditions(f: &[f64], s: &[f64], x0: &[f64], estimate: bool, out: &mut Recovered) -> bool {
    // One and two degrees of freedom (N = 2, 4) with the size known at
    // compile time (at every field step, and twice at every sample
    // between steps): the same operations in the same order. For one
    // degree of freedom the general loops over the 1 × 1 conditions cost
    // about 600 instructions a call (a tenth of a damped oscillator's
    // field, h-affine3).
    let n = f.len();
    if s.len() == n * n && x0.len() == n {
        match n {
            2 => return solve_conditions_one(f, s, x0, estimate, out),
            4 => return solve_conditions_sized::<4>(f, s, x0, estimate, out),
            // Three degrees of freedom (knife_edge, a triple pendulum).
            6 => return solve_conditions_sized::<6>(f, s, x0, estimate, out),
            _ => {}
        }
    }
    solve_conditions_sized::<0>(f, s, x0, estimate, out)
}

/// [`solve_conditions_sized`] for one degree of freedom (`N = 2`, the
/// `1 × 1` conditions `m z = r`), written out: the same operations in the
/// same order (folds from 0 with `max`, a sum of one term from `−0.0`),
/// without the vectors' resizing and the loops' bounds (the general code
/// cost about 600 instructions a call at every field step and twice a
/// sample between steps: a tenth of a damped oscillator's field,
/// h-affine3).
#[inline(always)]
fn solve_conditions_one(
    f: &[f64],
    s: &[f64],
    x0: &[f64],
    estimate: bool,
    out: &mut Recovered,
) -> bool {
    let (f, s, x0) = (&f[..2], &s[..4], &x0[..2]);
    let growth = s.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if !growth.is_finite() || f.iter().any(|v| !v.is_finite()) {
        return false;
    }
    out.growth = growth;
    if out.state.len() != 2 {
        out.state.clear();
        out.state.resize(2, 0.0);
    }
    // The right side `r = −(S_12 − S_11 x_20)` and the entry
    // `m = S_22 − S_21 x_20` (column-major `S`, as the general loops index).
    let product = s[1] * x0[1];
    let entry = s[3] - product;
    let mut z = -(s[2] - s[0] * x0[1]);
    let terms = 0.0_f64
        .max(s[3].abs() + product.abs())
        .max(s[2].abs() + (s[0] * x0[1]).abs());
    let entries = 0.0_f64.max(entry.abs()).max(z.abs());
    out.formation = if entries > 0.0 {
        (terms / entries).max(1.0)
    } else {
        f64::INFINITY
    };
    let lu = out.lu.get_or_insert_with(EquilibratedLu::empty);
    let condition = lu.refactor_scalar(entry, estimate);
    if lu.lu.is_singular() {
        return false;
    }
    out.condition = condition;
    out.determinant = lu.determinant();
    lu.solve_scalar(&mut z);
    out.state[1] = z;
    out.state[0] = f[0] + std::iter::once(f[1] * z).sum::<f64>();
    out.state.iter().all(|v| v.is_finite()) && condition.is_finite()
}

/// [`solve_conditions`] for `N` coefficients (`N = 0`: read at run time,
/// `s` and `x0` read as given).
#[inline(always)]
fn solve_conditions_sized<const N: usize>(
    f: &[f64],
    s: &[f64],
    x0: &[f64],
    estimate: bool,
    out: &mut Recovered,
) -> bool {
    let (f, s, x0) = if N == 0 {
        (f, s, x0)
    } else {
        (&f[..N], &s[..N * N], &x0[..N])
    };
    let n = if N == 0 { f.len() } else { N };
    let growth = s.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if !growth.is_finite() || f.iter().any(|v| !v.is_finite()) {
        return false;
    }
    out.growth = growth;
    out.state.clear();
    if n == 1 {
        out.state.push(f[0]);
        out.condition = 1.0;
        out.determinant = 1.0;
        out.formation = 1.0;
        out.lu = None;
        return true;
    }
    let m = n - 1;
    // The state is (x_1, z): the right side z of the conditions first,
    // solved in place.
    out.state.resize(n, 0.0);
    let z = &mut out.state[1..];
    for (row, v) in z.iter_mut().enumerate() {
        let a = row + 1;
        *v = -(s[a * n] - s[0] * x0[a]);
    }
    // Magnitudes of the terms of each entry against the entries (the
    // entries as `refactor_sized` forms them).
    let (mut terms, mut entries) = (0.0_f64, 0.0_f64);
    for col in 0..m {
        let b = col + 1;
        for row in 0..m {
            let a = row + 1;
            terms = terms.max(s[a * n + b].abs() + (s[b] * x0[a]).abs());
            entries = entries.max((s[a * n + b] - s[b] * x0[a]).abs());
        }
    }
    for (row, &value) in z.iter().enumerate() {
        let a = row + 1;
        terms = terms.max(s[a * n].abs() + (s[0] * x0[a]).abs());
        entries = entries.max(value.abs());
    }
    out.formation = if entries > 0.0 {
        (terms / entries).max(1.0)
    } else {
        f64::INFINITY
    };
    let lu = out.lu.get_or_insert_with(EquilibratedLu::empty);
    let condition = lu.refactor(s, n, x0, estimate);
    if lu.lu.is_singular() {
        return false;
    }
    out.condition = condition;
    out.determinant = lu.determinant();
    lu.solve_in_place(z);
    out.state[0] = f[0] + (1..n).map(|a| f[a] * out.state[a]).sum::<f64>();
    out.state.iter().all(|v| v.is_finite()) && condition.is_finite()
}

impl Recovered {
    /// Storage for [`recover_into`].
    pub fn empty() -> Recovered {
        Recovered {
            state: Vec::new(),
            condition: 1.0,
            determinant: 1.0,
            growth: 0.0,
            formation: 1.0,
            lu: None,
        }
    }

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

    /// A bound of the recovered state's error from errors `dr[a]` (a ≥ 1,
    /// `dr[0]` not read) of the conditions' right sides alone, into `dx`:
    /// `|M⁻¹| dr` on `x_2..x_N`, and `|fᵀ M⁻¹| dr` on `x_1 = f_1 + Σ_A f_A
    /// x_A` (the error `δz = M⁻¹ δr` reaches `x_1` as `fᵀ δz`, whose terms
    /// may cancel column by column: `Σ_A |f_A| dx_A` ended a chaotic double
    /// pendulum's windows at `x_1` near 0 for no digit lost). A bound
    /// column by column (one solve per nonzero `dr[a]`, into `column`),
    /// not one solve of `dr`, whose signs would let the columns of `M⁻¹`
    /// cancel where rounding's do not.
    pub fn right_side_bound(&self, f: &[f64], dr: &[f64], dx: &mut [f64], column: &mut Vec<f64>) {
        let n = f.len();
        dx.fill(0.0);
        let Some(lu) = &self.lu else {
            return;
        };
        column.resize(n - 1, 0.0);
        for a in 1..n {
            if dr[a] == 0.0 {
                continue;
            }
            column.fill(0.0);
            column[a - 1] = dr[a];
            lu.solve_in_place(column);
            for (d, v) in dx[1..].iter_mut().zip(column.iter()) {
                *d += v.abs();
            }
            dx[0] += (1..n).map(|b| f[b] * column[b - 1]).sum::<f64>().abs();
        }
    }

    /// The first-order change of the recovered state when `(f, S)` change
    /// by `(df, ds)` (same layouts), into `dx`.
    pub fn map_error(&self, f: &[f64], x0: &[f64], df: &[f64], ds: &[f64], dx: &mut [f64]) {
        // Twice at every field step: one, two and three degrees of
        // freedom (N = 2, 4, 6) with the size known, the same operations in the same
        // order.
        match f.len() {
            2 => self.map_error_sized::<2>(f, x0, df, ds, dx),
            4 => self.map_error_sized::<4>(f, x0, df, ds, dx),
            6 => self.map_error_sized::<6>(f, x0, df, ds, dx),
            _ => self.map_error_sized::<0>(f, x0, df, ds, dx),
        }
    }

    /// [`Recovered::map_error`] for `N` coefficients (`N = 0`: read at
    /// run time).
    #[inline(always)]
    fn map_error_sized<const N: usize>(
        &self,
        f: &[f64],
        x0: &[f64],
        df: &[f64],
        ds: &[f64],
        dx: &mut [f64],
    ) {
        let (f, x0, df, ds, dx) = if N == 0 {
            (f, x0, df, ds, dx)
        } else {
            (&f[..N], &x0[..N], &df[..N], &ds[..N * N], &mut dx[..N])
        };
        let n = if N == 0 { f.len() } else { N };
        let Some(lu) = &self.lu else {
            dx[0] = df[0];
            return;
        };
        let z = &self.state[1..n];
        // δz = M⁻¹ (δr − δM z), δr_A = −(δS_1A − δS_11 x_A0),
        // (δM z)_A = Σ_B (δS_BA − δS_B1 x_A0) z_B; into dx[1..].
        let (dx0, dz) = dx.split_at_mut(1);
        for (a, v) in (1..n).zip(dz.iter_mut()) {
            let dr = -(ds[a * n] - ds[0] * x0[a]);
            let dm_z: f64 = (1..n)
                .map(|b| (ds[a * n + b] - ds[b] * x0[a]) * z[b - 1])
                .sum();
            *v = dr - dm_z;
        }
        lu.solve_in_place(dz);
        dx0[0] = df[0]
            + (1..n)
                .map(|a| df[a] * z[a - 1] + f[a] * dz[a - 1])
                .sum::<f64>();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The power of two from the exponent's bits is `2^(−round(log2 x))`
    /// as `log2` computes it, bit for bit: over a sweep of magnitudes,
    /// next to √2 (where the rounding turns), at the ends of the range.
    #[test]
    fn power_of_two_is_the_log2_formula() {
        let reference = |x: f64| {
            if x > 0.0 && x.is_finite() {
                (-x.log2().round()).exp2()
            } else {
                1.0
            }
        };
        let mut values = vec![
            0.0,
            -1.0,
            f64::INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            f64::MAX,
        ];
        values.extend([5e-324, 1e-310, 1.0, 2.0, 0.75, 1.5]);
        let mut x = 1e-300;
        while x < 1e300 {
            values.push(x);
            x *= 1.37;
        }
        for k in -1030..=1030 {
            let at = std::f64::consts::SQRT_2 * 2f64.powi(k);
            let mut v = at;
            for _ in 0..4 {
                v = v.next_down();
            }
            for _ in 0..9 {
                values.push(v);
                v = v.next_up();
            }
            values.push(at * (1.0 + 2e-12));
            values.push(at * (1.0 - 2e-12));
        }
        for v in values {
            assert_eq!(power_of_two(v).to_bits(), reference(v).to_bits(), "{v:e}");
        }
    }

    /// The `1 × 1` conditions' own path factors, scales and estimates as
    /// the general loops do, to the bit: over entries of every magnitude,
    /// zero, subnormal, infinite and NaN.
    /// The conditions compiled for a size (the solve at N = 2 and 4, the
    /// equilibrated factors at N = 4 and 6) are the loops that read the
    /// size at run time, bit for bit: state, condition, determinant,
    /// growth and formation, with and without the estimate.
    #[test]
    fn conditions_compiled_for_a_size_are_the_general_loops() {
        let bits = |r: &Recovered| {
            let mut v: Vec<u64> = r.state.iter().map(|x| x.to_bits()).collect();
            v.extend([r.condition, r.determinant, r.growth, r.formation].map(f64::to_bits));
            v
        };
        for n in [2, 3, 4, 5, 6] {
            for case in 0..4 {
                let f: Vec<f64> = (0..n)
                    .map(|i| 0.5 - 0.37 * i as f64 + case as f64)
                    .collect();
                let s: Vec<f64> = (0..n * n)
                    .map(|k| {
                        let diagonal = if k % (n + 1) == 0 { 1.0 } else { 0.0 };
                        diagonal
                            + 0.3
                                * ((k * 7 + case * 3) as f64 * 0.71).sin()
                                * 10f64.powi(case as i32 - 1)
                    })
                    .collect();
                let x0: Vec<f64> = (0..n).map(|i| 1.3 - 0.6 * i as f64).collect();
                for estimate in [true, false] {
                    let (mut fast, mut slow) = (Recovered::empty(), Recovered::empty());
                    let ok = solve_conditions(&f, &s, &x0, estimate, &mut fast);
                    assert_eq!(
                        ok,
                        solve_conditions_sized::<0>(&f, &s, &x0, estimate, &mut slow)
                    );
                    assert!(ok, "n = {n}, case {case}");
                    assert_eq!(bits(&fast), bits(&slow), "n = {n}, case {case}");
                    let df: Vec<f64> = (0..n).map(|i| 1e-9 * (i as f64 - 1.5)).collect();
                    let ds: Vec<f64> = s.iter().map(|v| 1e-8 * (v * 3.1).cos()).collect();
                    let (mut dx_fast, mut dx_slow) = (vec![0.0; n], vec![0.0; n]);
                    fast.map_error(&f, &x0, &df, &ds, &mut dx_fast);
                    slow.map_error_sized::<0>(&f, &x0, &df, &ds, &mut dx_slow);
                    let raw = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(raw(&dx_fast), raw(&dx_slow), "n = {n}, case {case}");
                    let (mut sized, mut general) =
                        (EquilibratedLu::empty(), EquilibratedLu::empty());
                    let c = sized.refactor_general(&s, n, &x0, estimate);
                    let d = general.refactor_sized::<0>(&s, n, &x0, estimate);
                    assert_eq!(c.to_bits(), d.to_bits(), "n = {n}, case {case}");
                    assert_eq!(
                        sized.determinant().to_bits(),
                        general.determinant().to_bits()
                    );
                    let mut z: Vec<f64> = (1..n).map(|i| i as f64 - 0.5).collect();
                    let mut w = z.clone();
                    sized.solve_in_place(&mut z);
                    general.solve_in_place(&mut w);
                    assert_eq!(
                        z.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                        w.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
                    );
                }
            }
        }
    }

    #[test]
    fn scalar_conditions_are_the_general_loops() {
        let mut values = vec![
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            f64::MAX,
            -f64::MAX,
            5e-324,
            1e-310,
            std::f64::consts::SQRT_2,
        ];
        let mut x = 1e-300;
        while x < 1e300 {
            values.push(x);
            values.push(-x * 1.1);
            x *= 3.7;
        }
        let bits = |v: f64| v.to_bits();
        for &a in &values {
            for &b in &[0.0, 1.0, -2.5, 1e200, f64::NAN] {
                // s (column-major, n = 2) and x0 with S_22 − S_21 x0_2 = m.
                let s = [1.0, b, 0.5, a];
                let x0 = [0.3, 0.75];
                for estimate in [true, false] {
                    let (mut scalar, mut general) =
                        (EquilibratedLu::empty(), EquilibratedLu::empty());
                    let c1 = scalar.refactor(&s, 2, &x0, estimate);
                    let c2 = general.refactor_general(&s, 2, &x0, estimate);
                    assert_eq!(bits(c1), bits(c2), "{a:e} {b:e}");
                    assert_eq!(scalar.lu.is_singular(), general.lu.is_singular());
                    assert_eq!(bits(scalar.determinant()), bits(general.determinant()));
                    let (mut z1, mut z2) = ([0.7], [0.7]);
                    scalar.solve_in_place(&mut z1);
                    general.solve_in_place(&mut z2);
                    assert_eq!(bits(z1[0]), bits(z2[0]), "{a:e} {b:e}");
                }
            }
        }
    }

    /// The conditions of one degree of freedom written out
    /// (`solve_conditions_one`) are the general loops, bit for bit, on
    /// entries of every magnitude, zero, subnormal, infinite and NaN:
    /// whether they succeed, the state, condition, determinant, growth and
    /// formation, and the error map through their factors.
    #[test]
    fn one_degree_of_freedom_is_the_general_loops() {
        let values = [
            0.0,
            -0.0,
            1.0,
            -0.75,
            3.3e-5,
            1e200,
            -1e-200,
            5e-324,
            f64::MAX,
            std::f64::consts::SQRT_2,
            f64::INFINITY,
            f64::NAN,
        ];
        let bits = |r: &Recovered| {
            let mut v: Vec<u64> = r.state.iter().map(|x| x.to_bits()).collect();
            v.extend([r.condition, r.determinant, r.growth, r.formation].map(f64::to_bits));
            v
        };
        let mut fast = Recovered::empty();
        let mut cases = 0;
        for (i, &a) in values.iter().enumerate() {
            for (j, &b) in values.iter().enumerate() {
                for &(c, d) in &[(0.5, 1.0), (-2.0, 0.0), (1e-300, 7.0), (f64::NAN, 1.0)] {
                    let s = [1.0 + c, b, a, d];
                    let f = [values[(i + j) % values.len()], 0.25 - c];
                    let x0 = [0.3, values[(3 * i + j) % 9]];
                    for estimate in [true, false] {
                        let mut slow = Recovered::empty();
                        let ok = solve_conditions(&f, &s, &x0, estimate, &mut fast);
                        let ok_slow = solve_conditions_sized::<0>(&f, &s, &x0, estimate, &mut slow);
                        assert_eq!(ok, ok_slow, "{s:?} {f:?} {x0:?}");
                        if !ok {
                            continue;
                        }
                        cases += 1;
                        assert_eq!(bits(&fast), bits(&slow), "{s:?} {f:?} {x0:?}");
                        let (df, ds) = ([1e-9, -2e-9], [3e-9, -1e-9, 2e-9, 5e-9]);
                        let (mut dx_fast, mut dx_slow) = ([0.0; 2], [0.0; 2]);
                        fast.map_error(&f, &x0, &df, &ds, &mut dx_fast);
                        slow.map_error_sized::<0>(&f, &x0, &df, &ds, &mut dx_slow);
                        assert_eq!(dx_fast.map(f64::to_bits), dx_slow.map(f64::to_bits));
                    }
                }
            }
        }
        assert!(cases > 300, "{cases} cases solved");
    }

    /// Storage reused across sizes and values recovers what a fresh solve
    /// recovers, to the bit.
    #[test]
    fn recovery_into_reused_storage_is_a_fresh_recovery() {
        let mut reused = Recovered::empty();
        for (n, seed) in [(3, 0.3), (2, 0.7), (4, 1.1), (3, 1.9), (1, 0.2)] {
            let f: Vec<f64> = (0..n).map(|i| (seed + i as f64).sin()).collect();
            let mut s: Vec<f64> = (0..n * n)
                .map(|k| 0.3 * (seed * 3.0 + k as f64).cos())
                .collect();
            for i in 0..n {
                s[i * n + i] += 1.0;
            }
            let x0: Vec<f64> = (0..n).map(|i| (seed * 2.0 - i as f64).cos()).collect();
            let fresh = recover(&f, &s, &x0).unwrap();
            assert!(recover_into(&f, &s, &x0, &mut reused));
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&reused.state), bits(&fresh.state), "n = {n}");
            assert_eq!(reused.condition.to_bits(), fresh.condition.to_bits());
            assert_eq!(reused.determinant.to_bits(), fresh.determinant.to_bits());
            assert_eq!(reused.formation.to_bits(), fresh.formation.to_bits());
            let ds: Vec<f64> = s.iter().map(|v| 1e-7 * v).collect();
            let df: Vec<f64> = f.iter().map(|v| -2e-7 * v).collect();
            let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
            fresh.map_error(&f, &x0, &df, &ds, &mut a);
            reused.map_error(&f, &x0, &df, &ds, &mut b);
            assert_eq!(bits(&a), bits(&b));
        }
    }

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
