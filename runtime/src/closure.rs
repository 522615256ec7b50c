//! Holonomic constraints `f(t, q) = 0` at position level (SPEC §2.3):
//! Newton over the dependent coordinates for the initial positions
//! (completed from the given ones), and the projection of a run's state
//! onto the constraints along their normals, which the keeper
//! (`crate::run::keep`) makes before it keeps the velocities. The generated code
//! supplies `f` and its partials.

use std::cell::Cell;

use crate::failure::{Failure, FailureKind};
use crate::linalg::{Lu, Matrix};

/// `eval(z, f, jac)`: the residuals `f` and `jac = ∂f/∂z` at the dependent
/// coordinates `z` (`jac` zeroed by the caller).
pub type ClosureFn<'a> = &'a mut dyn FnMut(&[f64], &mut [f64], &mut Matrix);

/// At most this many Newton steps.
const STEPS: usize = 50;

/// Why Newton found no root.
#[derive(Clone, Debug, PartialEq)]
pub struct NoRoot {
    /// The residual `max |f_ν|` where it stopped.
    pub residual: f64,
    /// The Jacobian was singular there.
    pub singular: bool,
}

/// Newton on `f(z) = 0` from `z` (in place), a step that does not
/// decrease `max |f|` halved (down to 1/1024), until the step is at the
/// level of rounding. Returns the number of steps taken.
pub fn solve(z: &mut [f64], eval: ClosureFn) -> Result<usize, NoRoot> {
    let n = z.len();
    let mut f = vec![0.0; n];
    let mut f_next = vec![0.0; n];
    let mut jac = Matrix::zeros(n, n);
    let mut unused = Matrix::zeros(n, n);
    let norm = |f: &[f64]| f.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    eval(z, &mut f, &mut jac);
    let mut next = vec![0.0; n];
    for step in 0..STEPS {
        let residual = norm(&f);
        if !residual.is_finite() {
            return Err(NoRoot {
                residual,
                singular: false,
            });
        }
        if residual == 0.0 {
            return Ok(step);
        }
        let lu = Lu::new(&jac);
        let mut delta = f.clone();
        if lu.is_singular()
            || !lu.solve_in_place(&mut delta)
            || delta.iter().any(|d| !d.is_finite())
        {
            if on_constraints_by_rounding(residual, z) {
                return Ok(step);
            }
            return Err(NoRoot {
                residual,
                singular: true,
            });
        }
        let full = norm(&delta);
        let magnitude = z.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        let mut scale = 1.0;
        loop {
            for i in 0..n {
                next[i] = z[i] - scale * delta[i];
            }
            unused.fill(0.0);
            eval(&next, &mut f_next, &mut unused);
            if norm(&f_next) < residual || scale < 1e-3 {
                break;
            }
            scale *= 0.5;
        }
        if !(norm(&f_next) < residual) {
            // The residual no longer decreases: rounding, when the step
            // that would reduce it is at its level.
            if full <= 1e-9 * magnitude {
                return Ok(step);
            }
            return Err(NoRoot {
                residual,
                singular: false,
            });
        }
        z.copy_from_slice(&next);
        jac.fill(0.0);
        eval(z, &mut f, &mut jac);
        if full <= 4.0 * f64::EPSILON * magnitude {
            return Ok(step + 1);
        }
    }
    let residual = norm(&f);
    if residual == 0.0 {
        return Ok(STEPS);
    }
    Err(NoRoot {
        residual,
        singular: false,
    })
}

/// Whether a residual where the Jacobian in the dependents is singular is
/// the rounding of a configuration on the constraints (a double pendulum
/// in Cartesian coordinates started with its second rod level, where
/// `∂f/∂y2 = 2 (y2 - y1)` vanishes and `sin² + cos² - 1` leaves 1.7e-16):
/// no Newton step is needed there, and none can be taken. The measure is
/// the positions' squares, the size of a length constraint's terms; the
/// keeper then holds the run on the constraints to its tolerance. The
/// compiler's check of the model's own values takes the same rule.
pub fn on_constraints_by_rounding(residual: f64, z: &[f64]) -> bool {
    let magnitude = z.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
    residual <= ROUNDING_RESIDUAL * magnitude * magnitude
}

/// [`on_constraints_by_rounding`]'s relative residual.
const ROUNDING_RESIDUAL: f64 = 1e-12;

