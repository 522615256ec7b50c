//! The projection onto one velocity constraint (no holonomic ones): the
//! usual case, and every projected sample of the paper and the knife edge.
//! [`Keeper::project_general`]'s Gauss–Newton with `m = 1`, written for it:
//! the same operations in the same order (a sum of one term is that term,
//! `Sum` for f64 starting at −0.0), so the same bits; its normal read once
//! into the stack and only the partials it reads zeroed. The general form
//! was about 700 instructions a projected sample of the paper, most of it
//! the general solve's indexing and live state (docs/BENCHMARKS.md §10m).
//! `the projection onto one constraint is the general one bit for bit`
//! checks the two against each other.

use super::{left, settled, Keeper, BROKEN_ABOVE, BROKEN_TIMES_TOLERANCE, ITERATIONS};
use crate::failure::{Failure, FailureKind};
use crate::model::DynModel;

/// The most velocities whose normal is held on the stack; more take the
/// general path.
const NORMALS: usize = 16;

/// Whether [`Keeper::project_one`] projects for `keeper` in its current
/// mode (its fixed components known).
pub(super) fn applies(keeper: &Keeper, model: &dyn DynModel) -> bool {
    keeper.fixed.len() == 1 && keeper.velocities.len() <= NORMALS && !model.keeps_positions()
}

impl Keeper {
    /// [`Keeper::project_from`] when [`applies`]: the same result, distance
    /// recorded and failures. Compiled for two and three velocities (the
    /// paper's, the knife edge's) as DOP853's step is for small states: the
    /// loops over the velocities unrolled, their bounds checks gone (the
    /// same operations in the same order at every size, so the same bits).
    pub(super) fn project_one(
        &mut self,
        model: &dyn DynModel,
        t: f64,
        x: &[f64],
        judged: bool,
        bounded: bool,
    ) -> Result<f64, Failure> {
        match self.velocities.len() {
            2 => self.project_one_sized::<2>(model, t, x, judged, bounded),
            3 => self.project_one_sized::<3>(model, t, x, judged, bounded),
            _ => self.project_one_sized::<0>(model, t, x, judged, bounded),
        }
    }

