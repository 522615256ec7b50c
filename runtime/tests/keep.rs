//! Constraints kept (SPEC §2.3) through the driver, on a hand-written bead
//! on the curve y = e^(−x) whose constraint is written through the
//! dependent coordinate, `y' = −y x'`: integrated freely, the residual
//! `e = y' + y x'` obeys `e' = x' e` and the bead leaves its curve.

use lagc_runtime::driver::{run, Options};
use lagc_runtime::failure::{Failure, FailureKind};
use lagc_runtime::linalg::Matrix;
use lagc_runtime::method::Method;
use lagc_runtime::model::{Initial, Model};
use lagc_runtime::output::sample_times;
use lagc_runtime::tolerance::Tolerance;

/// The free bead, `L = (x'² + y'²)/2`, `y' = −y x'`; the reduced system by
/// hand (multiplier form `x'' − y y'' = 0`, `y'' = D(−y x')` on the
/// constraint): `x'' = y² x'²/(1 + y²)`, `y'' = y x'²/(1 + y²)`. `KEEP`
/// says whether the model declares its constraint for keeping.
#[derive(Clone, Debug)]
struct Bead<const KEEP: bool>;

impl<const KEEP: bool> Model for Bead<KEEP> {
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
    const KEEPS_CONSTRAINTS: bool = KEEP;

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

/// The largest distance from the curve and the largest change of energy
/// over 161 samples, and the summary's record of the constraint.
fn solve<M: Model + 'static>(method: Method) -> (f64, f64, Option<lagc_runtime::keep::Kept>) {
    let mut model = M::new(&[]);
    let x0 = model.initial_state(&[]).unwrap();
    let options = Options {
        method,
        tol: Tolerance {
            rtol: 1e-10,
            atol: 1e-12,
        },
        ..Options::default()
    };
    let (mut off_curve, mut energy) = (0.0_f64, 0.0_f64);
    let e0 = (x0[2] * x0[2] + x0[3] * x0[3]) / 2.0;
    let times = sample_times(0.0, 16.0, 161);
    let outcome = run(&mut model, &options, 0.0, 16.0, &x0, &times, |_, _, x| {
        off_curve = off_curve.max((x[1] - (-x[0]).exp()).abs());
        energy = energy.max(((x[2] * x[2] + x[3] * x[3]) / 2.0 - e0).abs());
        Ok(())
    })
    .unwrap();
    (off_curve, energy, outcome.kept)
}

#[test]
fn a_bead_written_through_its_dependent_coordinate_stays_on_its_curve_when_kept() {
    for method in [Method::Direct, Method::Field] {
        let (off_curve, energy, kept) = solve::<Bead<true>>(method);
        let kept = kept.expect("a model that keeps constraints reports them");
        eprintln!("{method:?}: off the curve {off_curve:.2e}, energy {energy:.2e}, {kept:?}");
        assert!(
            off_curve < 1e-9,
            "{method:?}: off the curve by {off_curve:e}"
        );
        assert!(energy < 1e-9, "{method:?}: energy changes by {energy:e}");
        assert!(
            kept.projections > 0,
            "{method:?}: the drift was never corrected"
        );
        // Left free, the same model drifts off its curve: the check above
        // can fail.
        let (free_off_curve, _, free_kept) = solve::<Bead<false>>(method);
        assert!(free_kept.is_none());
        assert!(
            free_off_curve > 1e-6,
            "{method:?}: the free bead stays on its curve ({free_off_curve:e}): the test shows nothing"
        );
    }
}

/// `y' = sqrt(1 − x'²)` with `x'` driven up through 1 (`x'' = 1`): past
/// `t = 0.5` the constraint has no value.
#[derive(Clone, Debug)]
struct RootPastItsBranch;

impl Model for RootPastItsBranch {
    const NAME: &'static str = "root";
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
        RootPastItsBranch
    }
    fn param_values(&self) -> &[f64] {
        &[]
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, 1.0)
    }
    fn initial_state(&self, _given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(vec![0.0, 0.0, 0.5, 0.75_f64.sqrt()])
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = x[2];
        dx[1] = x[3];
        dx[2] = 1.0;
        // y'' = D sqrt(1 − x'²) = −x' x''/y', written with the state's y'
        // so that the motion itself stays finite past the branch's end.
        dx[3] = -x[2] / x[3].abs().max(1e-3);
        Ok(())
    }
    fn jacobian(&self, _t: f64, _x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        jac[(0, 2)] = 1.0;
        jac[(1, 3)] = 1.0;
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn constrained(&self, _t: f64, x: &[f64], kept: &mut [f64]) -> Result<(), Failure> {
        kept[3] = (1.0 - x[2] * x[2]).sqrt();
        Ok(())
    }
    fn kept_gradient(&self, _t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        jac[(3, 2)] = -x[2] / (1.0 - x[2] * x[2]).sqrt();
        Ok(())
    }
}