/// The initial positions: [`solve`] from the given ones at `t0`, a failure
/// naming the constraints when there is no root near them.
pub fn initial(t0: f64, z: &mut [f64], constraint: &str, eval: ClosureFn) -> Result<(), Failure> {
    solve(z, eval).map(|_| ()).map_err(|why| {
        Failure::new(
            t0,
            FailureKind::InitialPositionsOffConstraint {
                constraint: constraint.to_string(),
                residual: why.residual,
                singular: why.singular,
            },
        )
    })
}

/// `eval(x, r, f, normals)`: for `r = 0` the residuals `f(t, q)` and the
/// normals `∂f/∂q` (over every coordinate, zeroed by the caller) at the
/// state `x`; for `r ≥ 1` the residuals `D^r f` of the derivatives.
pub type ProjectFn<'a> = &'a mut dyn FnMut(&[f64], usize, &mut [f64], &mut Matrix);

/// Projects the state `x` (in place) onto holonomic constraints along
/// their normals: Gauss–Newton `Δq = −Jᵀ (J Jᵀ)⁻¹ f` on the positions (the
/// smallest correction, to rounding), then each derivative block `q^(r)`,
/// `r = 1..levels`, onto `D^r f = 0`, which is affine in it with the same
/// `J` (one step, and one more for rounding). Moving the dependents alone
/// instead made a particle circling at uniform speed 100× less accurate:
/// where a dependent's pivot is poor, its correction is large and mostly
/// along the motion. Partitioned by `dependents` (the keeper's choice where
/// the independent coordinates are integrated exactly,
/// `run/keep/partition.rs`) the dependents alone are solved for; `None`,
/// dependents that are not one per constraint, or a singular block of
/// theirs in the normals: along the normals. `(m, n, levels)`: the
/// constraints, the coordinates, the derivative blocks.
pub fn project(
    t: f64,
    x: &mut [f64],
    dependents: Option<Dependents>,
    sizes: (usize, usize, usize),
    constraint: &str,
    eval: ProjectFn,
) -> Result<(), Failure> {
    let mut workspace = WORKSPACE.with(Cell::take).unwrap_or_else(|| Workspace {
        f: Vec::new(),
        normals: Matrix::zeros(0, 0),
        gram: Vec::new(),
        lambda: Vec::new(),
        lu: Lu::empty(),
    });
    let result = project_with(&mut workspace, t, x, dependents, sizes, constraint, eval);
    WORKSPACE.with(|w| w.set(Some(workspace)));
    result
}

/// The buffers of [`project`], kept on the thread from call to call: the
/// keeper projects a holonomic model's state after every step and at
/// every output, and these were four allocations a call and two more a
/// correction (docs/BENCHMARKS.md §10h). Taken out of the cell for a call
/// and put back after it (a call that never returns them leaves `None`,
/// and the next makes new ones).
#[derive(Debug)]
struct Workspace {
    f: Vec<f64>,
    normals: Matrix,
    gram: Vec<f64>,
    lambda: Vec<f64>,
    lu: Lu,
}

thread_local! {
    static WORKSPACE: Cell<Option<Workspace>> = const { Cell::new(None) };
}

/// The most dependent coordinates a partitioned projection holds.
pub const MOST_DEPENDENTS: usize = 8;

/// Dependent coordinates (indices among the coordinates) of a
/// partitioned projection: the independent ones are kept as they are, and
/// the dependents solved from the constraints (Wehage & Haug's coordinate
/// partitioning), in positions and in each derivative block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Dependents {
    indices: [usize; MOST_DEPENDENTS],
    len: usize,
}

impl Dependents {
    /// `None` for more than [`MOST_DEPENDENTS`].
    pub fn new(indices: &[usize]) -> Option<Dependents> {
        let len = indices.len();
        (len <= MOST_DEPENDENTS).then(|| {
            let mut all = [0; MOST_DEPENDENTS];
            all[..len].copy_from_slice(indices);
            Dependents { indices: all, len }
        })
    }

    pub fn as_slice(&self) -> &[usize] {
        &self.indices[..self.len]
    }
}