    /// The first measure of [`Keeper::project_one`] with `bounded`, alone:
    /// `Some(distance)`, recorded, when the state's residual bounds its
    /// distance below `PROJECT_ABOVE` (`settled`), as `project_one` would
    /// return it; else `None`, and `project_one` measures again (the same
    /// right side of the constraint on the same state, so the same
    /// residual) and projects, or names the failure (a constraint that
    /// fails or is not finite here is left to it).
    pub(super) fn settled_one(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Option<f64> {
        match self.velocities.len() {
            2 => self.settled_one_sized::<2>(model, t, x),
            3 => self.settled_one_sized::<3>(model, t, x),
            _ => self.settled_one_sized::<0>(model, t, x),
        }
    }

    /// [`Keeper::settled_one`] for `N` velocities (`N = 0`: any number).
    #[inline(always)]
    fn settled_one_sized<const N: usize>(
        &mut self,
        model: &dyn DynModel,
        t: f64,
        x: &[f64],
    ) -> Option<f64> {
        let Keeper {
            tol,
            fixed,
            velocities,
            states,
            largest,
            largest_absolute,
            largest_at,
            ..
        } = self;
        let j = fixed[0];
        let half = states.len() / 2;
        let kept = &mut states[..half];
        // As `project_one` starts its first iteration (its projected state
        // is a copy of `x`).
        kept[j] = x[j];
        model.constrained(t, x, kept).ok()?;
        if !kept[j].is_finite() {
            return None;
        }
        let residual = [x[j] - kept[j]];
        let record = (largest, largest_absolute, largest_at);
        let first = velocities.start;
        let count = if N == 0 { velocities.len() } else { N };
        settled(
            &residual,
            first..first + count,
            x,
            tol,
            (0.0, 0.0),
            t,
            record,
        )
    }

    /// [`Keeper::project_one`] for `N` velocities (`N = 0`: any number up
    /// to [`NORMALS`], read at run time).
    #[inline(always)]
    fn project_one_sized<const N: usize>(
        &mut self,
        model: &dyn DynModel,
        t: f64,
        x: &[f64],
        judged: bool,
        bounded: bool,
    ) -> Result<f64, Failure> {
        let Keeper {
            tol,
            fixed,
            velocities,
            states,
            gradient,
            largest,
            largest_absolute,
            largest_at,
            ..
        } = self;
        let fixed: &[usize] = fixed;
        let j = fixed[0];
        let first = velocities.start;
        let count = if N == 0 { velocities.len() } else { N };
        let half = states.len() / 2;
        let (kept, projected) = states.split_at_mut(half);
        projected.copy_from_slice(x);
        // No holonomic constraint: the general path's correction of them.
        let closure = (0.0_f64, 0.0_f64);
        let mut distance: Option<(f64, f64)> = None;
        let mut last = (0.0_f64, 0.0_f64);
        let mut residual = [0.0_f64];
        for _ in 0..ITERATIONS {
            // The model writes the component it fixes and leaves the
            // others (`Model::constrained`), and only that one is read:
            // it alone starts as the state's (the whole state was copied,
            // a `memcpy` an iteration).
            kept[j] = projected[j];
            model.constrained(t, projected, kept)?;
            if !kept[j].is_finite() {
                return Err(Failure::new(
                    t,
                    FailureKind::ConstraintUndefined {
                        component: model.state_names()[j].to_string(),
                    },
                ));
            }
            residual[0] = projected[j] - kept[j];
            if bounded && distance.is_none() {
                let record = (&mut *largest, &mut *largest_absolute, &mut *largest_at);
                if let Some(relative) =
                    settled(&residual, velocities.clone(), x, tol, closure, t, record)
                {
                    return Ok(relative);
                }
            }
            // Only the partials read below need to start at zero: a
            // model's `kept_gradient` writes its non-zero cells alone.
            for k in 0..count {
                gradient[(j, first + k)] = 0.0;
            }
            model.kept_gradient(t, projected, gradient)?;
            // The normal J = e_j − ∂φ/∂v over the velocities; the smallest
            // correction is Δv = −Jᵀ h / (J Jᵀ).
            let mut normal = [0.0; NORMALS];
            let normal = &mut normal[..count];
            for (k, a) in normal.iter_mut().enumerate() {
                let i = first + k;
                *a = f64::from(u8::from(i == j)) - gradient[(j, i)];
            }
            let gram = normal.iter().map(|a| a * a).sum::<f64>();
            let lambda = residual[0] / gram;
            let solved = lambda.is_finite();
            let (mut relative, mut absolute) = (0.0_f64, 0.0_f64);
            let mut worst = j;
            let moved = &mut projected[first..first + count];
            for (k, (&a, p)) in normal.iter().zip(moved.iter_mut()).enumerate() {
                let i = first + k;
                let delta = if solved {
                    -(a * lambda)
                } else if i == j {
                    // A normal that vanishes: the dependent component
                    // takes its value.
                    -residual[0]
                } else {
                    0.0
                };
                let v = *p;
                *p = v + delta;
                let scale = tol.atol + tol.rtol * v.abs().max(p.abs());
                if delta.abs() / scale > relative {
                    worst = i;
                }
                relative = relative.max(delta.abs() / scale);
                absolute = absolute.max(delta.abs());
            }
            if distance.is_none() {
                let size = x[worst].abs().max(projected[worst].abs()).max(1.0);
                if judged && relative > BROKEN_TIMES_TOLERANCE && absolute > BROKEN_ABOVE * size {
                    return Err(left(model, fixed, t, &residual, absolute));
                }
                distance = Some((relative, absolute));
            }
            last = (relative, absolute);
            if relative <= 1e-3 {
                break;
            }
        }
        if last.0 > 1.0 {
            return Err(left(model, fixed, t, &residual, last.1));
        }
        let (relative, absolute) = distance.unwrap_or((0.0, 0.0));
        let (relative, absolute) = if closure.0 > relative {
            closure
        } else {
            (relative, absolute)
        };
        if judged && relative > *largest {
            *largest = relative;
            *largest_absolute = absolute;
            *largest_at = t;
        }
        Ok(relative)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{fixed_components, Keeper};
    use crate::failure::Failure;
    use crate::linalg::Matrix;
    use crate::model::{DynModel, Initial, Model};
    use crate::ode::tolerance::Tolerance;

    /// A bead whose one constraint is non-linear in the velocities and
    /// depends on `t` (`v' = t u − c u³ y`, three velocities), so that the
    /// Gauss–Newton takes several iterations; `c` large enough leaves the
    /// constraint (no point near a state far off it).
    #[derive(Clone, Debug)]
    struct Curved(f64);

    impl Model for Curved {
        const NAME: &'static str = "curved";
        const SOURCE_HASH: &'static str = "test";
        const PARAMS: &'static [&'static str] = &["c"];
        const STATE: &'static [&'static str] = &["y", "z", "w", "u", "v", "s"];
        const COORDINATES: usize = 3;
        const INITIAL: &'static [Initial] = &[
            Initial::Given,
            Initial::Given,
            Initial::Given,
            Initial::Given,
            Initial::Constraint,
            Initial::Given,
        ];
        const KEEPS_CONSTRAINTS: bool = true;

