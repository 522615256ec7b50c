//! Text and LaTeX forms.

use super::{arena, num, q, sym, ALPHA, M, M0};
use lagc::ir::{Arena, ExprId, Func, Symbol};

/// `M*(1 + t^2)*q1'' + M*t*q1'`, built term by term in the given order.
fn paper_lhs(a: &mut Arena, reversed: bool) -> ExprId {
    let m = sym(a, M);
    let t = sym(a, Symbol::Time);
    let (q1d, q1dd) = (sym(a, q(0, 1)), sym(a, q(0, 2)));
    let one = a.one();
    let t2 = a.powi(t, 2);
    let s = if reversed {
        a.add(&[t2, one])
    } else {
        a.add(&[one, t2])
    };
    let first = if reversed {
        a.mul(&[q1dd, s, m])
    } else {
        a.mul(&[m, s, q1dd])
    };
    let second = if reversed {
        a.mul(&[q1d, t, m])
    } else {
        a.mul(&[m, t, q1d])
    };
    if reversed {
        a.add(&[second, first])
    } else {
        a.add(&[first, second])
    }
}

#[test]
fn display_does_not_depend_on_construction_order() {
    let mut a = arena();
    let e = paper_lhs(&mut a, false);
    let mut b = arena();
    // Unrelated nodes built first shift every id in the second arena.
    let x = sym(&mut b, q(1, 3));
    let c = num(&mut b, 17.0);
    b.mul(&[x, c]);
    b.aux("f_9");
    let f = paper_lhs(&mut b, true);
    assert_eq!(a.display(e).to_string(), b.display(f).to_string());
    assert_eq!(a.display(e).to_string(), "M*t*q1' + M*(1 + t^2)*q1''");
    assert_eq!(a.latex(e), b.latex(f));
}

/// Auxiliary symbols sort by name, not by registration order.
#[test]
fn aux_symbols_sort_by_name() {
    let mut a = arena();
    let (f1, f2) = (a.aux("f_1"), a.aux("f_2"));
    let (e1, e2) = (a.symbol(f1), a.symbol(f2));
    let s = a.add(&[e2, e1]);
    let mut b = arena();
    let (g2, g1) = (b.aux("f_2"), b.aux("f_1"));
    let (e2, e1) = (b.symbol(g2), b.symbol(g1));
    let r = b.add(&[e1, e2]);
    assert_eq!(a.display(s).to_string(), "f_1 + f_2");
    assert_eq!(b.display(r).to_string(), "f_1 + f_2");
}

#[test]
fn display_forms() {
    let mut a = arena();
    let t = sym(&mut a, Symbol::Time);
    let (al, m, m0) = (sym(&mut a, ALPHA), sym(&mut a, M), sym(&mut a, M0));
    let q1d = sym(&mut a, q(0, 1));
    let one = a.one();
    let t2 = a.powi(t, 2);
    let s = a.add(&[one, t2]);

    let r = a.func(Func::Sqrt, s);
    assert_eq!(a.display(r).to_string(), "sqrt(1 + t^2)");
    let am = a.mul(&[al, m, q1d]);
    let e = a.neg(am);
    assert_eq!(a.display(e).to_string(), "-alpha*M*q1'");
    let ratio = a.div(t, s);
    assert_eq!(a.display(ratio).to_string(), "t/(1 + t^2)");
    let inv = a.div(one, r);
    assert_eq!(a.display(inv).to_string(), "1/sqrt(1 + t^2)");
    let diff = a.sub(al, ratio);
    assert_eq!(a.display(diff).to_string(), "alpha - t/(1 + t^2)");
    let at = a.mul(&[al, t]);
    let mat = a.neg(at);
    let ex = a.func(Func::Exp, mat);
    let law = a.mul(&[m0, ex]);
    assert_eq!(a.display(law).to_string(), "M0*exp(-alpha*t)");
    let two = num(&mut a, 2.0);
    let den = a.mul(&[two, m, t]);
    let frac = a.div(q1d, den);
    assert_eq!(a.display(frac).to_string(), "0.5*q1'/(M*t)");
    let p = a.pow(t, s);
    assert_eq!(a.display(p).to_string(), "t^(1 + t^2)");
    let q4 = sym(&mut a, q(0, 4));
    let q3 = sym(&mut a, q(1, 3));
    let j = a.add(&[q4, q3]);
    assert_eq!(a.display(j).to_string(), "q1^(4) + q2'''");
    let minus_two = num(&mut a, -2.0);
    let neg_sq = a.pow(q1d, minus_two);
    let sum = a.add(&[t, neg_sq]);
    assert_eq!(a.display(sum).to_string(), "t + 1/q1'^2");
}

#[test]
fn latex_forms() {
    let mut a = arena();
    let t = sym(&mut a, Symbol::Time);
    let (al, m, m0) = (sym(&mut a, ALPHA), sym(&mut a, M), sym(&mut a, M0));
    let q1d = sym(&mut a, q(0, 1));
    let one = a.one();
    let t2 = a.powi(t, 2);
    let s = a.add(&[one, t2]);
    let r = a.func(Func::Sqrt, s);
    let ratio = a.div(t, r);
    assert_eq!(a.latex(ratio), "\\frac{t}{\\sqrt{1 + t^{2}}}");
    let at = a.mul(&[al, t]);
    let mat = a.neg(at);
    let ex = a.func(Func::Exp, mat);
    let law = a.mul(&[m0, ex]);
    assert_eq!(a.latex(law), "M_{0} e^{-\\alpha t}");
    let sq = a.powi(q1d, 2);
    let e = a.mul(&[m, sq]);
    assert_eq!(a.latex(e), "M {q_{1}'}^{2}");
    let c = a.func(Func::Cos, q1d);
    assert_eq!(a.latex(c), "\\cos\\left(q_{1}'\\right)");
    // A power of a fourth derivative is braced: TeX refuses x^{(4)}^{2}.
    let q4 = sym(&mut a, q(0, 4));
    let q4_sq = a.powi(q4, 2);
    assert_eq!(a.latex(q4_sq), "{q_{1}^{(4)}}^{2}");
    assert_eq!(a.display(q4_sq).to_string(), "(q1^(4))^2");
}
