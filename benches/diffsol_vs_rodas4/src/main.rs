//! lagc's RODAS4 against diffsol (BDF, TR-BDF2, ESDIRK34) on stiff models
//! that lagc generated: the same right side and exact Jacobian (lagc's
//! generated `rhs` and `jacobian`) for every solver, the same tolerances
//! (atol = rtol·1e-2, as `lagc report`), the error against the models'
//! exact solutions at 11 evenly spaced times (dense output for both), the
//! wall time the minimum of several runs. Prints Markdown.

use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod};
use lagc_runtime::api::solve;
use lagc_runtime::driver::Options;
use lagc_runtime::linalg::Matrix;
use lagc_runtime::method::{IntegratorChoice, Method};
use lagc_runtime::model::Model;
use std::time::Instant;

type LS = NalgebraLU<f64>;
type M = NalgebraMat<f64>;

/// One run: the states at the sample times, the steps, or why it failed.
struct Run {
    states: Vec<Vec<f64>>,
    steps: usize,
    jacobians: usize,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Solver {
    Rodas4,
    /// lagc's DOP853, for reference (what `auto` runs until it detects
    /// stiffness).
    Dop853,
    Bdf,
    TrBdf2,
    Esdirk34,
}

const SOLVERS: [Solver; 5] = [
    Solver::Rodas4,
    Solver::Bdf,
    Solver::TrBdf2,
    Solver::Esdirk34,
    Solver::Dop853,
];

fn run<Mo: Model + 'static>(solver: Solver, rtol: f64, times: &[f64]) -> Result<Run, String> {
    let atol = rtol * 1e-2;
    let params = Mo::parameters(&[]);
    let model = Mo::new(&params);
    let x0 = model.initial_state(&[]).map_err(|e| format!("{e:?}"))?;
    let t0 = model.time_span().0;
    let n = x0.len();
    if matches!(solver, Solver::Rodas4 | Solver::Dop853) {
        let choice = if solver == Solver::Rodas4 {
            IntegratorChoice::Stiff
        } else {
            IntegratorChoice::Explicit
        };
        let options = Options::default()
            .method(Method::Direct)
            .integrator(choice)
            .rtol(rtol)
            .atol(atol)
            .max_steps(10_000_000);
        let solution = solve::<Mo>(&params, &[], &options).map_err(|e| format!("{e}"))?;
        let stats = solution.outcome.report.stats;
        return Ok(Run {
            states: times.iter().map(|&t| solution.at(t)).collect(),
            steps: stats.accepted_steps + stats.rejected_steps,
            jacobians: stats.jacobian_evaluations,
        });
    }
    let rhs_model = model.clone();
    let jac_model = model.clone();
    let start = x0.clone();
    let problem = OdeBuilder::<M>::new()
        .t0(t0)
        .rtol(rtol)
        .atol([atol])
        .rhs_implicit(
            move |x: &[f64], _p: &[f64], t: f64, y: &mut [f64]| {
                rhs_model.rhs(t, x, y).expect("the right side");
            },
            move |x: &[f64], _p: &[f64], t: f64, v: &[f64], y: &mut [f64]| {
                // J v from lagc's exact Jacobian.
                let mut jac = Matrix::zeros(n, n);
                jac_model.jacobian(t, x, &mut jac).expect("the Jacobian");
                for (i, yi) in y.iter_mut().enumerate() {
                    *yi = (0..n).map(|j| jac[(i, j)] * v[j]).sum();
                }
            },
        )
        .init(
            move |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&start),
            n,
        )
        .build()
        .map_err(|e| format!("{e}"))?;
    let ts = &times[1..];
    let (values, steps, setups) = match solver {
        Solver::Bdf => {
            let mut s = problem.bdf::<LS>().map_err(|e| format!("{e}"))?;
            let (v, _) = s.solve_dense(ts).map_err(|e| format!("{e}"))?;
            let st = s.get_statistics();
            (v, st.number_of_steps, st.number_of_linear_solver_setups)
        }
        Solver::TrBdf2 => {
            let mut s = problem.tr_bdf2::<LS>().map_err(|e| format!("{e}"))?;
            let (v, _) = s.solve_dense(ts).map_err(|e| format!("{e}"))?;
            let st = s.get_statistics();
            (v, st.number_of_steps, st.number_of_linear_solver_setups)
        }
        Solver::Esdirk34 => {
            let mut s = problem.esdirk34::<LS>().map_err(|e| format!("{e}"))?;
            let (v, _) = s.solve_dense(ts).map_err(|e| format!("{e}"))?;
            let st = s.get_statistics();
            (v, st.number_of_steps, st.number_of_linear_solver_setups)
        }
        Solver::Rodas4 | Solver::Dop853 => unreachable!(),
    };
    let mut states = vec![x0];
    for j in 0..ts.len() {
        states.push((0..n).map(|i| values[(i, j)]).collect());
    }
    Ok(Run {
        states,
        steps,
        jacobians: setups,
    })
}

