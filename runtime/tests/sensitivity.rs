//! The library's forward sensitivities (`api::solve_sensitivity`) on a
//! hand-written model with a closed form, `x' = −a x²` (non-linear, so `J`
//! moves along the motion): `x = x0/(1 + a x0 t)`, `∂x/∂x0 = 1/(1 + a x0
//! t)²`, `∂x/∂a = −x0² t/(1 + a x0 t)²`; by DOP853 and by RODAS4 (whose
//! Jacobian of the augmented system holds the variational equations'
//! second derivatives).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use lagc_runtime::api::solve_sensitivity;
use lagc_runtime::failure::Failure;
use lagc_runtime::linalg::Matrix;
use lagc_runtime::method::IntegratorChoice;
use lagc_runtime::model::{DynModel, Initial, Model};
use lagc_runtime::run::options::Options;
use lagc_runtime::run::sensitivity::Augmented;

/// The system allocator, counting this thread's allocations (the tests
/// run on threads of their own).
struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|n| n.set(n.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static COUNTING: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

#[derive(Clone, Debug)]
struct Decay {
    params: Vec<f64>,
}

impl Model for Decay {
    const NAME: &'static str = "decay";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &["a"];
    const STATE: &'static [&'static str] = &["x"];
    const COORDINATES: usize = 1;
    const INITIAL: &'static [Initial] = &[Initial::Given];
    const PARAM_JACOBIAN: bool = true;

    fn parameters(overrides: &[Option<f64>]) -> Vec<f64> {
        vec![overrides.first().copied().flatten().unwrap_or(0.5)]
    }
    fn new(params: &[f64]) -> Self {
        Decay {
            params: params.to_vec(),
        }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, 4.0)
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(vec![given.first().copied().flatten().unwrap_or(2.0)])
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = -self.params[0] * x[0] * x[0];
        Ok(())
    }
    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        jac[(0, 0)] = -2.0 * self.params[0] * x[0];
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn param_jacobian(&self, _t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        jac[(0, 0)] = -x[0] * x[0];
        Ok(())
    }
}

#[test]
fn sensitivities_meet_the_closed_form_by_both_integrators() {
    for choice in [IntegratorChoice::Explicit, IntegratorChoice::Stiff] {
        let options = Options::default()
            .rtol(1e-10)
            .atol(1e-12)
            .integrator(choice);
        let mut model = Decay::new(&[0.5]);
        let found = solve_sensitivity(&mut model, &[None], &options).unwrap();
        assert_eq!(found.columns, ["x0", "a"]);
        let (a, x0) = (0.5, 2.0);
        let mut worst = 0.0_f64;
        for k in 0..=40 {
            let t = 0.1 * k as f64;
            let (x, s) = found.at(t);
            let d = 1.0 + a * x0 * t;
            worst = worst
                .max((x[0] - x0 / d).abs())
                .max((s[0] - 1.0 / (d * d)).abs())
                .max((s[1] + x0 * x0 * t / (d * d)).abs());
        }
        assert!(worst < 1e-8, "{choice:?}: {worst:e}");
    }
}

/// The augmented right side runs a dozen times a step: it reuses its `J`
/// and `∂X/∂p` buffers (allocating them each call was a third of the
/// bouncing ball's `--sensitivity` run, docs/BENCHMARKS.md §15b). Its
/// values: `x' = −a x²`, `S' = J S + ∂X/∂p` with `J = −2 a x`, `∂X/∂a = −x²`.
#[test]
fn the_augmented_right_side_allocates_nothing() {
    let augmented = Augmented::new(Box::new(Decay::new(&[0.5])), vec![1.0]);
    let z = [2.0, 0.3, -0.7];
    let mut dz = [0.0; 3];
    augmented.rhs(0.0, &z, &mut dz).unwrap();
    let before = allocations();
    for _ in 0..100 {
        augmented.rhs(0.0, &z, &mut dz).unwrap();
    }
    assert_eq!(allocations() - before, 0);
    assert_eq!(dz, [-2.0, -2.0 * 0.3, -2.0 * -0.7 - 4.0]);
}
