//! Canonical forms built by the constructors.

use super::{arena, num, q, sym, ALPHA, M0};
use lagc::ir::{Func, Node, Symbol};

#[test]
fn like_terms_collect_and_order_does_not_matter() {
    let mut a = arena();
    let x = sym(&mut a, q(0, 0));
    let y = sym(&mut a, ALPHA);
    let two = num(&mut a, 2.0);
    let x_plus_x = a.add(&[x, x]);
    let two_x = a.mul(&[two, x]);
    assert_eq!(x_plus_x, two_x);
    assert_eq!(a.add(&[x, y]), a.add(&[y, x]));
    assert_eq!(a.mul(&[x, y]), a.mul(&[y, x]));
    let three = num(&mut a, 3.0);
    let three_x = a.mul(&[x, three]);
    let five = num(&mut a, 5.0);
    let five_x = a.mul(&[five, x]);
    assert_eq!(a.add(&[two_x, three_x]), five_x);
    let minus = a.neg(five_x);
    let zero = a.zero();
    assert_eq!(a.add(&[five_x, minus]), zero);
}

#[test]
fn like_powers_collect() {
    let mut a = arena();
    let x = sym(&mut a, q(0, 1));
    let inv = a.powi(x, -1);
    let one = a.one();
    assert_eq!(a.mul(&[x, inv]), one);
    let x2 = a.powi(x, 2);
    let x3 = a.powi(x, 3);
    assert_eq!(a.mul(&[x, x2]), x3);
    assert_eq!(a.mul(&[x, x, x]), x3);
    let x6 = a.powi(x, 6);
    assert_eq!(a.powi(x2, 3), x6);
    let r = a.func(Func::Sqrt, x);
    assert_eq!(a.mul(&[r, r]), x);
    assert_eq!(a.powi(r, 2), x);
    // Symbolic exponents add: x^t · x^alpha = x^(t + alpha).
    let t = sym(&mut a, Symbol::Time);
    let al = sym(&mut a, ALPHA);
    let xt = a.pow(x, t);
    let xa = a.pow(x, al);
    let sum = a.add(&[t, al]);
    let expected = a.pow(x, sum);
    assert_eq!(a.mul(&[xt, xa]), expected);
}

#[test]
fn integer_powers_distribute_over_products() {
    let mut a = arena();
    let x = sym(&mut a, q(0, 0));
    let y = sym(&mut a, q(1, 0));
    let three = num(&mut a, 3.0);
    let xy = a.mul(&[three, x, y]);
    let sq = a.powi(xy, 2);
    let nine = num(&mut a, 9.0);
    let x2 = a.powi(x, 2);
    let y2 = a.powi(y, 2);
    assert_eq!(sq, a.mul(&[nine, x2, y2]));
    // A half power does not distribute (it is not valid for negative factors).
    let half = num(&mut a, 0.5);
    let root = a.pow(xy, half);
    assert!(matches!(a.node(root), Node::Pow(..)));
}

/// The paper's law `M0·exp(−αt)` divides out, and so does its rate.
#[test]
fn exponential_mass_law_cancels() {
    let mut a = arena();
    let m0 = sym(&mut a, M0);
    let al = sym(&mut a, ALPHA);
    let t = sym(&mut a, Symbol::Time);
    let at = a.mul(&[al, t]);
    let minus_at = a.neg(at);
    let e = a.func(Func::Exp, minus_at);
    let law = a.mul(&[m0, e]);
    let one = a.one();
    assert_eq!(a.div(law, law), one);
    let inv = a.powi(law, -1);
    assert_eq!(a.mul(&[law, inv]), one);
    let rate = a.diff(law, Symbol::Time);
    let minus_alpha = a.neg(al);
    assert_eq!(a.div(rate, law), minus_alpha);

    // A law that would overflow numerically: M0·exp(1000 t).
    let k = num(&mut a, 1000.0);
    let kt = a.mul(&[k, t]);
    let e = a.func(Func::Exp, kt);
    let law = a.mul(&[m0, e]);
    let rate = a.diff(law, Symbol::Time);
    assert_eq!(a.div(rate, law), k);
    let at_big_t = a.eval(law, &|_| 1.0);
    assert!(at_big_t.is_infinite(), "the law itself overflows at t = 1");
}

