//! Fixed helpers of the generated library, emitted only when the system
//! needs them: the linear solve of the mass matrix, Newton's method, and
//! finite-difference Jacobians for implicit systems.

use crate::check::model::IntegratorChoice;
use proc_macro2::TokenStream;
use quote::quote;

/// `A z = b` by LU, with the failure SPEC §4 asks for, and the watch on
/// the mass matrix's condition that names a singular mass matrix as the
/// cause when the integrator stops.
pub fn linear_solve() -> TokenStream {
    quote! {
        /// Solves `a z = b` for the highest derivatives; a singular mass
        /// matrix stops the run.
        fn solve_mass_matrix(t: f64, a: DMatrix<f64>, b: DVector<f64>, watch: &MassMatrixWatch) -> Result<DVector<f64>, Failure> {
            let condition = condition_number(&a);
            watch.record(t, condition);
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

        /// The mass matrix's condition number at the first solve and at the
        /// latest one. A mass matrix that becomes singular at `t*` (a mass
        /// that vanishes) rarely meets the exact singularity: the motion
        /// blows up as `t → t*` and the integrator's step underflows first.
        /// The watch lets that failure name its cause.
        #[derive(Debug, Default)]
        pub struct MassMatrixWatch {
            first: std::cell::Cell<Option<f64>>,
            latest: std::cell::Cell<f64>,
        }

        impl MassMatrixWatch {
            /// The growth of the condition number since the start beyond
            /// which a failure of the integrator is blamed on the mass
            /// matrix: four orders of magnitude. RODAS4 (with its
            /// finite-difference Jacobian) gives up at `1 − t ≈ 6e-6` on
            /// `tests/data/runtime_failures/singular_mass_matrix.lag`, a
            /// growth of 1e5; DOP853 at `1e-11`.
            const GROWTH: f64 = 1e4;

            fn record(&self, _t: f64, condition: f64) {
                if self.first.get().is_none() {
                    self.first.set(Some(condition));
                }
                self.latest.set(condition);
            }

            /// A step-size underflow or a non-finite state while the mass
            /// matrix is nearly singular is reported as a singular mass
            /// matrix, at the same time.
            fn explain(&self, failure: Failure) -> Failure {
                let (Some(first), latest) = (self.first.get(), self.latest.get()) else {
                    return failure;
                };
                let integrator_stopped = matches!(
                    failure.kind,
                    FailureKind::StepSizeUnderflow { .. } | FailureKind::NonFiniteState { .. }
                );
                if integrator_stopped && !(latest <= Self::GROWTH * first) {
                    Failure::new(failure.time, FailureKind::SingularMassMatrix { condition: latest })
                } else {
                    failure
                }
            }
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

/// `solve(...)`: the method chosen at run time, on this system, and the
/// choice of integrator with the model's `integrator` statement as default.
pub fn solve(affine: bool, linear: bool, declared: Option<IntegratorChoice>) -> TokenStream {
    let declared = match declared {
        None => quote! { None },
        Some(IntegratorChoice::Auto) => quote! { Some(IntegratorChoice::Auto) },
        Some(IntegratorChoice::Explicit) => quote! { Some(IntegratorChoice::Explicit) },
        Some(IntegratorChoice::Stiff) => quote! { Some(IntegratorChoice::Stiff) },
        Some(IntegratorChoice::Magnus) => quote! { Some(IntegratorChoice::Magnus) },
    };
    let field = if affine {
        quote! {
            let coefficients = Coefficients { params: params.clone() };
            let report = solve_field(&coefficients, &field_options, times, x0, on_sample)?;
            Ok(Summary {
                method: format!("field ({})", report.integrator),
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
            let report = solve_local_field(&system, &field_options, times, x0, on_sample)
                .map_err(|failure| system.explain(failure))?;
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
    // What the field method makes of the choice (FieldOptions::for_choice):
    // RODAS4 and Magnus need a linear coefficient system.
    let field_plan = if affine && linear {
        quote! {
            match choice {
                IntegratorChoice::Stiff => format!("RODAS4 ({source})"),
                IntegratorChoice::Magnus => format!("Magnus-4 ({source})"),
                IntegratorChoice::Auto | IntegratorChoice::Explicit => format!("DOP853 ({source})"),
            }
        }
    } else if affine {
        quote! {
            match choice {
                IntegratorChoice::Stiff | IntegratorChoice::Magnus => format!(
                    "DOP853 ({source}; not {}: the coefficient system is of Riccati type, and it needs a linear one)",
                    choice.name()
                ),
                IntegratorChoice::Auto | IntegratorChoice::Explicit => format!("DOP853 ({source})"),
            }
        }
    } else {
        quote! {
            let _ = choice;
            format!("DOP853 ({source}; the local field method integrates each window's linear field with DOP853)")
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
                let (choice, _) = resolved_choice(options);
                // The ensemble integrates with DOP853 or RODAS4 (no Magnus).
                let field_options = FieldOptions {
                    reanchor: options.reanchor,
                    magnus: false,
                    ..FieldOptions::for_choice(choice, options.tol, options.anchor.clone())
                };
                let integrator = field_options.integrator_name(&coefficients);
                let solved = solve_field_ensemble(&coefficients, &field_options, times, members, on_sample);
                Some(solved.map(|report| Summary {
                    method: format!("field ensemble ({}, {} cop{})", integrator, report.copies, if report.copies == 1 { "y" } else { "ies" }),
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

        pub use runtime::method::IntegratorChoice;

        /// The model's `integrator` statement (`None`: it has none).
        pub const DECLARED_INTEGRATOR: Option<IntegratorChoice> = #declared;

        /// How to integrate (the generated binary's options).
        #[derive(Clone, Debug, PartialEq)]
        pub struct Options {
            pub field: bool,
            /// `None`: the model's `integrator` statement decides, or `Auto`.
            pub integrator: Option<IntegratorChoice>,
            pub tol: Tolerance,
            pub anchor: Anchor,
            /// `false`: stop with a singular-condition-matrix failure when
            /// the conditions (13) pass the field's condition threshold,
            /// instead of re-anchoring (to see where the field degrades).
            pub reanchor: bool,
        }

        /// The integrator choice of a run with `options`, and where it
        /// comes from, in words.
        fn resolved_choice(options: &Options) -> (IntegratorChoice, String) {
            match (options.integrator, DECLARED_INTEGRATOR) {
                (Some(choice), _) => (choice, format!("--integrator {}", choice.name())),
                (None, Some(choice)) => (choice, format!("declared {} in the model", choice.name())),
                (None, None) => (IntegratorChoice::Auto, "auto, the default".to_string()),
            }
        }

        /// The line a run prints on stderr before it starts, e.g.
        /// `direct: RODAS4 (declared stiff in the model)`; a switch made
        /// during the run shows in the summary's method.
        pub fn integrator_choice(options: &Options) -> String {
            let (choice, source) = resolved_choice(options);
            if options.field {
                let plan = { #field_plan };
                return format!("field: {plan}");
            }
            let plan = match choice {
                IntegratorChoice::Stiff => format!("RODAS4 ({source})"),
                IntegratorChoice::Explicit => format!("DOP853 ({source}; stiffness is only reported)"),
                IntegratorChoice::Auto | IntegratorChoice::Magnus => {
                    format!("DOP853, switching to RODAS4 if it detects stiffness ({source})")
                }
            };
            format!("direct: {plan}")
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
            let system = System::new(params.clone());
            let (choice, _) = resolved_choice(options);
            if !options.field {
                let report = solve_direct_choice(&system, choice, options.tol, times, x0, on_sample)
                    .map_err(|failure| system.explain(failure))?;
                let method = match report.note() {
                    Some(note) => format!("{} [{}]", report.method_name(), note.trim_start_matches("direct: ")),
                    None => report.method_name(),
                };
                return Ok(Summary {
                    method,
                    steps: report.stats.accepted_steps,
                    rejected_steps: report.stats.rejected_steps,
                    rhs_evaluations: report.stats.rhs_evaluations,
                    largest_condition: None,
                    reanchorings: None,
                    wall_time: start.elapsed(),
                });
            }
            let field_options = FieldOptions {
                reanchor: options.reanchor,
                ..FieldOptions::for_choice(choice, options.tol, options.anchor.clone())
            };
            #field
        }
    }
}
