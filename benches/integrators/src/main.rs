//! Measurement: lagc's own DOP853/RODAS4 vs differential-equations 0.7.
#[path = "../../../src/emit/runtime/mod.rs"]
#[allow(dead_code, unused_imports)]
mod runtime;

use differential_equations::linalg::matrix::Matrix;
use differential_equations::prelude::*;
use nalgebra::DMatrix;
use runtime::direct::solve_direct;
use runtime::error::Failure;
use runtime::method::Integrator;
use runtime::stepper::Tolerance;
use runtime::system::Motion;
use std::cell::Cell;
use std::time::Instant;

/// A test problem, written once, adapted to both libraries.
trait Problem<const N: usize> {
    const NAME: &'static str;
    fn t_end(&self) -> f64;
    fn x0(&self) -> [f64; N];
    fn f(&self, t: f64, x: &[f64], dx: &mut [f64]);
    fn jac(&self, t: f64, x: &[f64], j: &mut [[f64; N]; N]);
    fn dfdt(&self, t: f64, x: &[f64], d: &mut [f64]);
}

struct Paper {
    alpha: f64,
}
impl Problem<4> for Paper {
    const NAME: &'static str = "paper";
    fn t_end(&self) -> f64 {
        5.0
    }
    fn x0(&self) -> [f64; 4] {
        [0.0, 0.0, 1.0, 0.0]
    }
    fn f(&self, t: f64, x: &[f64], dx: &mut [f64]) {
        let p = self.alpha - t / (1.0 + t * t);
        let r = self.alpha * t + 1.0 / (1.0 + t * t);
        dx[0] = x[2];
        dx[1] = x[3];
        dx[2] = p * x[2];
        dx[3] = r * x[2];
    }
    fn jac(&self, t: f64, _x: &[f64], j: &mut [[f64; 4]; 4]) {
        j[0][2] = 1.0;
        j[1][3] = 1.0;
        j[2][2] = self.alpha - t / (1.0 + t * t);
        j[3][2] = self.alpha * t + 1.0 / (1.0 + t * t);
    }
    fn dfdt(&self, t: f64, x: &[f64], d: &mut [f64]) {
        d[2] = -(1.0 - t * t) / (1.0 + t * t).powi(2) * x[2];
        d[3] = (self.alpha - 2.0 * t / (1.0 + t * t).powi(2)) * x[2];
    }
}

struct Oscillator;
impl Problem<2> for Oscillator {
    const NAME: &'static str = "oscillator";
    fn t_end(&self) -> f64 {
        100.0
    }
    fn x0(&self) -> [f64; 2] {
        [1.0, 0.0]
    }
    fn f(&self, _t: f64, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = -x[0];
    }
    fn jac(&self, _t: f64, _x: &[f64], j: &mut [[f64; 2]; 2]) {
        j[0][1] = 1.0;
        j[1][0] = -1.0;
    }
    fn dfdt(&self, _t: f64, _x: &[f64], _d: &mut [f64]) {}
}

/// y' = -1000 (y - cos t) - sin t, y(0) = 1: y = cos t.
struct StiffLinear;
impl Problem<1> for StiffLinear {
    const NAME: &'static str = "stiff-linear";
    fn t_end(&self) -> f64 {
        10.0
    }
    fn x0(&self) -> [f64; 1] {
        [1.0]
    }
    fn f(&self, t: f64, x: &[f64], dx: &mut [f64]) {
        dx[0] = -1000.0 * (x[0] - t.cos()) - t.sin();
    }
    fn jac(&self, _t: f64, _x: &[f64], j: &mut [[f64; 1]; 1]) {
        j[0][0] = -1000.0;
    }
    fn dfdt(&self, t: f64, _x: &[f64], d: &mut [f64]) {
        d[0] = -1000.0 * t.sin() - t.cos();
    }
}

