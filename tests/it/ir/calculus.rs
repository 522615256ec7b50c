//! Derivatives, the total derivative, substitution and evaluation.

use super::{arena, env_at, num, q, sym, Rng, ALPHA, M, M0};
use lagc::ir::{Arena, ExprId, Func, Node, Symbol};
use std::collections::{BTreeSet, HashMap};

/// A random expression of `q1`, `q1'`, `t`, `alpha` and `M`.
fn random_expr(a: &mut Arena, rng: &mut Rng, depth: u32, funcs: &mut BTreeSet<Func>) -> ExprId {
    if depth == 0 || rng.below(5) == 0 {
        return match rng.below(6) {
            0 => a.symbol(q(0, 0)),
            1 => a.symbol(q(0, 1)),
            2 => a.symbol(Symbol::Time),
            3 => a.symbol(ALPHA),
            4 => a.symbol(M),
            _ => {
                let v = (rng.range(-2.0, 2.0) * 4.0).round() / 4.0;
                a.constant(v)
            }
        };
    }
    // Never a literal zero below: `1/0` is legitimately kept symbolic and
    // evaluates to inf, which is no test of the derivative rules.
    let mut child = |a: &mut Arena, rng: &mut Rng| {
        let e = random_expr(a, rng, depth - 1, funcs);
        if a.is_zero(e) {
            a.one()
        } else {
            e
        }
    };
    match rng.below(8) {
        0 | 1 => {
            let n = 2 + rng.below(2);
            let ts: Vec<ExprId> = (0..n).map(|_| child(a, rng)).collect();
            a.add(&ts)
        }
        2 | 3 => {
            let n = 2 + rng.below(2);
            let fs: Vec<ExprId> = (0..n).map(|_| child(a, rng)).collect();
            a.mul(&fs)
        }
        4 => {
            let (x, y) = (child(a, rng), child(a, rng));
            if rng.below(2) == 0 {
                a.sub(x, y)
            } else {
                a.div(x, y)
            }
        }
        5 => {
            let x = child(a, rng);
            let n = rng.below(6) as i32 - 2;
            a.powi(x, n)
        }
        6 => {
            // A positive base with a symbolic exponent.
            let (x, y) = (child(a, rng), child(a, rng));
            let x2 = a.powi(x, 2);
            let c = a.constant(1.25);
            let base = a.add(&[c, x2]);
            a.pow(base, y)
        }
        _ => {
            let f = Func::ALL[rng.below(Func::ALL.len())];
            let x = child(a, rng);
            let e = a.func(f, x);
            funcs.insert(f);
            e
        }
    }
}

/// `d/dv e` at `env` by central differences with one Richardson step, or
/// `None` where the difference quotient is not stable (near a singularity).
fn finite_difference(a: &Arena, e: ExprId, v: Symbol, env: &dyn Fn(Symbol) -> f64) -> Option<f64> {
    let x0 = env(v);
    let at = |x: f64| a.eval(e, &|s| if s == v { x } else { env(s) });
    let central = |h: f64| (at(x0 + h) - at(x0 - h)) / (2.0 * h);
    let h = 1e-4 * x0.abs().max(1.0);
    let (d1, d2) = (central(h), central(h / 2.0));
    if !d1.is_finite() || !d2.is_finite() || (d1 - d2).abs() > 1e-3 * (1.0 + d2.abs()) {
        return None;
    }
    Some((4.0 * d2 - d1) / 3.0)
}

/// Hundreds of random expressions: `diff` agrees with finite differences.
#[test]
fn derivatives_match_finite_differences() {
    let mut rng = Rng::new(42);
    let mut covered = BTreeSet::new();
    let (mut checked, total) = (0, 400);
    for i in 0..total {
        let mut a = arena();
        let mut funcs = BTreeSet::new();
        let e = random_expr(&mut a, &mut rng, 4, &mut funcs);
        let wrt = if i % 2 == 0 { q(0, 0) } else { q(0, 1) };
        let d = a.diff(e, wrt);
        let mut any = false;
        for p in 0..3 {
            let env = env_at(i * 10 + p);
            let value = a.eval(e, &env);
            if !value.is_finite() || value.abs() > 1e8 {
                continue;
            }
            let Some(fd) = finite_difference(&a, e, wrt, &env) else {
                continue;
            };
            let exact = a.eval(d, &env);
            let tol = 1e-6 * (1.0 + exact.abs() + value.abs());
            assert!(
                (exact - fd).abs() <= tol,
                "d/d{wrt:?} of {} = {}: {exact} vs finite difference {fd}",
                a.display(e),
                a.display(d)
            );
            any = true;
        }
        if any {
            checked += 1;
            covered.extend(funcs);
        }
    }
    assert!(
        checked >= total * 3 / 4,
        "only {checked} of {total} expressions were checked"
    );
    assert_eq!(covered.len(), Func::ALL.len(), "covered only {covered:?}");
}

