//! `Model.linearize(at=…, params=…, inputs=…, t=…)`: `lagc linearize`
//! from Python (issue 27). The symbolic half — the free state, the
//! ignorable coordinates, the rates with the constraints' fixed components
//! substituted, their exact partials in the free state, the params and the
//! inputs — is the compiler's (`src/linearize/parts.rs`), printed into the
//! module as `impl Linear for Model` (`src/emit/linear.rs`); this file
//! evaluates it at a point in the order `src/linearize/system.rs` does, so
//! the result is the command line's `--format json` to rounding.

use lagc_runtime::linalg::Matrix;
use lagc_runtime::model::{Inputs, Model};

/// Which state components the linearization holds. Indices into the state
/// are the model's; "free position" `i` is `free[i]`.
pub struct LinearLayout {
    /// The state components the constraints do not fix.
    pub free: &'static [usize],
    /// Free positions of `A`'s state (no ignorable coordinates).
    pub kept: &'static [usize],
    /// Free positions of the ignorable coordinates.
    pub ignorable: &'static [usize],
    /// The state components the constraints fix, in `linear_fixed`'s order.
    pub fixed: &'static [usize],
    /// The dependent positions of holonomic constraints `f(t, q) = 0`
    /// (columns `free.len() + d` of `linear_a` and `linear_g_x`).
    pub bound: &'static [usize],
    /// The number of unknowns `z` of the implicit system of the highest
    /// derivatives, `G(t, x, z) = 0` (0: explicit).
    pub unknowns: usize,
    /// `(free position, j)`: the rates that are `z_j`.
    pub unknown_rows: &'static [(usize, usize)],
    /// `G` is affine in `z` (one linear solve; else Newton from `z = 0`).
    pub implicit_linear: bool,
}

/// The linearization's symbolic half, printed by lagc for one model. Every
/// function reads the params from the model, the inputs from the values it
/// holds (`set_inputs`), the state from `x` (free components only) and the
/// implicit system's unknowns from `z`; matrices get their non-zero
/// entries written.
pub trait Linear {
    /// Why the module carries no linearization (`None`: it does).
    const UNAVAILABLE: Option<&'static str>;
    /// Per mode (the candidates' choice of dependents; one for most
    /// models), its layout. Every function takes the mode first.
    const LAYOUTS: &'static [LinearLayout];
    /// Per free position: the model's stated initial value.
    fn linear_stated(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut [f64]) {}
    /// Per fixed component: the value the constraints give it.
    fn linear_fixed(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut [f64]) {}
    /// Per free position (not an unknown's): its rate `f`.
    fn linear_rates(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut [f64]) {}
    /// `∂f/∂x` over the free state (rows not an unknown's).
    fn linear_a(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut Matrix) {}
    /// `∂f/∂(p, u)`: the params' direct partials, then the inputs'.
    fn linear_b(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut Matrix) {}
    /// `∂p_k/∂p_l` of each param's expression in the params before it.
    fn linear_chain(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut Matrix) {}
    /// `G`, `∂G/∂z`, `∂G/∂x` (free columns), `∂G/∂(p, u)`.
    fn linear_g(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut [f64]) {}
    fn linear_g_z(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut Matrix) {}
    fn linear_g_x(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut Matrix) {}
    fn linear_g_p(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut Matrix) {}
    /// `∂D/∂z` of the dependent highest derivatives' rates (free rows).
    fn linear_d_z(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut Matrix) {}
    /// The holonomic constraints `f`, `∂f/∂z` (the bound positions),
    /// `∂f/∂x` (free columns), `∂f/∂(p, u)`.
    fn linear_f(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut [f64]) {}
    fn linear_f_z(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut Matrix) {}
    fn linear_f_x(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut Matrix) {}
    fn linear_f_p(&self, _mode: usize, _t: f64, _x: &[f64], _z: &[f64], _out: &mut Matrix) {}
}