#[test]
fn exp_and_ln() {
    let mut a = arena();
    let x = sym(&mut a, q(0, 0));
    let y = sym(&mut a, q(1, 0));
    let ex = a.func(Func::Exp, x);
    let ey = a.func(Func::Exp, y);
    let xy = a.add(&[x, y]);
    let exy = a.func(Func::Exp, xy);
    assert_eq!(a.mul(&[ex, ey]), exy);
    assert_eq!(a.func(Func::Ln, ex), x);
    let lx = a.func(Func::Ln, x);
    assert_eq!(a.func(Func::Exp, lx), x);
    let minus_x = a.neg(x);
    let emx = a.func(Func::Exp, minus_x);
    let one = a.one();
    assert_eq!(a.mul(&[ex, emx]), one);
    // (e^x)^3 = e^(3x)
    let three = num(&mut a, 3.0);
    let x3 = a.mul(&[three, x]);
    let e3 = a.func(Func::Exp, x3);
    assert_eq!(a.powi(ex, 3), e3);
}

#[test]
fn identities() {
    let mut a = arena();
    let x = sym(&mut a, q(0, 0));
    let (zero, one) = (a.zero(), a.one());
    assert_eq!(a.add(&[x, zero]), x);
    assert_eq!(a.mul(&[x, one]), x);
    assert_eq!(a.mul(&[x, zero]), zero);
    assert_eq!(a.pow(x, one), x);
    assert_eq!(a.pow(x, zero), one);
    assert_eq!(a.add(&[]), zero);
    assert_eq!(a.mul(&[]), one);
    assert_eq!(a.sub(x, x), zero);
}

#[test]
fn constants_fold_only_to_finite_values() {
    let mut a = arena();
    let two = num(&mut a, 2.0);
    let three = num(&mut a, 3.0);
    let five = a.add(&[two, three]);
    assert_eq!(a.as_const(five), Some(5.0));
    let p = a.pow(two, three);
    assert_eq!(a.as_const(p), Some(8.0));
    let zero = a.zero();
    let s = a.func(Func::Sin, zero);
    assert_eq!(a.as_const(s), Some(0.0));
    // 1/0 stays symbolic instead of becoming inf.
    let one = a.one();
    let inv0 = a.div(one, zero);
    assert_eq!(a.as_const(inv0), None);
    // 0/0 never becomes a NaN constant.
    let zz = a.div(zero, zero);
    assert!(a.as_const(zz).is_none_or(|v| !v.is_nan()));
    // ln 0, sqrt(−1), asin 2 stay symbolic.
    let ln0 = a.func(Func::Ln, zero);
    assert_eq!(a.as_const(ln0), None);
    let m1 = num(&mut a, -1.0);
    let r = a.func(Func::Sqrt, m1);
    assert_eq!(a.as_const(r), None);
    let asin2 = a.func(Func::Asin, two);
    assert_eq!(a.as_const(asin2), None);
    // Overflowing products stay unfolded.
    let big = num(&mut a, 1e200);
    let prod = a.mul(&[big, big]);
    assert!(a.as_const(prod).is_none_or(|v| v.is_finite()));
    let e = a.func(Func::Exp, big);
    assert_eq!(a.as_const(e), None);
    // −0 is 0.
    assert_eq!(num(&mut a, -0.0), zero);
}

/// Sums of products of sums stay factored.
#[test]
fn products_of_sums_are_not_expanded() {
    let mut a = arena();
    let x = sym(&mut a, q(0, 0));
    let y = sym(&mut a, q(1, 0));
    let s = a.add(&[x, y]);
    let d = a.sub(x, y);
    let p = a.mul(&[s, d]);
    match a.node(p) {
        Node::Mul(fs) => assert_eq!(fs.len(), 2),
        other => panic!("expected a product, got {other:?}"),
    }
}