/// Each function's derivative rule, inside a product and a chain.
#[test]
fn every_function_derivative() {
    for f in Func::ALL {
        let mut a = arena();
        let x = sym(&mut a, q(0, 0));
        let y = sym(&mut a, q(1, 0));
        let c = num(&mut a, 0.25);
        let k = num(&mut a, 0.3);
        let xy = a.mul(&[c, x, y]);
        let u = a.add(&[k, xy]);
        let fu = a.func(f, u);
        let e = a.mul(&[fu, x]);
        let d = a.diff(e, q(0, 0));
        for p in 0..5 {
            let env = env_at(p);
            let fd = finite_difference(&a, e, q(0, 0), &env).expect("smooth in the domain");
            let exact = a.eval(d, &env);
            assert!(
                (exact - fd).abs() < 1e-7 * (1.0 + exact.abs()),
                "{f:?}: {exact} vs {fd}"
            );
        }
    }
}

#[test]
fn symbolic_exponent_derivative() {
    let mut a = arena();
    let x = sym(&mut a, q(0, 0));
    let y = sym(&mut a, q(1, 0));
    let e = a.pow(x, y);
    let dy = a.diff(e, q(1, 0));
    let lx = a.func(Func::Ln, x);
    assert_eq!(dy, a.mul(&[e, lx]));
    let dx = a.diff(e, q(0, 0));
    let m1 = num(&mut a, -1.0);
    let y1 = a.add(&[y, m1]);
    let p = a.pow(x, y1);
    assert_eq!(dx, a.mul(&[y, p]));
    // A constant exponent never produces a logarithm.
    let x3 = a.powi(x, 3);
    let d3 = a.diff(x3, q(0, 0));
    assert_eq!(a.display(d3).to_string(), "3*q1^2");
}

#[test]
fn total_derivative_on_jets() {
    let mut a = arena();
    let q1 = sym(&mut a, q(0, 0));
    let q1d = sym(&mut a, q(0, 1));
    let q1dd = sym(&mut a, q(0, 2));
    let t = sym(&mut a, Symbol::Time);
    let m = sym(&mut a, M);
    let two = num(&mut a, 2.0);

    let sq = a.powi(q1d, 2);
    let d = a.total_derivative(sq);
    assert_eq!(d, a.mul(&[two, q1d, q1dd]));

    let tq = a.mul(&[t, q1]);
    let d = a.total_derivative(tq);
    let tq1d = a.mul(&[t, q1d]);
    assert_eq!(d, a.add(&[q1, tq1d]));

    // Mass laws are frozen under D, params are constants.
    let zero = a.zero();
    assert_eq!(a.total_derivative(m), zero);
    let al = sym(&mut a, ALPHA);
    assert_eq!(a.total_derivative(al), zero);
    let mq = a.mul(&[m, q1d]);
    let d = a.total_derivative(mq);
    assert_eq!(d, a.mul(&[m, q1dd]));
    // D^3 t = 0, D^2 q1 = q1'', D q1''' = q1^(4).
    assert_eq!(a.total_derivative_n(t, 3), zero);
    assert_eq!(a.total_derivative_n(q1, 2), q1dd);
    let q3 = sym(&mut a, q(0, 3));
    let d = a.total_derivative(q3);
    assert_eq!(d, sym(&mut a, q(0, 4)));
}

/// D agrees with its definition `∂/∂t + Σ q^(r+1) ∂/∂q^(r)` on random expressions.
#[test]
fn total_derivative_matches_its_definition() {
    let mut rng = Rng::new(7);
    for i in 0..200 {
        let mut a = arena();
        let e = random_expr(&mut a, &mut rng, 4, &mut BTreeSet::new());
        let d = a.total_derivative(e);
        let mut terms = vec![a.diff(e, Symbol::Time)];
        for s in a.free_symbols(e) {
            if let Symbol::Jet { coord, order } = s {
                let next = a.jet(coord, order + 1);
                let partial = a.diff(e, s);
                terms.push(a.mul(&[next, partial]));
            }
        }
        let by_definition = a.add(&terms);
        let env = env_at(i);
        let (x, y) = (a.eval(d, &env), a.eval(by_definition, &env));
        if x.is_finite() || y.is_finite() {
            assert!(
                (x - y).abs() <= 1e-9 * (1.0 + x.abs()),
                "{}: {x} vs {y}",
                a.display(e)
            );
        }
    }
}