/// A request, names resolved to indices.
pub struct Request {
    /// `(state index, value)`.
    pub at: Vec<(usize, f64)>,
    /// Every param's value, and whether it was given (not recomputed from
    /// the params before it).
    pub params: Vec<f64>,
    pub overridden: Vec<bool>,
    /// Every input's value at the point.
    pub inputs: Vec<f64>,
    pub t: Option<f64>,
}

/// The linearization at a point, as `lagc linearize --format json` has it.
pub struct Linearization {
    pub t: f64,
    pub state: Vec<usize>,
    pub point: Vec<f64>,
    pub ignorable: Vec<(usize, f64)>,
    pub fixed: Vec<(usize, f64)>,
    pub a: Vec<Vec<f64>>,
    pub b_params: Vec<Vec<f64>>,
    pub b_inputs: Vec<Vec<f64>>,
    pub eigenvalues: Vec<(f64, f64)>,
    pub residual: Vec<f64>,
    pub equilibrium: bool,
}

/// A residual smaller than this fraction of its scale is zero.
const ZERO: f64 = 1e-9;

/// The linearization of model `M` with these params at the request's
/// point; `Err` is the message of a `ValueError`. A model of several modes
/// is linearized in the first whose fixed components the request does not
/// give and that is defined there (mode 1 if none is), as `lagc
/// linearize` chooses.
pub fn linearize<M: Model + Linear>(
    request: &Request,
    names: &[&str],
) -> Result<Linearization, String> {
    if let Some(why) = M::UNAVAILABLE {
        return Err(format!(
            "this module carries no linearization: {why}; `lagc linearize FILE` gives it"
        ));
    }
    let layouts = M::LAYOUTS;
    if layouts.len() > 1 {
        for (mode, layout) in layouts.iter().enumerate() {
            let fixes_given = layout
                .fixed
                .iter()
                .any(|&k| request.at.iter().any(|&(j, _)| j == k));
            if fixes_given {
                continue;
            }
            if let Ok(l) = linearize_in::<M>(request, names, mode) {
                return Ok(l);
            }
        }
    }
    linearize_in::<M>(request, names, 0)
}