/// Odd half-integer powers are square roots of integer powers (a fraction
/// of `powf`'s cost in generated right sides: drag's `(v·v)^(-1/2)`,
/// gravity's `(r·r)^(-3/2)`); they must agree with `powf` to rounding, and
/// only they take that route.
#[test]
fn half_odd_powers_agree_with_powf() {
    use lagc::ir::{half_odd_power, pow_value};
    for (exp, m) in [
        (0.5, Some(1)),
        (-0.5, Some(-1)),
        (1.5, Some(3)),
        (-1.5, Some(-3)),
        (4.5, Some(9)),
    ] {
        assert_eq!(half_odd_power(exp), m, "{exp}");
    }
    for exp in [0.25, 1.0, -2.0, 5.5, 0.3] {
        assert_eq!(half_odd_power(exp), None, "{exp}");
    }
    for exp in [0.5, -0.5, 1.5, -1.5, 2.5, -3.5, 4.5] {
        for base in [1e-6, 0.3, 1.0, 2.7, 1e5] {
            let (ours, libm) = (pow_value(base, exp), base.powf(exp));
            assert!(
                ((ours - libm) / libm).abs() < 4.0 * f64::EPSILON,
                "{base}^{exp}: {ours} vs {libm}"
            );
        }
    }
}

#[test]
fn a_number_times_a_sum_distributes_when_its_terms_collect() {
    // Issue 11's example: 48a + 48b − 1.5(24a + 24b) = 12a + 12b.
    let mut a = arena();
    let x = sym(&mut a, q(0, 0));
    let y = sym(&mut a, ALPHA);
    let c48 = num(&mut a, 48.0);
    let c24 = num(&mut a, 24.0);
    let c15 = num(&mut a, -1.5);
    let c12 = num(&mut a, 12.0);
    let t1 = a.mul(&[c48, x]);
    let t2 = a.mul(&[c48, y]);
    let u1 = a.mul(&[c24, x]);
    let u2 = a.mul(&[c24, y]);
    let inner = a.add(&[u1, u2]);
    let scaled = a.mul(&[c15, inner]);
    let e = a.add(&[t1, t2, scaled]);
    let v1 = a.mul(&[c12, x]);
    let v2 = a.mul(&[c12, y]);
    assert_eq!(e, a.add(&[v1, v2]));
    // In any order of the terms.
    assert_eq!(a.add(&[scaled, t2, t1]), e);
    // A sum whose terms collect with nothing stays one product: 2(a + b) + t.
    let two = num(&mut a, 2.0);
    let t = sym(&mut a, Symbol::Time);
    let xy = a.add(&[x, y]);
    let kept = a.mul(&[two, xy]);
    let e = a.add(&[kept, t]);
    match a.node(e) {
        Node::Add(ts) => assert!(ts.contains(&kept), "{}", a.display(e)),
        other => panic!("{other:?}"),
    }
}

/// `reachable` and the free-symbol unions reuse marks across calls: every
/// call must see all of its own nodes and symbols however much an earlier
/// call shared with it, and nothing of the earlier call's.
#[test]
fn walks_and_free_symbols_do_not_leak_between_calls() {
    let mut a = arena();
    let x = sym(&mut a, q(0, 0));
    let y = sym(&mut a, q(1, 0));
    let t = sym(&mut a, Symbol::Time);
    let sx = a.func(Func::Sin, x);
    let e1 = a.mul(&[sx, y]);
    let e2 = a.add(&[sx, t]);
    let sorted = |mut v: Vec<lagc::ir::ExprId>| {
        v.sort();
        v
    };
    let r1 = a.reachable(&[e1]);
    assert_eq!(sorted(r1.clone()), sorted(vec![x, sx, y, e1]));
    assert_eq!(r1.last(), Some(&e1));
    // `sx` and `x`, met by the first walk, are met again by the second.
    let r2 = a.reachable(&[e2]);
    assert_eq!(sorted(r2), sorted(vec![x, sx, t, e2]));
    let r12 = a.reachable(&[e1, e2]);
    assert_eq!(sorted(r12), sorted(vec![x, sx, y, e1, t, e2]));
    assert_eq!(a.dag_size(&[e2]), 4);
    // Unions of overlapping sets, one after the other.
    let m = sym(&mut a, M0);
    let e3 = a.mul(&[e1, e2, m]);
    let e4 = a.add(&[e2, x]);
    assert_eq!(
        a.free_symbols(e3),
        [q(0, 0), q(1, 0), Symbol::Time, M0].into_iter().collect()
    );
    assert_eq!(
        a.free_symbols(e4),
        [q(0, 0), Symbol::Time].into_iter().collect()
    );
}