/// The largest error over the samples and the components the model gives
/// exactly, relative to max(1, |exact|).
fn error<Mo: Model + 'static>(times: &[f64], states: &[Vec<f64>]) -> f64 {
    let model = Mo::new(&Mo::parameters(&[]));
    let mut exact = vec![None; states[0].len()];
    let mut worst: f64 = 0.0;
    for (&t, x) in times.iter().zip(states) {
        exact.iter_mut().for_each(|e| *e = None);
        model.exact(t, &mut exact);
        for (xi, ei) in x.iter().zip(&exact) {
            if let Some(e) = ei {
                let d = (xi - e).abs() / e.abs().max(1.0);
                worst = worst.max(if d.is_finite() { d } else { f64::INFINITY });
            }
        }
    }
    worst
}

/// A row: rtol, solver, error, time (ms), steps, Jacobians; or failure.
struct Row {
    rtol: f64,
    solver: Solver,
    result: Result<(f64, f64, usize, usize), String>,
}

fn model_table<Mo: Model + 'static>(repeats: usize) -> Vec<Row> {
    let model = Mo::new(&Mo::parameters(&[]));
    let (t0, t1) = model.time_span();
    let times: Vec<f64> = (0..=10).map(|i| t0 + (t1 - t0) * i as f64 / 10.0).collect();
    let mut rows = Vec::new();
    for k in 3..=10 {
        let rtol = 10f64.powi(-k);
        for solver in SOLVERS {
            let mut best = f64::INFINITY;
            let mut last = None;
            for _ in 0..repeats {
                let start = Instant::now();
                let outcome = run::<Mo>(solver, rtol, &times);
                best = best.min(start.elapsed().as_secs_f64() * 1e3);
                let failed = outcome.is_err();
                last = Some(outcome);
                if failed {
                    break;
                }
            }
            let result = match last.unwrap() {
                Ok(r) => Ok((error::<Mo>(&times, &r.states), best, r.steps, r.jacobians)),
                Err(e) => Err(e),
            };
            rows.push(Row {
                rtol,
                solver,
                result,
            });
        }
    }
    rows
}

/// The cheapest run of `solver` whose error is at most `target`.
fn cheapest(rows: &[Row], solver: Solver, target: f64) -> Option<(f64, f64)> {
    rows.iter()
        .filter(|r| r.solver == solver)
        .filter_map(|r| match &r.result {
            Ok((e, ms, _, _)) if *e <= target => Some((*ms, r.rtol)),
            _ => None,
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

fn print<Mo: Model + 'static>(repeats: usize) {
    let rows = model_table::<Mo>(repeats);
    println!("### {}\n", Mo::NAME);
    println!("| rtol | solver | max error | wall ms (min of {repeats}) | steps | Jacobians / LU setups |");
    println!("|---|---|---:|---:|---:|---:|");
    for r in &rows {
        match &r.result {
            Ok((e, ms, steps, jac)) => println!(
                "| {:.0e} | {:?} | {:.2e} | {:.3} | {} | {} |",
                r.rtol, r.solver, e, ms, steps, jac
            ),
            Err(message) => {
                let message: String = message.chars().take(120).collect();
                println!(
                    "| {:.0e} | {:?} | FAILED: {} | | | |",
                    r.rtol,
                    r.solver,
                    message.replace('|', "/")
                )
            }
        }
    }
    println!("\nTime at equal error (the cheapest run reaching it; its rtol):\n");
    println!("| error ≤ | Rodas4 | Bdf | TrBdf2 | Esdirk34 | Dop853 (lagc, explicit) |");
    println!("|---|---:|---:|---:|---:|---:|");
    for target in [1e-4, 1e-6, 1e-8] {
        let cells: Vec<String> = SOLVERS
            .iter()
            .map(|&s| match cheapest(&rows, s, target) {
                Some((ms, rtol)) => format!("{ms:.3} ms ({rtol:.0e})"),
                None => "not reached".to_string(),
            })
            .collect();
        println!("| {target:.0e} | {} |", cells.join(" | "));
    }
    println!();
}

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(5);
    print::<lag_mass_gain_stiff::Model>(repeats);
    print::<lag_mass_loss_stiff_spring::Model>(repeats);
    print::<lag_mass_gain_1000::Model>(repeats);
}