/// The linearization in one mode.
fn linearize_in<M: Model + Linear>(
    request: &Request,
    names: &[&str],
    mode: usize,
) -> Result<Linearization, String> {
    let layout = &M::LAYOUTS[mode];
    let mut model = M::new(&request.params);
    model.set_inputs(&Inputs::held(&request.inputs));
    let t = request.t.unwrap_or_else(|| model.time_span().0);
    let nf = layout.free.len();
    let dim = M::STATE.len();
    let mut x = vec![f64::NAN; dim];
    let nb = layout.bound.len();
    let mut stated = vec![f64::NAN; nf + nb];
    model.linear_stated(mode, t, &x, &[], &mut stated);
    for (i, &k) in layout.free.iter().enumerate() {
        let given = request.at.iter().find(|&&(j, _)| j == k).map(|&(_, v)| v);
        let v = given.unwrap_or(stated[i]);
        if !v.is_finite() {
            return Err(format!(
                "the model states no value of `{}` (or it is {v} with these params): give it \
                 in `at`",
                names[k]
            ));
        }
        x[k] = v;
    }
    for (d, &k) in layout.bound.iter().enumerate() {
        let given = request.at.iter().find(|&&(j, _)| j == k).map(|&(_, v)| v);
        let v = given.unwrap_or(stated[nf + d]);
        if !v.is_finite() {
            return Err(format!(
                "the model states no value of `{}`: give it in `at`",
                names[k]
            ));
        }
        x[k] = v;
    }
    close(&model, mode, layout, request, names, t, &mut x)?;
    let mut fixed = vec![f64::NAN; layout.fixed.len()];
    model.linear_fixed(mode, t, &x, &[], &mut fixed);
    for (&k, &v) in layout.fixed.iter().zip(&fixed) {
        if !v.is_finite() {
            return Err(format!(
                "the constraint's value of `{}` is {v} at this point: choose another point",
                names[k]
            ));
        }
        if let Some(&(_, g)) = request.at.iter().find(|&&(j, _)| j == k) {
            if (g - v).abs() > 1e-9 * (1.0 + v.abs()) {
                return Err(format!(
                    "`{}={g}` in `at` violates the constraints, which fix it at {v} here: \
                     leave it out",
                    names[k]
                ));
            }
        }
    }
    // The fixed components as the constraints give them: every function
    // reads the free ones only, but the state is whole.
    for (&k, &v) in layout.fixed.iter().zip(&fixed) {
        x[k] = v;
    }

    let z = solve_highest(&model, mode, layout, t, &x)?;
    let g_z = factored(&model, mode, layout, t, &x, &z);
    let mut a_free = rows(
        &model,
        mode,
        layout,
        t,
        &x,
        &z,
        g_z.as_ref(),
        nf + nb,
        Columns::State,
    )?;
    let dz_x = closure_slopes(&model, mode, layout, t, &x, nf, Columns::State)?;
    chain_through(&mut a_free, &dz_x, nf);
    let kept = layout.kept;
    let a: Vec<Vec<f64>> = kept
        .iter()
        .map(|&i| kept.iter().map(|&c| a_free[i][c]).collect())
        .collect();
    for (r, row) in a.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            if !v.is_finite() {
                return Err(format!(
                    "A is not defined at this point: ∂(rate of {})/∂{} is {v}",
                    names[layout.free[kept[r]]], names[layout.free[kept[c]]]
                ));
            }
        }
    }

    let np = request.params.len();
    let columns = np + request.inputs.len();
    let b_partial = rows(
        &model,
        mode,
        layout,
        t,
        &x,
        &z,
        g_z.as_ref(),
        columns,
        Columns::Params,
    )?;
    // The dependent positions move with the params too.
    let dz_p = closure_slopes(&model, mode, layout, t, &x, columns, Columns::Params)?;
    let mut b_partial = b_partial;
    for (row, a_row) in b_partial.iter_mut().zip(&a_free) {
        let through = &a_row[nf..];
        for (p, cell) in row.iter_mut().enumerate() {
            *cell += through
                .iter()
                .zip(&dz_p)
                .map(|(a, dzd)| a * dzd[p])
                .sum::<f64>();
        }
    }
    let chain = param_chain(&model, mode, t, &x, &request.overridden);
    let b_params: Vec<Vec<f64>> = kept
        .iter()
        .map(|&i| {
            (0..np)
                .map(|j| {
                    (0..np)
                        .map(|k| b_partial[i][k] * chain[k][j])
                        .filter(|v| *v != 0.0)
                        .sum()
                })
                .collect()
        })
        .collect();
    let b_inputs: Vec<Vec<f64>> = kept
        .iter()
        .map(|&i| {
            (np..np + request.inputs.len())
                .map(|c| b_partial[i][c])
                .collect()
        })
        .collect();

    let mut rates = vec![f64::NAN; nf];
    model.linear_rates(mode, t, &x, &z, &mut rates);
    for &(i, j) in layout.unknown_rows {
        rates[i] = z[j];
    }
    let mut residual = Vec::with_capacity(kept.len());
    let mut equilibrium = true;
    for (r, &i) in kept.iter().enumerate() {
        let value = rates[i];
        if !value.is_finite() {
            return Err(format!(
                "the right side is not defined at this point: the rate of {} is {value}",
                names[layout.free[i]]
            ));
        }
        // The scale of the rate's terms near the point, first order:
        // `Σ |∂f/∂x_j x_j| + Σ |∂f/∂p_k p_k|` (the command line scales
        // the rate's expression itself; the two agree on whether a rate
        // is zero wherever it is zero or not small).
        let scale: f64 = (0..nf)
            .map(|c| (a_free[i][c] * x[layout.free[c]]).abs())
            .chain((0..np).map(|k| (b_params[r][k] * request.params[k]).abs()))
            .filter(|v| v.is_finite())
            .sum();
        if !(value == 0.0 || value.abs() <= ZERO * scale) {
            equilibrium = false;
        }
        residual.push(value);
    }
    Ok(Linearization {
        t,
        state: kept.iter().map(|&i| layout.free[i]).collect(),
        point: kept.iter().map(|&i| x[layout.free[i]]).collect(),
        ignorable: layout
            .ignorable
            .iter()
            .map(|&i| (layout.free[i], x[layout.free[i]]))
            .collect(),
        fixed: layout.fixed.iter().copied().zip(fixed).collect(),
        eigenvalues: eigenvalues(&a),
        a,
        b_params,
        b_inputs,
        residual,
        equilibrium,
    })
}

