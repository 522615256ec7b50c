//! Fixed helpers of the generated library, emitted only when the system
//! needs them: the linear solve of the mass matrix, Newton's method, and
//! finite-difference Jacobians for implicit systems.

use proc_macro2::TokenStream;
use quote::quote;

/// `A z = b` by LU, with the failure SPEC §4 asks for.
pub fn linear_solve() -> TokenStream {
    quote! {
        /// Solves `a z = b` for the highest derivatives; a singular mass
        /// matrix stops the run.
        fn solve_mass_matrix(t: f64, a: DMatrix<f64>, b: DVector<f64>) -> Result<DVector<f64>, Failure> {
            let condition = condition_number(&a);
            match a.lu().solve(&b) {
                Some(z) if z.iter().all(|v| v.is_finite()) && condition < 1e15 => Ok(z),
                _ => Err(Failure::new(t, FailureKind::SingularMassMatrix { condition })),
            }
        }

        /// The 2-norm condition number from the singular values.
        fn condition_number(a: &DMatrix<f64>) -> f64 {
            let values = a.clone().singular_values();
            let largest = values.max();
            let smallest = values.min();
            if smallest > 0.0 { largest / smallest } else { f64::INFINITY }
        }
    }
}

pub fn newton() -> TokenStream {
    quote! {
        /// Newton's method on `residual(z) = (G, ∂G/∂z)` from `z`.
        fn newton(
            t: f64,
            mut z: DVector<f64>,
            residual: impl Fn(&DVector<f64>) -> (DVector<f64>, DMatrix<f64>),
        ) -> Result<DVector<f64>, Failure> {
            const MAX_ITERATIONS: usize = 50;
            let mut norm = f64::INFINITY;
            for iteration in 0..MAX_ITERATIONS {
                let (g, g_z) = residual(&z);
                norm = g.norm();
                let Some(step) = g_z.lu().solve(&(-g)) else {
                    return Err(Failure::new(t, FailureKind::SingularMassMatrix { condition: f64::INFINITY }));
                };
                z += &step;
                if !z.iter().all(|v| v.is_finite()) {
                    break;
                }
                // Quadratic convergence: after a step of 1e-12 (relative)
                // the error left is at rounding level.
                if step.norm() <= 1e-12 * z.norm().max(1.0) || (iteration > 0 && norm == 0.0) {
                    return Ok(z);
                }
            }
            Err(Failure::new(t, FailureKind::NewtonNonConvergence { residual: norm, iterations: MAX_ITERATIONS }))
        }
    }
}

pub fn finite_differences() -> TokenStream {
    quote! {
        /// `∂X/∂x` by central differences of the right side.
        fn finite_difference_jacobian(system: &System, t: f64, x: &[f64], n: usize, jac: &mut DMatrix<f64>) -> Result<(), Failure> {
            let mut plus = vec![0.0; n];
            let mut minus = vec![0.0; n];
            let mut shifted = x.to_vec();
            for k in 0..n {
                let h = f64::EPSILON.cbrt() * x[k].abs().max(1.0);
                shifted[k] = x[k] + h;
                system.rhs(t, &shifted, &mut plus)?;
                shifted[k] = x[k] - h;
                system.rhs(t, &shifted, &mut minus)?;
                shifted[k] = x[k];
                for i in 0..n {
                    jac[(i, k)] = (plus[i] - minus[i]) / (2.0 * h);
                }
            }
            Ok(())
        }

        /// `∂X/∂t` by central differences of the right side.
        fn finite_difference_time_partial(system: &System, t: f64, x: &[f64], n: usize, dxdt: &mut [f64]) -> Result<(), Failure> {
            let mut plus = vec![0.0; n];
            let mut minus = vec![0.0; n];
            let h = f64::EPSILON.cbrt() * t.abs().max(1.0);
            system.rhs(t + h, x, &mut plus)?;
            system.rhs(t - h, x, &mut minus)?;
            for i in 0..n {
                dxdt[i] = (plus[i] - minus[i]) / (2.0 * h);
            }
            Ok(())
        }
    }
}