/// MATLAB's vdp1000: y1' = y2, y2' = mu (1 - y1^2) y2 - y1, y(0) = (2, 0).
struct VanDerPol {
    mu: f64,
}
impl Problem<2> for VanDerPol {
    const NAME: &'static str = "vdp-1000";
    fn t_end(&self) -> f64 {
        3000.0
    }
    fn x0(&self) -> [f64; 2] {
        [2.0, 0.0]
    }
    fn f(&self, _t: f64, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = self.mu * (1.0 - x[0] * x[0]) * x[1] - x[0];
    }
    fn jac(&self, _t: f64, x: &[f64], j: &mut [[f64; 2]; 2]) {
        j[0][1] = 1.0;
        j[1][0] = -2.0 * self.mu * x[0] * x[1] - 1.0;
        j[1][1] = self.mu * (1.0 - x[0] * x[0]);
    }
    fn dfdt(&self, _t: f64, _x: &[f64], _d: &mut [f64]) {}
}

/// Adapter with an independent call counter.
struct Counted<'a, P, const N: usize> {
    p: &'a P,
    calls: Cell<usize>,
}

impl<'a, P: Problem<N>, const N: usize> Motion for Counted<'a, P, N> {
    fn dim(&self) -> usize {
        N
    }
    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        self.calls.set(self.calls.get() + 1);
        self.p.f(t, x, dx);
        Ok(())
    }
    fn jacobian(&self, t: f64, x: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        let mut j = [[0.0; N]; N];
        self.p.jac(t, x, &mut j);
        for r in 0..N {
            for c in 0..N {
                jac[(r, c)] = j[r][c];
            }
        }
        Ok(())
    }
    fn time_partial(&self, t: f64, x: &[f64], d: &mut [f64]) -> Result<(), Failure> {
        self.p.dfdt(t, x, d);
        Ok(())
    }
}