/// `G(t, x, z) = 0` solved for `z`: one linear solve, or Newton from
/// `z = 0` with the exact `G_z` (as `lagc linearize`, nalgebra's LU).
fn solve_highest<M: Linear>(
    model: &M,
    mode: usize,
    layout: &LinearLayout,
    t: f64,
    x: &[f64],
) -> Result<Vec<f64>, String> {
    let m = layout.unknowns;
    let mut z = vec![0.0; m];
    if m == 0 {
        return Ok(z);
    }
    let iterations = if layout.implicit_linear { 1 } else { 50 };
    for _ in 0..iterations {
        let mut g = vec![0.0; m];
        model.linear_g(mode, t, x, &z, &mut g);
        let jz = dense(&{
            let mut jz = Matrix::zeros(m, m);
            model.linear_g_z(mode, t, x, &z, &mut jz);
            jz
        });
        let rhs = -nalgebra::DVector::from_vec(g);
        let step = jz
            .lu()
            .solve(&rhs)
            .filter(|s| s.iter().all(|v| v.is_finite()))
            .ok_or_else(|| {
                "the highest derivatives are not defined at this point: the matrix of their \
                 coefficients is singular (a singular mass matrix or a vanishing pivot of the \
                 constraints): choose another point"
                    .to_string()
            })?;
        let size = step.amax();
        for (zk, dk) in z.iter_mut().zip(step.iter()) {
            *zk += dk;
        }
        if size <= 1e-14 * (1.0 + z.iter().fold(0.0_f64, |a, v| a.max(v.abs()))) {
            break;
        }
    }
    Ok(z)
}

fn dense(m: &Matrix) -> nalgebra::DMatrix<f64> {
    nalgebra::DMatrix::from_fn(m.rows(), m.cols(), |r, c| m[(r, c)])
}

/// `G_z` at the point (`None` for an explicit system).
fn factored<M: Linear>(
    model: &M,
    mode: usize,
    layout: &LinearLayout,
    t: f64,
    x: &[f64],
    z: &[f64],
) -> Option<nalgebra::DMatrix<f64>> {
    let m = layout.unknowns;
    (m > 0).then(|| {
        let mut jz = Matrix::zeros(m, m);
        model.linear_g_z(mode, t, x, z, &mut jz);
        dense(&jz)
    })
}

