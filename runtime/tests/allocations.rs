//! Steps allocate nothing: a direct run on a constrained model (the
//! keeper measuring the residual after every step, projecting after some,
//! projecting every sample) allocates its buffers when it starts and none
//! per step (a copy of the state a step was a tenth of the paper's
//! instructions with malloc and free, docs/BENCHMARKS.md §10h).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use lagc_runtime::closure::ProjectFn;
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

/// Two such beads, on `y1 = e^(−x1)` and `y2 = e^(−x2)` at different
/// speeds: two constraints, whose Gram matrix is solved by LU.
#[derive(Clone, Debug)]
struct TwoBeads;

impl Model for TwoBeads {
    const NAME: &'static str = "two_beads";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &[];
    const STATE: &'static [&'static str] = &["x1", "y1", "x2", "y2", "x1'", "y1'", "x2'", "y2'"];
    const COORDINATES: usize = 4;
    const INITIAL: &'static [Initial] = &[
        Initial::Given,
        Initial::Given,
        Initial::Given,
        Initial::Given,
        Initial::Given,
        Initial::Constraint,
        Initial::Given,
        Initial::Constraint,
    ];
    const KEEPS_CONSTRAINTS: bool = true;

    fn parameters(_overrides: &[Option<f64>]) -> Vec<f64> {
        Vec::new()
    }
    fn new(_params: &[f64]) -> Self {
        TwoBeads
    }
    fn param_values(&self) -> &[f64] {
        &[]
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, 16.0)
    }
    fn initial_state(&self, _given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(vec![0.0, 1.0, 0.0, 1.0, 1.0, -1.0, 0.5, -0.5])
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        for b in 0..2 {
            let (y, v) = (x[2 * b + 1], x[4 + 2 * b]);
            dx[2 * b] = x[4 + 2 * b];
            dx[2 * b + 1] = x[5 + 2 * b];
            dx[4 + 2 * b] = y * y * v * v / (1.0 + y * y);
            dx[5 + 2 * b] = y * v * v / (1.0 + y * y);
        }
        Ok(())
    }
    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        for b in 0..2 {
            let (y, v) = (x[2 * b + 1], x[4 + 2 * b]);
            let s = 1.0 + y * y;
            let (q, r) = (2 * b, 4 + 2 * b);
            jac[(q, r)] = 1.0;
            jac[(q + 1, r + 1)] = 1.0;
            jac[(r, q + 1)] = 2.0 * y * v * v / (s * s);
            jac[(r, r)] = 2.0 * y * y * v / s;
            jac[(r + 1, q + 1)] = v * v * (1.0 - y * y) / (s * s);
            jac[(r + 1, r)] = 2.0 * y * v / s;
        }
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn constrained(&self, _t: f64, x: &[f64], kept: &mut [f64]) -> Result<(), Failure> {
        kept[5] = -x[1] * x[4];
        kept[7] = -x[3] * x[6];
        Ok(())
    }
    fn kept_gradient(&self, _t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        jac[(5, 4)] = -x[1];
        jac[(7, 6)] = -x[3];
        Ok(())
    }
}

/// The allocations of advancing from the first sample to the last (the
/// first advance starts the run and allocates its buffers), the steps
/// taken and the projections after steps.
fn allocations_past_the_start<M: Model + 'static>(
    mut model: M,
    rtol: f64,
) -> (usize, usize, usize) {
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
        for (name, (during, steps, projections)) in [
            ("bead", allocations_past_the_start(Bead, rtol)),
            ("two beads", allocations_past_the_start(TwoBeads, rtol)),
        ] {
            eprintln!(
                "{name}, rtol {rtol:e}: {steps} steps, {projections} projections, {during} allocations"
            );
            // The check can fail: the run steps, and the keeper projects.
            assert!(steps > 10, "{name}, rtol {rtol:e}: only {steps} steps");
            assert!(projections > 0, "{name}, rtol {rtol:e}: no projection");
            assert_eq!(
                during, 0,
                "{name}, rtol {rtol:e}: {during} allocations in {steps} steps"
            );
        }
    }
}

/// The projection onto holonomic constraints (`closure::project`, which a
/// holonomic model's keeper calls after every step and at every output)
/// reuses its buffers from call to call: two circles, `q1² + q2² = 1` and
/// `q3² + q4² = 4`, their velocities onto `D f = 0`, from states off both.
#[test]
fn the_projection_onto_holonomic_constraints_allocates_nothing_after_its_first_call() {
    let mut eval = |x: &[f64], level: usize, f: &mut [f64], normals: &mut Matrix| {
        for c in 0..2 {
            let (q, v) = (&x[2 * c..2 * c + 2], &x[4 + 2 * c..4 + 2 * c + 2]);
            if level == 0 {
                f[c] = q[0] * q[0] + q[1] * q[1] - [1.0, 4.0][c];
                normals[(c, 2 * c)] = 2.0 * q[0];
                normals[(c, 2 * c + 1)] = 2.0 * q[1];
            } else {
                f[c] = 2.0 * (q[0] * v[0] + q[1] * v[1]);
            }
        }
    };
    let project = |eval: ProjectFn<'_>, k: usize| {
        let s = 1e-3 * k as f64;
        let mut x = [0.6 + s, 0.8, 1.2, 1.6 - s, 0.8, -0.6 + s, 1.6, -1.2];
        lagc_runtime::closure::project(0.0, &mut x, None, (2, 4, 1), "circles", eval).unwrap();
        x
    };
    // A first call off the constraints (one on them solves nothing).
    project(&mut eval, 1);
    let before = allocations();
    let mut off = 0.0_f64;
    for k in 2..=100 {
        let x = project(&mut eval, k);
        off = off
            .max((x[0] * x[0] + x[1] * x[1] - 1.0).abs())
            .max((x[2] * x[2] + x[3] * x[3] - 4.0).abs())
            .max((x[0] * x[4] + x[1] * x[5]).abs());
    }
    assert_eq!(allocations() - before, 0);
    // The projections did their work: the states started 2e-3 … 0.1 off.
    assert!(off < 1e-12, "off the constraints by {off:e}");
}