        fn parameters(overrides: &[Option<f64>]) -> Vec<f64> {
            vec![overrides.first().copied().flatten().unwrap_or(0.3)]
        }
        fn new(params: &[f64]) -> Self {
            Curved(params[0])
        }
        fn param_values(&self) -> &[f64] {
            std::slice::from_ref(&self.0)
        }
        fn time_span(&self) -> (f64, f64) {
            (0.0, 1.0)
        }
        fn initial_state(&self, _given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
            Ok(vec![0.5, 0.0, 0.0, 1.0, 0.0, 0.2])
        }
        fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
            dx[..3].copy_from_slice(&x[3..]);
            dx[3..].fill(0.0);
            Ok(())
        }
        fn jacobian(&self, _t: f64, _x: &[f64], _jac: &mut Matrix) -> Result<(), Failure> {
            Ok(())
        }
        fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
            Ok(())
        }
        fn constrained(&self, t: f64, x: &[f64], kept: &mut [f64]) -> Result<(), Failure> {
            let (y, u) = (x[0], x[3]);
            kept[4] = t * u - self.0 * u * u * u * y;
            Ok(())
        }
        fn kept_gradient(&self, t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
            let (y, u) = (x[0], x[3]);
            jac[(4, 3)] = t - 3.0 * self.0 * u * u * y;
            Ok(())
        }
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// Every state of a grid (on, near and far off the constraint, and
    /// non-finite), measured and projected, judged or not, by the path for
    /// one constraint and by the general one from the same keeper: the
    /// same distance (bits), the same projected state and record, the
    /// same failures.
    #[test]
    fn the_projection_onto_one_constraint_is_the_general_one_bit_for_bit() {
        let mut compared = (0, 0, 0);
        for c in [0.3, 40.0] {
            let model = Curved(c);
            let dyn_model: &dyn DynModel = &model;
            let tol = Tolerance {
                rtol: 1e-6,
                atol: 1e-8,
            };
            let mut keeper = Keeper::new(dyn_model, tol).expect("a model that keeps");
            fixed_components(dyn_model, 0, &mut keeper.fixed);
            keeper.mode = Some(0);
            assert!(super::applies(&keeper, dyn_model));
            for (k, off) in [0.0, 1e-15, 1e-9, 3e-7, 1e-4, 0.3, 5.0, f64::NAN]
                .into_iter()
                .enumerate()
            {
                for u in [-1.7_f64, 0.0, 0.9, 2.5] {
                    let t = 0.25 * k as f64;
                    let mut x = [0.5, -0.1, 0.3, u, 0.0, 0.2 - 0.1 * u];
                    let mut on = x;
                    dyn_model.constrained(t, &x, &mut on).unwrap();
                    x[4] = on[4] + off * (1.0 + u.abs());
                    for (judged, bounded) in [(true, true), (true, false), (false, false)] {
                        let mut general = keeper.clone();
                        let b = general.project_general(dyn_model, t, &x, judged, bounded);
                        // The sized path (three velocities), the path for
                        // any number, and the measure after a step
                        // (`settled_one` first when bounded), each against
                        // the general projection.
                        for path in 0..3 {
                            let mut one = keeper.clone();
                            let a = match path {
                                0 => one.project_one(dyn_model, t, &x, judged, bounded),
                                1 => one.project_one_sized::<0>(dyn_model, t, &x, judged, bounded),
                                _ if judged && bounded => {
                                    // What the run reads after a step:
                                    // the projected state past
                                    // `PROJECT_ABOVE`, else nothing.
                                    let after =
                                        one.after_step(dyn_model, 0, t, &x).map(|p| p.map(bits));
                                    let expected = b.as_ref().map(|&d| {
                                        (d > super::super::PROJECT_ABOVE)
                                            .then(|| bits(general.projected()))
                                    });
                                    assert_eq!(format!("{after:?}"), format!("{expected:?}"));
                                    let (ka, kb) = (one.kept(), general.kept());
                                    assert_eq!(ka.largest.to_bits(), kb.largest.to_bits());
                                    assert_eq!(ka.largest_at.to_bits(), kb.largest_at.to_bits());
                                    compared.2 += 1;
                                    continue;
                                }
                                _ => continue,
                            };
                            match (&a, &b) {
                                (Ok(a), Ok(b)) => {
                                    assert_eq!(a.to_bits(), b.to_bits(), "distance at {x:?}");
                                    assert_eq!(bits(one.projected()), bits(general.projected()));
                                    compared.0 += 1;
                                }
                                _ => {
                                    assert_eq!(format!("{a:?}"), format!("{b:?}"), "at {x:?}");
                                    compared.1 += 1;
                                }
                            }
                            let (ka, kb) = (one.kept(), general.kept());
                            assert_eq!(ka.largest.to_bits(), kb.largest.to_bits());
                            assert_eq!(
                                ka.largest_absolute.to_bits(),
                                kb.largest_absolute.to_bits()
                            );
                            assert_eq!(ka.largest_at.to_bits(), kb.largest_at.to_bits());
                        }
                    }
                }
            }
        }
        // Both kinds of outcome were compared: projections and failures.
        assert!(
            compared.0 > 100 && compared.1 > 5 && compared.2 > 50,
            "{compared:?}"
        );
    }
}