/// The dependent positions put on `f(t, q) = 0` by Newton over them alone
/// from the values given (or the model's), as `lagc linearize` does
/// (`src/linearize/closure.rs`; it stops at a residual within rounding of
/// its terms, this at a step within rounding of the positions); a value
/// given that is not on the constraints is an error.
fn close<M: Linear>(
    model: &M,
    mode: usize,
    layout: &LinearLayout,
    request: &Request,
    names: &[&str],
    t: f64,
    x: &mut [f64],
) -> Result<(), String> {
    let m = layout.bound.len();
    if m == 0 {
        return Ok(());
    }
    let guess: Vec<f64> = layout.bound.iter().map(|&k| x[k]).collect();
    for _ in 0..50 {
        let mut f = vec![0.0; m];
        model.linear_f(mode, t, x, &[], &mut f);
        if f.iter().all(|&v| v == 0.0) {
            break;
        }
        let mut fz = Matrix::zeros(m, m);
        model.linear_f_z(mode, t, x, &[], &mut fz);
        let step = dense(&fz)
            .lu()
            .solve(&(-nalgebra::DVector::from_vec(f)))
            .filter(|s| s.iter().all(|v| v.is_finite()))
            .ok_or_else(|| {
                "the holonomic constraints cannot be solved for their dependent positions \
                 here (their Jacobian is singular): choose another point"
                    .to_string()
            })?;
        let mut largest = 0.0_f64;
        for (&k, d) in layout.bound.iter().zip(step.iter()) {
            x[k] += d;
            largest = largest.max(d.abs() / (1.0 + x[k].abs()));
        }
        if largest <= 1e-16 {
            break;
        }
    }
    let mut f = vec![0.0; m];
    model.linear_f(mode, t, x, &[], &mut f);
    for (d, &k) in layout.bound.iter().enumerate() {
        let v = x[k];
        if f.iter()
            .any(|r| !r.is_finite() || r.abs() > 1e-8 * (1.0 + v.abs()))
        {
            return Err(
                "no configuration on the holonomic constraints near this point: choose \
                 positions on (or near) them"
                    .to_string(),
            );
        }
        let given = request.at.iter().any(|&(j, _)| j == k);
        if given && (v - guess[d]).abs() > 1e-9 * (1.0 + v.abs()) {
            return Err(format!(
                "`{}={}` in `at` is off the holonomic constraints, which put it at {v} here: \
                 leave it out",
                names[k], guess[d]
            ));
        }
    }
    Ok(())
}

/// `∂z/∂v = −f_z⁻¹ ∂f/∂v` for the dependent positions, one row per
/// position (empty without holonomic constraints).
fn closure_slopes<M: Linear>(
    model: &M,
    mode: usize,
    layout: &LinearLayout,
    t: f64,
    x: &[f64],
    columns: usize,
    of: Columns,
) -> Result<Vec<Vec<f64>>, String> {
    let m = layout.bound.len();
    if m == 0 {
        return Ok(Vec::new());
    }
    let mut fz = Matrix::zeros(m, m);
    model.linear_f_z(mode, t, x, &[], &mut fz);
    let mut fv = Matrix::zeros(m, columns);
    match of {
        Columns::State => model.linear_f_x(mode, t, x, &[], &mut fv),
        Columns::Params => model.linear_f_p(mode, t, x, &[], &mut fv),
    }
    let slopes = dense(&fz).lu().solve(&(-dense(&fv))).ok_or_else(|| {
        "the holonomic constraints are singular here: choose another point".to_string()
    })?;
    Ok((0..m)
        .map(|r| slopes.row(r).iter().copied().collect())
        .collect())
}

/// `A[r][c] += Σ_d A[r][free + d] ∂z_d/∂x_c` for the free columns.
fn chain_through(a: &mut [Vec<f64>], dz: &[Vec<f64>], free: usize) {
    if dz.is_empty() {
        return;
    }
    for row in a.iter_mut() {
        let through: Vec<f64> = row[free..].to_vec();
        for (c, cell) in row.iter_mut().take(free).enumerate() {
            *cell += through
                .iter()
                .zip(dz)
                .map(|(a, dzd)| a * dzd[c])
                .sum::<f64>();
        }
    }
}

/// Which variables a row of partials is taken in.
#[derive(Clone, Copy)]
enum Columns {
    State,
    Params,
}

