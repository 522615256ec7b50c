//! Steps allocate nothing: a direct run on a constrained model (the
//! keeper measuring the residual after every step, projecting after some,
//! projecting every sample) allocates its buffers when it starts and none
//! per step (a copy of the state a step was a tenth of the paper's
//! instructions with malloc and free, docs/BENCHMARKS.md §10f).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use lagc_runtime::failure::Failure;
use lagc_runtime::integration::Integration;
use lagc_runtime::linalg::Matrix;
use lagc_runtime::method::Method;
use lagc_runtime::model::{Initial, Model};
use lagc_runtime::output::sample_times;
use lagc_runtime::run::options::Options;
use lagc_runtime::tolerance::Tolerance;

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

/// A bead on the curve y = e^(−x) whose constraint is written through the
/// dependent coordinate, `y' = −y x'` (runtime/tests/keep.rs): its
/// residual grows along the motion, so the keeper projects after steps as
/// well as measuring.
#[derive(Clone, Debug)]
struct Bead;

impl Model for Bead {
    const NAME: &'static str = "bead";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &[];
    const STATE: &'static [&'static str] = &["x", "y", "x'", "y'"];
    const COORDINATES: usize = 2;
    const INITIAL: &'static [Initial] = &[
        Initial::Given,
        Initial::Given,
        Initial::Given,
        Initial::Constraint,
    ];
    const KEEPS_CONSTRAINTS: bool = true;

    fn parameters(_overrides: &[Option<f64>]) -> Vec<f64> {
        Vec::new()
    }
    fn new(_params: &[f64]) -> Self {
        Bead
    }
    fn param_values(&self) -> &[f64] {
        &[]
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, 16.0)
    }
    fn initial_state(&self, _given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(vec![0.0, 1.0, 1.0, -1.0])
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        let (y, v) = (x[1], x[2]);
        dx[0] = x[2];
        dx[1] = x[3];
        dx[2] = y * y * v * v / (1.0 + y * y);
        dx[3] = y * v * v / (1.0 + y * y);
        Ok(())
    }
    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        let (y, v) = (x[1], x[2]);
        let s = 1.0 + y * y;
        jac[(0, 2)] = 1.0;
        jac[(1, 3)] = 1.0;
        jac[(2, 1)] = 2.0 * y * v * v / (s * s);
        jac[(2, 2)] = 2.0 * y * y * v / s;
        jac[(3, 1)] = v * v * (1.0 - y * y) / (s * s);
        jac[(3, 2)] = 2.0 * y * v / s;
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn constrained(&self, _t: f64, x: &[f64], kept: &mut [f64]) -> Result<(), Failure> {
        kept[3] = -x[1] * x[2];
        Ok(())
    }
    fn kept_gradient(&self, _t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        jac[(3, 2)] = -x[1];
        Ok(())
    }
}

/// The allocations of advancing from the first sample to the last (the
/// first advance starts the run and allocates its buffers), the steps
/// taken and the projections after steps.
fn allocations_past_the_start(rtol: f64) -> (usize, usize, usize) {
    let mut model = Bead;
    let x0 = model.initial_state(&[]).unwrap();
    let options = Options {
        method: Method::Direct,
        tol: Tolerance {
            rtol,
            atol: rtol / 100.0,
        },
        ..Options::default()
    };
    let times = sample_times(0.0, 16.0, 161);
    let mut run = Integration::new(&mut model, &options, 0.0, 16.0, &x0);
    run.advance_to(times[1]).unwrap();
    let before = allocations();
    for &t in &times[2..] {
        run.advance_to(t).unwrap();
    }
    let during = allocations() - before;
    let outcome = run.finish().unwrap();
    let kept = outcome
        .kept
        .expect("a model that keeps constraints reports them");
    (
        during,
        outcome.report.stats.accepted_steps,
        kept.projections,
    )
}

#[test]
fn a_direct_run_on_a_constrained_model_allocates_nothing_per_step() {
    for rtol in [1e-4, 1e-8, 1e-11] {
        let (during, steps, projections) = allocations_past_the_start(rtol);
        eprintln!("rtol {rtol:e}: {steps} steps, {projections} projections, {during} allocations");
        // The check can fail: the run steps, and the keeper projects.
        assert!(steps > 10, "rtol {rtol:e}: only {steps} steps");
        assert_eq!(
            during, 0,
            "rtol {rtol:e}: {during} allocations in {steps} steps"
        );
    }
}