#[test]
fn substitution_is_simultaneous() {
    let mut a = arena();
    let x = sym(&mut a, q(0, 0));
    let y = sym(&mut a, q(1, 0));
    let two = num(&mut a, 2.0);
    let y2 = a.mul(&[two, y]);
    let e = a.add(&[x, y2]);
    let map = HashMap::from([(q(0, 0), y), (q(1, 0), x)]);
    let swapped = a.subst(e, &map);
    let x2 = a.mul(&[two, x]);
    assert_eq!(swapped, a.add(&[y, x2]));
    // Substituting re-canonicalises: x − y with y := x is 0.
    let diff = a.sub(x, y);
    let zero = a.zero();
    assert_eq!(a.subst(diff, &HashMap::from([(q(1, 0), x)])), zero);
    // An unrelated symbol leaves the expression untouched.
    assert_eq!(a.subst(e, &HashMap::from([(Symbol::Time, x)])), e);
}

/// The paper's constraint `q2' = t q1'` substituted into `L = M/2 (q1'² + q2'²)`.
#[test]
fn substitution_of_a_constraint() {
    let mut a = arena();
    let m = sym(&mut a, M);
    let (q1d, q2d) = (sym(&mut a, q(0, 1)), sym(&mut a, q(1, 1)));
    let t = sym(&mut a, Symbol::Time);
    let half = num(&mut a, 0.5);
    let s1 = a.powi(q1d, 2);
    let s2 = a.powi(q2d, 2);
    let s = a.add(&[s1, s2]);
    let lagrangian = a.mul(&[half, m, s]);
    let phi = a.mul(&[t, q1d]);
    let star = a.subst(lagrangian, &HashMap::from([(q(1, 1), phi)]));
    assert!(!a.depends_on(star, q(1, 1)));
    let t2 = a.powi(t, 2);
    let one = a.one();
    let one_t2 = a.add(&[one, t2]);
    let expected = a.mul(&[half, m, one_t2, s1]);
    for p in 0..5 {
        let env = env_at(p);
        let (x, y) = (a.eval(star, &env), a.eval(expected, &env));
        assert!((x - y).abs() < 1e-12 * y.abs());
    }
}

/// The coefficient of `f_A` in an expression affine in it: ∂/∂f_A, then the
/// free term by substituting zero.
#[test]
fn coefficient_of_an_affine_symbol() {
    let mut a = arena();
    let f2 = a.aux("f_2");
    let f3 = a.aux("f_3");
    assert_eq!(a.aux("f_2"), f2);
    let (x, t) = (sym(&mut a, q(0, 0)), sym(&mut a, Symbol::Time));
    let (e2, e3) = (a.symbol(f2), a.symbol(f3));
    let sin_t = a.func(Func::Sin, t);
    let coeff = a.add(&[sin_t, x]);
    let term = a.mul(&[e2, coeff]);
    let other = a.mul(&[e3, t]);
    let free = a.powi(x, 2);
    let e = a.add(&[term, other, free]);
    assert_eq!(a.diff(e, f2), coeff);
    let zero = a.zero();
    let map = HashMap::from([(f2, zero), (f3, zero)]);
    assert_eq!(a.subst(e, &map), free);
}

#[test]
fn evaluation_and_symbol_facts() {
    let mut a = arena();
    let (x, t) = (sym(&mut a, q(0, 2)), sym(&mut a, Symbol::Time));
    let xt = a.mul(&[x, t]);
    let s = a.func(Func::Sin, xt);
    let e = a.add(&[xt, s]);
    let env = |s: Symbol| match s {
        Symbol::Time => 2.0,
        _ => 0.25,
    };
    assert_eq!(a.eval(e, &env), 0.5 + 0.5f64.sin());
    assert_eq!(a.eval_many(&[xt, e], &env), vec![0.5, 0.5 + 0.5f64.sin()]);
    assert_eq!(a.free_symbols(e), BTreeSet::from([Symbol::Time, q(0, 2)]));
    assert!(a.depends_on(e, q(0, 2)) && !a.depends_on(e, q(0, 1)));
    assert_eq!(a.max_jet_order(e, 0), Some(2));
    assert_eq!(a.max_jet_order(e, 1), None);
    // x, t, x*t, sin(x*t), the sum: 5 nodes, 3 operations.
    assert_eq!(a.dag_size(&[e]), 5);
    assert_eq!(a.op_count(&[e]), 3);
}

