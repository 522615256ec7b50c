//! One field for many initial states (`runtime::ensemble`) against the
//! exact motions: a linear coefficient system (the paper's), Riccati ones
//! (the oscillator re-anchors before `tan` blows up; the damped
//! oscillator), and a stiff one that re-anchors often.

use super::rt::ensemble::solve_ensemble;
use super::rt::field::{Anchor, FieldOptions};
use super::rt::method::Integrator;
use super::rt::output::sample_times;
use super::rt::system::CoefficientSystem;
use super::systems::*;
use super::{field_options, TOL};

/// `k` initial states spread around `x0` (the first is `x0`); components
/// from `fixed` on are left alone (the paper's `q2'(0) = 0` is forced by
/// its constraint, and its exact motion assumes it).
fn members(x0: &[f64], k: usize, fixed: usize) -> Vec<Vec<f64>> {
    (0..k)
        .map(|m| {
            x0.iter()
                .enumerate()
                .map(|(i, x)| {
                    let sign = if i % 2 == 0 { 1.0 } else { -0.7 };
                    if i < fixed {
                        x + 0.3 * (m as f64) * sign
                    } else {
                        *x
                    }
                })
                .collect()
        })
        .collect()
}

/// The largest error of every member at every sample, relative to
/// `max(|exact|, 1)`, and the report.
fn ensemble_error(
    system: &dyn CoefficientSystem,
    exact: &dyn Fn(f64, &[f64]) -> Vec<f64>,
    options: &FieldOptions,
    t1: f64,
    x0: &[f64],
    fixed: usize,
    k: usize,
) -> (f64, super::rt::ensemble::EnsembleReport) {
    let starts = members(x0, k, fixed);
    let times = sample_times(0.0, t1, 11);
    let n = x0.len();
    let mut largest = 0.0_f64;
    let mut calls = 0;
    let report = solve_ensemble(system, options, &times, &starts, |t, states| {
        assert_eq!(states.len(), k * n);
        calls += 1;
        for (state, start) in states.chunks(n).zip(&starts) {
            for (x, truth) in state.iter().zip(exact(t, start)) {
                largest = largest.max((x - truth).abs() / truth.abs().max(1.0));
            }
        }
    })
    .unwrap();
    assert_eq!(calls, times.len());
    (largest, report)
}

#[test]
fn linear_coefficient_system_needs_one_copy_and_matches_exact_motion() {
    let system = PaperExample { alpha: 0.5 };
    let x0 = [0.0, 0.0, 1.0, 0.0];
    for k in [1, 3, 8] {
        let exact = |t: f64, x: &[f64]| system.exact(t, x);
        let (error, report) = ensemble_error(&system, &exact, &field_options(), 5.0, &x0, 3, k);
        assert_eq!(report.copies, 1);
        assert!(error <= 1e-8, "K = {k}: error {error:e}");
    }
}

#[test]
fn riccati_coefficient_systems_take_two_copies_and_reanchor() {
    let oscillator = Oscillator { omega: 2.0 };
    let exact = |t: f64, x: &[f64]| oscillator.exact(t, x);
    for k in [1, 2, 5] {
        let (error, report) = ensemble_error(
            &oscillator,
            &exact,
            &field_options(),
            10.0,
            &[1.0, 0.5],
            2,
            k,
        );
        assert_eq!(report.copies, 2);
        assert!(report.reanchorings > 0, "{report:?}");
        assert!(error <= 1e-8, "oscillator K = {k}: error {error:e}");
    }
    let damped = DampedOscillator {
        omega: 3.0,
        zeta: 0.2,
    };
    let exact = |t: f64, x: &[f64]| damped.exact(t, x);
    let options = FieldOptions {
        anchor: Anchor::Given(vec![0.3]),
        ..field_options()
    };
    let (error, _) = ensemble_error(&damped, &exact, &options, 4.0, &[1.0, -1.0], 2, 6);
    assert!(error <= 1e-8, "damped oscillator: error {error:e}");
}

#[test]
fn stiff_system_reanchors_every_member_with_either_integrator() {
    let system = StiffPair { rate: 1000.0 };
    let exact = |t: f64, x: &[f64]| system.exact(t, x);
    for integrator in [Integrator::Explicit, Integrator::Stiff] {
        let options = FieldOptions {
            integrator,
            tol: TOL,
            ..FieldOptions::default()
        };
        let (error, report) = ensemble_error(&system, &exact, &options, 2.0, &[1.0, 2.0], 2, 4);
        assert!(report.reanchorings > 0, "{report:?}");
        assert!(error <= 1e-8, "{integrator:?}: error {error:e}");
    }
}