/// `add` works on distinct terms and remembers what it builds, but must
/// give what summing copy by copy gives: a `c·S` that comes twice is like
/// itself and distributes, and coefficients are summed in the order of
/// the terms (floating-point addition does not associate).
#[test]
fn repeated_terms_sum_as_their_copies_would() {
    let mut a = arena();
    let x = sym(&mut a, q(0, 0));
    let y = sym(&mut a, ALPHA);
    let two = num(&mut a, 2.0);
    let xy = a.add(&[x, y]);
    let scaled = a.mul(&[two, xy]);
    // One copy stays one product; two copies distribute and collect.
    assert_eq!(a.add(&[scaled]), scaled);
    let four = num(&mut a, 4.0);
    let four_x = a.mul(&[four, x]);
    let four_y = a.mul(&[four, y]);
    let expected = a.add(&[four_x, four_y]);
    assert_eq!(a.add(&[scaled, scaled]), expected);
    let six = num(&mut a, 6.0);
    let t = sym(&mut a, Symbol::Time);
    let six_x = a.mul(&[six, x]);
    let six_y = a.mul(&[six, y]);
    let expected = a.add(&[six_x, six_y, t]);
    assert_eq!(a.add(&[scaled, t, scaled, scaled]), expected);
    // (0.1 + 0.6) + 0.1 = 0.7999999999999999, not 2·0.1 + 0.6 = 0.8.
    let (p1, p2) = (num(&mut a, 0.1), num(&mut a, 0.6));
    let (x1, x2) = (a.mul(&[p1, x]), a.mul(&[p2, x]));
    let e = a.add(&[x1, x2, x1]);
    let in_order = (0.1 + 0.6) + 0.1;
    assert_ne!(in_order, 2.0 * 0.1 + 0.6);
    let c = num(&mut a, in_order);
    assert_eq!(e, a.mul(&[c, x]), "{}", a.display(e));
}

/// The sum of one term is the term, but for a number times a long product
/// kept whole (`canon::SEALED_PRODUCT`): the sum flattens that into one
/// product, as it always has.
#[test]
fn one_term_is_its_own_sum_but_a_number_times_a_sealed_product() {
    let mut a = arena();
    let x = sym(&mut a, q(0, 0));
    let t = sym(&mut a, Symbol::Time);
    let three = num(&mut a, 3.0);
    let sin_x = a.func(Func::Sin, x);
    let xt = a.mul(&[x, t]);
    let three_xt = a.mul(&[three, xt]);
    let power = a.powi(x, 3);
    for e in [x, three, sin_x, xt, three_xt, power] {
        assert_eq!(a.add(&[e]), e, "{}", a.display(e));
    }
    // 13 distinct factors: kept whole as a factor of a product.
    let factors: Vec<_> = (0..13)
        .map(|k| {
            let s = sym(&mut a, q(k % 2, k / 2));
            a.func(Func::Sin, s)
        })
        .collect();
    let long = a.mul(&factors);
    let scaled = a.mul(&[three, long]);
    let Node::Mul(fs) = a.node(scaled).clone() else {
        panic!("{}", a.display(scaled))
    };
    assert_eq!(fs.len(), 2, "the long product stays one factor");
    let summed = a.add(&[scaled]);
    match a.node(summed) {
        Node::Mul(fs) => assert_eq!(fs.len(), 14, "{}", a.display(summed)),
        other => panic!("{other:?}"),
    }
}

/// Free-symbol sets beyond the first 64 symbol slots (kept as bits).
#[test]
fn free_symbols_beyond_64_symbols() {
    let mut a = arena();
    let syms: Vec<Symbol> = (0..150).map(|k| q(k, k % 3)).collect();
    let ids: Vec<_> = syms.iter().map(|&s| sym(&mut a, s)).collect();
    let sum = a.add(&ids);
    assert_eq!(a.free_symbols(sum), syms.iter().copied().collect());
    let tail = a.mul(&ids[100..]);
    assert!(a.depends_on(tail, syms[149]) && a.depends_on(tail, syms[100]));
    assert!(!a.depends_on(tail, syms[99]) && !a.depends_on(tail, syms[0]));
    assert_eq!(a.max_jet_order(tail, 120), Some(0));
    assert_eq!(a.max_jet_order(tail, 20), None);
    let grad = a.jacobian(&[tail], &[syms[0], syms[120]]).remove(0);
    assert!(a.is_zero(grad[0]) && !a.is_zero(grad[1]));
}