impl<'a, P: Problem<N>, const N: usize> ODE<f64, [f64; N]> for Counted<'a, P, N> {
    fn diff(&self, t: f64, y: &[f64; N], dydt: &mut [f64; N]) {
        self.calls.set(self.calls.get() + 1);
        self.p.f(t, y, dydt);
    }
    fn jacobian(&self, t: f64, y: &[f64; N], m: &mut Matrix<f64>) {
        let mut j = [[0.0; N]; N];
        self.p.jac(t, y, &mut j);
        for r in 0..N {
            for c in 0..N {
                m[(r, c)] = j[r][c];
            }
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Solver {
    OursDop853,
    OursRodas4,
    TheirsDop853,
    TheirsRadau5,
    TheirsKvaerno745,
    TheirsBdf,
}

struct Outcome {
    samples: Vec<(f64, Vec<f64>)>,
    accepted: usize,
    rejected: usize,
    lib_evals: usize,
    counted_evals: usize,
    jac: usize,
}

const MAX_STEPS: usize = 20_000_000;

fn run<P: Problem<N>, const N: usize>(
    p: &P,
    solver: Solver,
    rtol: f64,
    times: &[f64],
) -> Result<Outcome, String> {
    let atol = rtol * 1e-2;
    let sys: Counted<P, N> = Counted {
        p,
        calls: Cell::new(0),
    };
    let x0 = p.x0();
    let (t0, t1) = (times[0], *times.last().unwrap());
    let theirs = |sol: Result<Solution<f64, [f64; N]>, _>| -> Result<Outcome, String> {
        let sol: Solution<f64, [f64; N]> = sol.map_err(|e: differential_equations::error::Error<f64, [f64; N]>| format!("{e:?}"))?;
        Ok(Outcome {
            samples: sol.t.iter().zip(&sol.y).map(|(t, y)| (*t, y.to_vec())).collect(),
            accepted: sol.steps.accepted,
            rejected: sol.steps.rejected,
            lib_evals: sol.evals.function,
            counted_evals: sys.calls.get(),
            jac: sol.evals.jacobian,
        })
    };
    let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match solver {
        Solver::OursDop853 | Solver::OursRodas4 => {
            let integ = if solver == Solver::OursDop853 {
                Integrator::Explicit
            } else {
                Integrator::Stiff
            };
            let mut samples = Vec::with_capacity(times.len());
            let stats = solve_direct(&sys, integ, Tolerance { rtol, atol }, times, &x0, |t, x| {
                samples.push((t, x.to_vec()))
            })
            .map_err(|e| e.to_string())?;
            Ok(Outcome {
                samples,
                accepted: stats.accepted_steps,
                rejected: stats.rejected_steps,
                lib_evals: stats.rhs_evaluations,
                counted_evals: sys.calls.get(),
                jac: stats.jacobian_evaluations,
            })
        }
        Solver::TheirsDop853 => theirs(
            IVP::ode(&sys, t0, t1, x0)
                .t_eval(times)
                .method(ExplicitRungeKutta::dop853().rtol(rtol).atol(atol).max_steps(MAX_STEPS))
                .solve(),
        ),
        Solver::TheirsRadau5 => theirs(
            IVP::ode(&sys, t0, t1, x0)
                .t_eval(times)
                .method(ImplicitRungeKutta::radau5().rtol(rtol).atol(atol).max_steps(MAX_STEPS))
                .solve(),
        ),
        Solver::TheirsKvaerno745 => theirs(
            IVP::ode(&sys, t0, t1, x0)
                .t_eval(times)
                .method(
                    DiagonallyImplicitRungeKutta::kvaerno745()
                        .rtol(rtol)
                        .atol(atol)
                        .max_steps(MAX_STEPS),
                )
                .solve(),
        ),
        Solver::TheirsBdf => theirs(
            IVP::ode(&sys, t0, t1, x0)
                .t_eval(times)
                .method(
                    BackwardDifferentiationFormula::adaptive()
                        .rtol(rtol)
                        .atol(atol)
                        .max_steps(MAX_STEPS),
                )
                .solve(),
        ),
    }));
    match caught {
        Ok(r) => r,
        Err(e) => Err(format!(
            "PANIC: {}",
            e.downcast_ref::<String>()
                .cloned()
                .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default()
        )),
    }
}

/// Largest |x - exact| / max(|exact|, 1) over samples and components,
/// plus a check that the samples are at the requested times.
fn max_error(samples: &[(f64, Vec<f64>)], times: &[f64], exact: &dyn Fn(f64) -> Vec<f64>) -> Result<f64, String> {
    if samples.len() != times.len() {
        return Err(format!("{} samples, expected {}", samples.len(), times.len()));
    }
    let mut worst = 0.0_f64;
    for ((t, x), &tt) in samples.iter().zip(times) {
        if (t - tt).abs() > 1e-12 * tt.abs().max(1.0) {
            return Err(format!("sample at {t}, expected {tt}"));
        }
        let e = exact(tt);
        for (a, b) in x.iter().zip(&e) {
            worst = worst.max((a - b).abs() / b.abs().max(1.0));
        }
    }
    Ok(worst)
}

fn simpson(g: &dyn Fn(f64) -> f64, a: f64, b: f64, ga: f64, gm: f64, gb: f64, whole: f64, tol: f64, depth: u32) -> f64 {
    let m = 0.5 * (a + b);
    let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
    let (glm, grm) = (g(lm), g(rm));
    let left = (m - a) / 6.0 * (ga + 4.0 * glm + gm);
    let right = (b - m) / 6.0 * (gm + 4.0 * grm + gb);
    let delta = left + right - whole;
    if depth == 0 || delta.abs() <= 15.0 * tol {
        return left + right + delta / 15.0;
    }
    simpson(g, a, m, ga, glm, gm, left, tol / 2.0, depth - 1) + simpson(g, m, b, gm, grm, gb, right, tol / 2.0, depth - 1)
}
fn integrate(g: &dyn Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    if a == b {
        return 0.0;
    }
    let (ga, gm, gb) = (g(a), g(0.5 * (a + b)), g(b));
    let whole = (b - a) / 6.0 * (ga + 4.0 * gm + gb);
    simpson(g, a, b, ga, gm, gb, whole, 1e-15, 50)
}

const SOLVERS: [Solver; 6] = [
    Solver::OursDop853,
    Solver::OursRodas4,
    Solver::TheirsDop853,
    Solver::TheirsRadau5,
    Solver::TheirsKvaerno745,
    Solver::TheirsBdf,
];

fn bench<P: Problem<N>, const N: usize>(p: &P, exact: &dyn Fn(f64) -> Vec<f64>, reps: usize, skip: &[Solver]) {
    let times: Vec<f64> = (0..=100).map(|i| p.t_end() * i as f64 / 100.0).collect();
    println!("\n### {}\n", P::NAME);
    println!("| rtol | solver | accepted | rejected | RHS evals (lib) | RHS calls (counted) | Jacobians | wall ms (min of {reps}) | max rel. error |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for rtol in [1e-6, 1e-8, 1e-10, 1e-12] {
        for s in SOLVERS {
            if skip.contains(&s) {
                println!("| {rtol:e} | {s:?} | skipped | | | | | | |");
                continue;
            }
            // warm-up run, also the one whose counts and errors are reported
            let first = run(p, s, rtol, &times);
            let o = match first {
                Err(e) => {
                    let e: String = e.chars().take(160).collect();
                    println!("| {rtol:e} | {s:?} | FAILED: {} | | | | | | |", e.replace('|', "/").replace('\n', " "));
                    continue;
                }
                Ok(o) => o,
            };
            let mut best = f64::INFINITY;
            for _ in 0..reps {
                let t = Instant::now();
                let r = run(p, s, rtol, &times);
                let el = t.elapsed().as_secs_f64() * 1e3;
                std::hint::black_box(&r);
                best = best.min(el);
            }
            let err = match max_error(&o.samples, &times, exact) {
                Ok(e) => format!("{e:.2e}"),
                Err(e) => format!("BAD SAMPLES: {e}"),
            };
            println!(
                "| {rtol:e} | {s:?} | {} | {} | {} | {} | {} | {best:.3} | {err} |",
                o.accepted, o.rejected, o.lib_evals, o.counted_evals, o.jac
            );
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map(String::as_str).unwrap_or("all");
    let reps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);

    if which == "all" || which == "paper" {
        let alpha = 0.5;
        let exact = move |t: f64| {
            let speed = move |tau: f64| (alpha * tau).exp() / (1.0 + tau * tau).sqrt();
            let v = speed(t);
            vec![integrate(&speed, 0.0, t), integrate(&|tau| tau * speed(tau), 0.0, t), v, t * v]
        };
        bench(&Paper { alpha }, &exact, reps, &[]);
    }
    if which == "all" || which == "osc" {
        bench(&Oscillator, &|t: f64| vec![t.cos(), -t.sin()], reps, &[]);
    }
    if which == "all" || which == "stiff" {
        bench(&StiffLinear, &|t: f64| vec![t.cos()], reps, &[]);
    }
    if which == "all" || which == "vdp" {
        let p = VanDerPol { mu: 1000.0 };
        let times: Vec<f64> = (0..=100).map(|i| 3000.0 * i as f64 / 100.0).collect();
        // reference: tightest runs of two different stiff methods, compared
        let refo = run(&p, Solver::OursRodas4, 1e-13, &times).expect("reference RODAS4");
        let refr = run(&p, Solver::TheirsRadau5, 1e-13, &times);
        match &refr {
            Ok(r) => println!(
                "\nVdP reference: ours RODAS4 rtol 1e-13 ({} steps); vs theirs Radau5 rtol 1e-13: max rel. diff {:.2e}",
                refo.accepted,
                max_error(&r.samples, &times, &|t| {
                    let i = (t / 30.0).round() as usize;
                    refo.samples[i].1.clone()
                })
                .unwrap_or(f64::NAN)
            ),
            Err(e) => println!("\nVdP reference Radau5 1e-13 failed: {e}"),
        }
        let refs = refo.samples.clone();
        let exact = move |t: f64| {
            let i = (t / 30.0).round() as usize;
            refs[i].1.clone()
        };
        let skip: Vec<Solver> = args.get(3).map(|s| s.split(',').filter_map(|n| SOLVERS.iter().copied().find(|x| format!("{x:?}") == n)).collect()).unwrap_or_default();
        bench(&p, &exact, reps, &skip);
    }
}