fn project_with(
    workspace: &mut Workspace,
    t: f64,
    x: &mut [f64],
    dependents: Option<Dependents>,
    (m, n, levels): (usize, usize, usize),
    constraint: &str,
    eval: ProjectFn,
) -> Result<(), Failure> {
    let Workspace {
        f,
        normals,
        gram,
        lambda,
        lu,
    } = workspace;
    // As new buffers would be: `f` zeros, `normals` m × n (zeroed before
    // every use), `gram` and `lambda` written before they are read.
    f.clear();
    f.resize(m, 0.0);
    if normals.rows() != m || normals.cols() != n {
        *normals = Matrix::zeros(m, n);
    }
    gram.resize(m * m, 0.0);
    let norm = |f: &[f64]| f.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let left = |residual: f64, singular: bool| {
        Failure::new(
            t,
            FailureKind::PositionsLeftConstraint {
                constraint: constraint.to_string(),
                residual,
                singular,
            },
        )
    };
    let dependents = dependents.filter(|d| d.len == m && d.as_slice().iter().all(|&j| j < n));
    // Solves (J Jᵀ) λ = f and moves block `r` of x by −Jᵀ λ; the largest
    // move, or None when J Jᵀ is singular. Partitioned: solves J_d δ = f
    // over the dependents' columns and moves them alone by −δ.
    let mut correct = |x: &mut [f64], r: usize, f: &[f64], normals: &Matrix| -> Option<f64> {
        if let Some(dependents) = &dependents {
            let d = dependents.as_slice();
            lambda.clear();
            lambda.extend_from_slice(f);
            lu.refactor(m, |a| {
                for i in 0..m {
                    for (c, &j) in d.iter().enumerate() {
                        a[(i, c)] = normals[(i, j)];
                    }
                }
            });
            // A singular dependent block: along the normals, below.
            if lu.solve_in_place(lambda) && lambda.iter().all(|v| v.is_finite()) {
                let mut largest = 0.0_f64;
                for (&j, delta) in d.iter().zip(lambda.iter()) {
                    x[r * n + j] -= delta;
                    largest = largest.max(delta.abs());
                }
                return Some(largest);
            }
        }
        for a in 0..m {
            for b in 0..m {
                gram[a * m + b] = (0..n).map(|j| normals[(a, j)] * normals[(b, j)]).sum();
            }
        }
        lambda.clear();
        lambda.extend_from_slice(f);
        // What `linalg::solve_dense` does, in kept storage.
        lu.refactor(m, |a| {
            for i in 0..m {
                for j in 0..m {
                    a[(i, j)] = gram[i * m + j];
                }
            }
        });
        if !(lu.solve_in_place(lambda) && lambda.iter().all(|v| v.is_finite())) {
            return None;
        }
        let mut largest = 0.0_f64;
        for j in 0..n {
            let delta: f64 = (0..m).map(|a| normals[(a, j)] * lambda[a]).sum();
            x[r * n + j] -= delta;
            largest = largest.max(delta.abs());
        }
        Some(largest)
    };
    let mut previous = f64::INFINITY;
    for step in 0..STEPS {
        normals.fill(0.0);
        eval(x, 0, f, normals);
        let residual = norm(f);
        if !residual.is_finite() {
            return Err(left(residual, false));
        }
        if residual == 0.0 {
            break;
        }
        let magnitude = x[..n].iter().fold(1.0_f64, |a, v| a.max(v.abs()));
        // Rounding: the residual no longer decreases.
        if step > 0 && !(residual < previous) {
            break;
        }
        previous = residual;
        let Some(moved) = correct(x, 0, f, normals) else {
            return Err(left(residual, true));
        };
        if moved <= 4.0 * f64::EPSILON * magnitude {
            break;
        }
        if step + 1 == STEPS {
            return Err(left(residual, false));
        }
    }
    normals.fill(0.0);
    eval(x, 0, f, normals);
    for r in 1..=levels {
        for _ in 0..2 {
            let mut unused = Matrix::zeros(0, 0);
            eval(x, r, f, &mut unused);
            if norm(f) == 0.0 {
                break;
            }
            if correct(x, r, f, normals).is_none() {
                return Err(left(norm(f), true));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_circle_is_reached_from_a_rough_start() {
        // x^2 + y^2 = 1 at x = 0.6, for y from -0.7.
        let mut z = [-0.7];
        let steps = solve(&mut z, &mut |z, f, jac| {
            f[0] = 0.36 + z[0] * z[0] - 1.0;
            jac[(0, 0)] = 2.0 * z[0];
        })
        .unwrap();
        assert!((z[0] + 0.8).abs() <= 1e-15, "{z:?} after {steps}");
    }

    #[test]
    fn no_root_is_reported() {
        let mut z = [0.5];
        let why = solve(&mut z, &mut |z, f, jac| {
            f[0] = z[0] * z[0] + 1.0;
            jac[(0, 0)] = 2.0 * z[0];
        })
        .unwrap_err();
        assert!(why.residual >= 1.0);
    }

    #[test]
    fn a_start_on_the_constraints_but_for_rounding_is_taken_where_the_jacobian_is_singular() {
        // A rod level with its dependent `y` (`f = x^2 + y^2 - l^2` at
        // y = 0): its Jacobian in `y` alone vanishes, and the residual that
        // `sin^2 + cos^2 - 1` leaves (1.7e-16 in a double pendulum's check)
        // is rounding: taken as it is, no step.
        let mut eval = |z: &[f64], f: &mut [f64], jac: &mut Matrix| {
            f[0] = 1.7e-16 + z[0] * z[0];
            jac[(0, 0)] = 2.0 * z[0];
        };
        let mut z = [0.0];
        assert_eq!(solve(&mut z, &mut eval), Ok(0));
        assert_eq!(z, [0.0]);
        // Off the constraints by more than rounding: refused, singular.
        let mut eval = |z: &[f64], f: &mut [f64], jac: &mut Matrix| {
            f[0] = 1e-6 + z[0] * z[0];
            jac[(0, 0)] = 2.0 * z[0];
        };
        let mut z = [0.0];
        assert!(solve(&mut z, &mut eval).is_err_and(|why| why.singular));
    }

    /// `x² + y² = 1` over the state `(x, y, x', y')`, and its derivative
    /// `2 (x x' + y y') = 0`, partitioned by `dependents`.
    fn circle(x: &mut [f64], dependents: Option<Dependents>) -> Result<(), Failure> {
        project(
            0.0,
            x,
            dependents,
            (1, 2, 1),
            "x^2 + y^2 = 1",
            &mut |s, level, f, normals| {
                if level == 0 {
                    f[0] = s[0] * s[0] + s[1] * s[1] - 1.0;
                    normals[(0, 0)] = 2.0 * s[0];
                    normals[(0, 1)] = 2.0 * s[1];
                } else {
                    f[0] = 2.0 * (s[0] * s[2] + s[1] * s[3]);
                }
            },
        )
    }

    #[test]
    fn a_partitioned_projection_keeps_the_independent_coordinates() {
        let start = [0.6, 0.81, 0.3, -0.2];
        // Partitioned with y dependent: x and x' kept, y and y' solved.
        let mut x = start;
        let y = Dependents::new(&[1]);
        circle(&mut x, y).unwrap();
        assert_eq!((x[0], x[2]), (start[0], start[2]));
        assert!((x[1] - 0.8).abs() <= 1e-15, "{x:?}");
        assert!((x[3] - (-0.6 * 0.3 / 0.8)).abs() <= 1e-15, "{x:?}");
        // Without dependents, and with dependents that are not one per
        // constraint, along the normals (every component moved), the
        // same bits both ways.
        let mut normal = start;
        circle(&mut normal, None).unwrap();
        assert!(normal[0] != start[0] && normal[2] != start[2]);
        let mut two = start;
        circle(&mut two, Dependents::new(&[0, 1])).unwrap();
        assert_eq!(two.map(f64::to_bits), normal.map(f64::to_bits));
        // A singular dependent block (y dependent at y = 0): along the
        // normals too.
        let level = [1.01, 0.0, 0.0, 0.5];
        let (mut a, mut b) = (level, level);
        circle(&mut a, y).unwrap();
        circle(&mut b, None).unwrap();
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
        // The partition is the call's alone: a projection along the
        // normals after a partitioned one is the same as before it.
        let mut again = start;
        circle(&mut again, None).unwrap();
        assert_eq!(again.map(f64::to_bits), normal.map(f64::to_bits));
    }

    #[test]
    fn a_satisfied_constraint_at_a_singular_point_is_kept() {
        let mut z = [0.0];
        solve(&mut z, &mut |z, f, jac| {
            f[0] = z[0] * z[0];
            jac[(0, 0)] = 2.0 * z[0];
        })
        .unwrap();
        assert_eq!(z[0], 0.0);
    }
}