#[test]
fn affine_parts_and_affinity() {
    let mut a = arena();
    let (x, y, t) = (
        sym(&mut a, q(0, 0)),
        sym(&mut a, q(1, 0)),
        sym(&mut a, Symbol::Time),
    );
    let sin_t = a.func(Func::Sin, t);
    let xs = a.mul(&[sin_t, x]);
    let three = num(&mut a, 3.0);
    let y3 = a.mul(&[three, y]);
    let e = a.add(&[xs, y3, t]);
    let vars = [q(0, 0), q(1, 0)];
    assert!(a.is_affine_in(e, &vars));
    assert_eq!(a.affine_parts(e, &vars), (vec![sin_t, three], t));
    let xy = a.mul(&[x, y]);
    let bilinear = a.add(&[e, xy]);
    assert!(!a.is_affine_in(bilinear, &vars));
    // sign(x) = (if x < 0 then -1 else 1): its derivative in x is 0 on
    // either side, but it is not 1 + 0·x (Coulomb friction, sign(x'), was
    // once folded to its branch at x' = 0 this way). A switch on t alone
    // keeps an expression affine in x.
    let (minus_one, one) = (num(&mut a, -1.0), num(&mut a, 1.0));
    let sign_x = a.select(x, minus_one, one);
    let friction = a.add(&[e, sign_x]);
    assert!(a.switches_on(friction, q(0, 0)));
    assert!(!a.is_affine_in(friction, &vars));
    let on_time = a.select(t, minus_one, one);
    let burnout = a.mul(&[on_time, x]);
    let switched_in_time = a.add(&[e, burnout]);
    assert!(!a.switches_on(switched_in_time, q(0, 0)));
    assert!(a.is_affine_in(switched_in_time, &vars));
}

/// `Arena::jacobian` (one forward pass for every symbol) builds the very
/// node `diff` builds, entry by entry: random expressions sharing
/// subexpressions, sums with terms that do not move, selections, symbolic
/// exponents, a symbol given twice and symbols the arena never saw.
/// `diff` runs first; the pass does not read its memo, so every entry is
/// built again and compared by id (ids are equal iff the canonical
/// expressions are).
#[test]
fn jacobian_is_diff_entry_by_entry() {
    let mut rng = Rng::new(29);
    let mut a = arena();
    let mut funcs = BTreeSet::new();
    let mut roots = Vec::new();
    for _ in 0..80 {
        let x = random_expr(&mut a, &mut rng, 4, &mut funcs);
        let y = random_expr(&mut a, &mut rng, 3, &mut funcs);
        let g = random_expr(&mut a, &mut rng, 2, &mut funcs);
        roots.push(x);
        roots.push(a.add(&[x, y]));
        roots.push(a.mul(&[x, y]));
        roots.push(a.select(g, x, y));
    }
    // `alpha + 2(1 + q1)q1'`: in `q1'` the sum's partial is `add` of
    // `2(1 + q1)` and a 0 for `alpha`, and the 0 makes `add` distribute
    // (`2 + 2q1`); without it the partial would stay `2(1 + q1)`.
    let (one, two) = (a.one(), a.constant(2.0));
    let (x, v, alpha) = (a.symbol(q(0, 0)), a.symbol(q(0, 1)), a.symbol(ALPHA));
    let inner = a.add(&[one, x]);
    let term = a.mul(&[two, inner, v]);
    roots.push(a.add(&[alpha, term]));
    let wrt = [
        q(0, 1),
        q(0, 0),
        Symbol::Time,
        ALPHA,
        M,
        q(1, 0),
        q(0, 0),
        M0,
    ];
    let expected: Vec<Vec<ExprId>> = roots
        .iter()
        .map(|&r| wrt.iter().map(|&s| a.diff(r, s)).collect())
        .collect();
    let got = a.jacobian(&roots, &wrt);
    for (r, (g, e)) in got.iter().zip(&expected).enumerate() {
        for (c, (&g, &e)) in g.iter().zip(e).enumerate() {
            assert_eq!(
                g,
                e,
                "∂/∂{:?} of {}: {} by the pass, {} by diff",
                wrt[c],
                a.display(roots[r]),
                a.display(g),
                a.display(e)
            );
        }
    }
    assert_eq!(got.len(), roots.len());
    let last = got.last().expect("a row");
    assert!(
        matches!(a.node(last[0]), Node::Add(_)),
        "{}",
        a.display(last[0])
    );
    let moving = expected
        .iter()
        .flatten()
        .filter(|&&e| !a.is_zero(e))
        .count();
    assert!(moving > 400, "only {moving} non-zero entries");
}