/// `∂rate_i/∂v_c` evaluated, one row per free position: a rate's own
/// partials; an unknown's row `−G_z⁻¹ G_v`; a dependent highest
/// derivative's `D_v + D_z z_v` (`evaluate_rows` in
/// `src/linearize/system.rs`).
#[allow(clippy::too_many_arguments)]
fn rows<M: Linear>(
    model: &M,
    mode: usize,
    layout: &LinearLayout,
    t: f64,
    x: &[f64],
    z: &[f64],
    g_z: Option<&nalgebra::DMatrix<f64>>,
    columns: usize,
    of: Columns,
) -> Result<Vec<Vec<f64>>, String> {
    let nf = layout.free.len();
    let mut direct = Matrix::zeros(nf, columns);
    match of {
        Columns::State => model.linear_a(mode, t, x, z, &mut direct),
        Columns::Params => model.linear_b(mode, t, x, z, &mut direct),
    }
    let mut out: Vec<Vec<f64>> = (0..nf)
        .map(|i| (0..columns).map(|c| direct[(i, c)]).collect())
        .collect();
    let Some(jz) = g_z else {
        return Ok(out);
    };
    let m = layout.unknowns;
    let mut g_v = Matrix::zeros(m, columns);
    match of {
        Columns::State => model.linear_g_x(mode, t, x, z, &mut g_v),
        Columns::Params => model.linear_g_p(mode, t, x, z, &mut g_v),
    }
    let z_v = jz.clone().lu().solve(&(-dense(&g_v))).ok_or_else(|| {
        "the highest derivatives' coefficients are singular at this point: choose another point"
            .to_string()
    })?;
    let mut d_z = Matrix::zeros(nf, m);
    model.linear_d_z(mode, t, x, z, &mut d_z);
    for (i, row) in out.iter_mut().enumerate() {
        if let Some(&(_, j)) = layout.unknown_rows.iter().find(|&&(r, _)| r == i) {
            for (c, cell) in row.iter_mut().enumerate() {
                *cell = z_v[(j, c)];
            }
            continue;
        }
        for (c, cell) in row.iter_mut().enumerate() {
            let through: f64 = (0..m)
                .filter(|&k| d_z[(i, k)] != 0.0)
                .map(|k| d_z[(i, k)] * z_v[(k, c)])
                .sum();
            *cell += through;
        }
    }
    Ok(out)
}

/// `T[k][j] = dp_k/dp_j` with the params after `p_j` recomputed from it
/// (an overridden one is not recomputed), as `lagc linearize` chains them.
fn param_chain<M: Linear>(
    model: &M,
    mode: usize,
    t: f64,
    x: &[f64],
    overridden: &[bool],
) -> Vec<Vec<f64>> {
    let np = overridden.len();
    let mut slopes = Matrix::zeros(np, np);
    model.linear_chain(mode, t, x, &[], &mut slopes);
    let mut chain = vec![vec![0.0; np]; np];
    for k in 0..np {
        chain[k][k] = 1.0;
        if overridden[k] {
            continue;
        }
        for l in 0..k {
            let slope = slopes[(k, l)];
            if slope == 0.0 {
                continue;
            }
            let (done, rest) = chain.split_at_mut(k);
            for (sum, &through) in rest[0].iter_mut().zip(&done[l]).take(l + 1) {
                *sum += slope * through;
            }
        }
    }
    chain
}

/// The eigenvalues of `A`, largest real part first (pairs: positive
/// imaginary part first), by nalgebra's real Schur form as `lagc
/// linearize` takes them (`src/linearize/eigen.rs`); all NaN when the
/// iteration does not converge.
fn eigenvalues(a: &[Vec<f64>]) -> Vec<(f64, f64)> {
    let n = a.len();
    if n == 0 {
        return Vec::new();
    }
    let m = nalgebra::DMatrix::from_fn(n, n, |r, c| a[r][c]);
    let Some(schur) = nalgebra::linalg::Schur::try_new(m, f64::EPSILON, 10_000) else {
        return vec![(f64::NAN, f64::NAN); n];
    };
    let mut out: Vec<(f64, f64)> = schur
        .complex_eigenvalues()
        .iter()
        .map(|c| (c.re, c.im))
        .collect();
    out.sort_by(|x, y| y.0.total_cmp(&x.0).then_with(|| y.1.total_cmp(&x.1)));
    out
}