/// `solve(...)`: the method chosen at run time, on this system.
pub fn solve(affine: bool) -> TokenStream {
    let field = if affine {
        quote! {
            let coefficients = Coefficients { params: params.clone() };
            let report = solve_field(&coefficients, &field_options, times, x0, on_sample)?;
            let integrator = if coefficients.is_linear() { integrator } else { Integrator::Explicit };
            Ok(Summary {
                method: format!("field ({})", integrator.name()),
                steps: report.stats.accepted_steps,
                rejected_steps: report.stats.rejected_steps,
                rhs_evaluations: report.stats.rhs_evaluations,
                largest_condition: Some(report.largest_condition),
                reanchorings: Some(report.reanchorings),
                wall_time: start.elapsed(),
            })
        }
    } else {
        quote! {
            let report = solve_local_field(&system, &field_options, times, x0, on_sample)?;
            Ok(Summary {
                method: "local field (DOP853 windows)".to_string(),
                steps: report.accepted_windows,
                rejected_steps: report.rejected_windows,
                rhs_evaluations: report.field_stats.rhs_evaluations + report.linearisations,
                largest_condition: Some(report.largest_condition),
                reanchorings: Some(report.accepted_windows),
                wall_time: start.elapsed(),
            })
        }
    };
    let ensemble = if affine {
        quote! {
            /// One field for every initial state of `members` (affine
            /// systems), calling `on_sample(t, states)` with member `k` at
            /// `states[k·N..(k+1)·N]`; `None` when the system is not affine.
            pub fn solve_ensemble(
                params: &Params,
                options: &Options,
                times: &[f64],
                members: &[Vec<f64>],
                on_sample: impl FnMut(f64, &[f64]),
            ) -> Option<Result<Summary, Failure>> {
                let start = std::time::Instant::now();
                let coefficients = Coefficients { params: params.clone() };
                let integrator = if options.stiff && coefficients.is_linear() { Integrator::Stiff } else { Integrator::Explicit };
                let field_options = FieldOptions {
                    tol: options.tol,
                    integrator,
                    anchor: options.anchor.clone(),
                    ..FieldOptions::default()
                };
                let solved = solve_field_ensemble(&coefficients, &field_options, times, members, on_sample);
                Some(solved.map(|report| Summary {
                    method: format!("field ensemble ({}, {} cop{})", integrator.name(), report.copies, if report.copies == 1 { "y" } else { "ies" }),
                    steps: report.stats.accepted_steps,
                    rejected_steps: report.stats.rejected_steps,
                    rhs_evaluations: report.stats.rhs_evaluations,
                    largest_condition: Some(report.largest_condition),
                    reanchorings: Some(report.reanchorings),
                    wall_time: start.elapsed(),
                }))
            }
        }
    } else {
        quote! {
            /// The ensemble mode needs the field method proper (an affine
            /// system): always `None` here.
            pub fn solve_ensemble(
                _params: &Params,
                _options: &Options,
                _times: &[f64],
                _members: &[Vec<f64>],
                _on_sample: impl FnMut(f64, &[f64]),
            ) -> Option<Result<Summary, Failure>> {
                None
            }
        }
    };
    quote! {
        #ensemble

        /// How to integrate (the generated binary's options).
        #[derive(Clone, Debug, PartialEq)]
        pub struct Options {
            pub field: bool,
            pub stiff: bool,
            pub tol: Tolerance,
            pub anchor: Anchor,
        }

        /// Integrates the model from `x0` over `times`, by the field method
        /// or directly, calling `on_sample` at every sample time.
        pub fn solve(
            params: &Params,
            options: &Options,
            times: &[f64],
            x0: &[f64],
            on_sample: impl FnMut(f64, &[f64]),
        ) -> Result<Summary, Failure> {
            let start = std::time::Instant::now();
            let system = System { params: params.clone() };
            let integrator = if options.stiff { Integrator::Stiff } else { Integrator::Explicit };
            if !options.field {
                let stats = solve_direct(&system, integrator, options.tol, times, x0, on_sample)?;
                return Ok(Summary {
                    method: format!("direct ({})", integrator.name()),
                    steps: stats.accepted_steps,
                    rejected_steps: stats.rejected_steps,
                    rhs_evaluations: stats.rhs_evaluations,
                    largest_condition: None,
                    reanchorings: None,
                    wall_time: start.elapsed(),
                });
            }
            let field_options = FieldOptions {
                tol: options.tol,
                integrator,
                anchor: options.anchor.clone(),
                ..FieldOptions::default()
            };
            #field
        }
    }
}
