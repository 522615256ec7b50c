//! Which projection keeps the holonomic constraints: along their normals
//! (`closure::project`, the smallest correction), or partitioned — the
//! independent coordinates and their derivatives kept as integrated and
//! the mode's dependents solved from the constraints (Wehage & Haug) —
//! where the independent coordinates' highest derivatives are constant.
//!
//! Why that rule (docs/BENCHMARKS.md §10v): which projection keeps less
//! error depends on where the step's error lies. Where the independent
//! coordinates' highest derivatives are constant, the integrator moves
//! them exactly (a polynomial in t of degree u), so the whole error of a
//! step is in the dependents, and solving them from the exact independents
//! removes it; the projection along the normals hands the independents a
//! share of it instead. A bead sliding down a helical wire (its height
//! falls with constant acceleration) ended 11–30 rtol off by direct
//! integration along the normals, 0.00–4.4 rtol partitioned. Elsewhere
//! partitioning measured worse (a particle on a circle 20–550× by direct,
//! where its dependent's pivot is poor; a bead in a spinning tube 3–17×;
//! a cycloid 1.2–2.9×), and no measure of the pivots picks the helix out
//! (its dependent block is the poorer), so everywhere else the projection
//! stays along the normals.

use std::ops::Range;

use crate::closure::Dependents;
use crate::linalg::Matrix;
use crate::model::DynModel;

/// The dependents to solve for in the mode whose fixed components are
/// `fixed` (the dependent velocities, `velocities` the block they are in),
/// or `None` for the projection along the normals: every independent
/// coordinate's highest derivative has no partial and no time partial,
/// at `(t, x)` and at a second point moved off it (a partial that vanishes
/// at one point is no constant: a pendulum's at the horizontal).
pub(super) fn choose(
    model: &dyn DynModel,
    fixed: &[usize],
    velocities: Range<usize>,
    t: f64,
    x: &[f64],
) -> Option<Dependents> {
    if !model.keeps_positions() || fixed.is_empty() {
        return None;
    }
    // The dependent coordinates: the fixed velocities' indices among the
    // coordinates (a fixed component outside the velocity block, or one
    // of a velocity constraint beside the holonomic ones, leaves the
    // count unequal to the constraints', and `closure::project` ignores
    // the partition then).
    let mut dependents = Vec::with_capacity(fixed.len());
    for &j in fixed {
        if !velocities.contains(&j) {
            return None;
        }
        dependents.push(j - velocities.start);
    }
    let independent: Vec<usize> = velocities.clone().filter(|j| !fixed.contains(j)).collect();
    if independent.is_empty() {
        return None;
    }
    let n = model.dim();
    let mut moved = x.to_vec();
    for (i, v) in moved.iter_mut().enumerate() {
        // Deterministic, different for every component, of the state's
        // size.
        let phase = (0.618_033_988_75 * (i + 1) as f64).fract();
        *v += (0.25 + phase) * v.abs().max(1.0);
    }
    let mut jacobian = Matrix::zeros(n, n);
    let mut time_partial = vec![0.0; n];
    for (t, x) in [(t, x), (t + 0.375, &moved[..])] {
        jacobian.fill(0.0);
        time_partial.fill(0.0);
        if model.jacobian(t, x, &mut jacobian).is_err()
            || model.time_partial(t, x, &mut time_partial).is_err()
        {
            return None;
        }
        let constant = independent
            .iter()
            .all(|&j| time_partial[j] == 0.0 && (0..n).all(|c| jacobian[(j, c)] == 0.0));
        if !constant {
            return None;
        }
    }
    Dependents::new(&dependents)
}