#[test]
fn a_constraint_whose_branch_ends_stops_the_run_naming_its_component() {
    let mut model = RootPastItsBranch;
    let x0 = model.initial_state(&[]).unwrap();
    let options = Options {
        method: Method::Direct,
        ..Options::default()
    };
    let failure = run(&mut model, &options, 0.0, 1.0, &x0, &[], |_, _, _| Ok(())).unwrap_err();
    let named = matches!(
        &failure.kind,
        FailureKind::ConstraintUndefined { component }
            | FailureKind::ConstraintLeft { component, .. } if component == "y'"
    );
    assert!(named, "{failure}");
    assert!(
        failure.time <= 0.5 + 1e-6,
        "past the branch's end: {failure}"
    );
}

/// The kept bead's exact motion: the speed stays √2 (the energy), so the
/// arc length from x = 0 is √2·t. With w(x) = √(1 + e^(−2x)) the arc length
/// is F(x) − F(0), F = acoth(w) − w (F' = w), inverted by Newton; since
/// w − 1 = e^(−2x)/(w + 1), acoth(w) = ln(w + 1) + x without cancellation.
fn exact_bead(t: f64) -> [f64; 4] {
    let w = |x: f64| (1.0 + (-2.0 * x).exp()).sqrt();
    let f = |x: f64| {
        let w = w(x);
        (w + 1.0).ln() + x - w
    };
    let target = f(0.0) + 2.0_f64.sqrt() * t;
    let mut x = t;
    for _ in 0..60 {
        let dx = (f(x) - target) / w(x);
        x -= dx;
        if dx.abs() < 1e-15 * x.abs().max(1.0) {
            break;
        }
    }
    let v = 2.0_f64.sqrt() / w(x);
    let y = (-x).exp();
    [x, y, v, -y * v]
}

/// The kept bead's largest error against [`exact_bead`] (relative where a
/// component exceeds 1) over 17 samples, and the steps it took (rejected
/// and predictor steps included: the work).
fn kept_bead_error(method: Method, rtol: f64) -> (usize, f64) {
    let mut model = Bead::<true>;
    let x0 = model.initial_state(&[]).unwrap();
    let options = Options {
        method,
        tol: Tolerance { rtol, atol: rtol },
        ..Options::default()
    };
    let mut error = 0.0_f64;
    let times = sample_times(0.0, 16.0, 17);
    let outcome = run(&mut model, &options, 0.0, 16.0, &x0, &times, |_, t, x| {
        for (u, v) in x.iter().zip(exact_bead(t)) {
            error = error.max((u - v).abs() / v.abs().max(1.0));
        }
        Ok(())
    })
    .unwrap_or_else(|f| panic!("{method:?} rtol {rtol}: {f}"));
    let r = outcome.report;
    let predictor = r
        .predictor
        .map_or(0, |p| p.accepted_steps + p.rejected_steps);
    (
        r.stats.accepted_steps + r.stats.rejected_steps + predictor,
        error,
    )
}

/// The least-squares slope of `log error` against `log steps`, negated.
fn observed_order(points: &[(usize, f64)]) -> f64 {
    let xs: Vec<f64> = points.iter().map(|p| (p.0 as f64).ln()).collect();
    let ys: Vec<f64> = points.iter().map(|p| p.1.ln()).collect();
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let num: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let den: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    -num / den
}

/// Projection must not cost the integrators their order: a projection
/// that lost a step's information (or re-anchored the field wrongly)
/// would leave the kept run right at one tolerance but of low order.
#[test]
fn kept_runs_keep_the_order_of_their_method() {
    for (method, rtols, least) in [
        (Method::Direct, [1e-5, 1e-7, 1e-9, 1e-11], 6.5),
        (Method::Field, [1e-5, 1e-7, 1e-9, 1e-11], 5.5),
    ] {
        let points: Vec<(usize, f64)> = rtols.iter().map(|&r| kept_bead_error(method, r)).collect();
        let p = observed_order(&points);
        eprintln!("kept bead, {method:?}: order {p:.2} {points:?}");
        assert!(p > least, "{method:?}: order {p:.2} {points:?}");
        let tightest = points.last().unwrap().1;
        assert!(
            tightest < 1e-9,
            "{method:?}: error {tightest:e} at rtol 1e-11"
        );
    }
}
