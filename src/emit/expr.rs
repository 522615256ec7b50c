//! IR expressions → Rust expressions (token trees), with every node used
//! more than once bound to a `let` first.
//!
//! Numbers are exact (`{:?}` is the shortest decimal that reads back to the
//! same `f64`) with an `_f64` suffix; integer powers become `powi`, odd
//! half-integer ones square roots of them (`x^-1.5` is `x.powi(3).sqrt()
//! .recip()`), other powers `powf` — the same choices as `ir::pow_value`, so the
//! generated code computes what `Arena::eval` computes. A sine and a cosine
//! of one argument are one `lagc_runtime::math::sin_cos` call. Parentheses are
//! written only where precedence needs them (rustc warns on the others).

use super::namer::Namer;
use crate::ir::{half_odd_power, postorder, Arena, ExprId, Func, Node, Symbol};
use proc_macro2::{Ident, Span, TokenStream};
use quote::quote;
use std::collections::{HashMap, HashSet};

/// Binding strength of a generated expression.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Prec {
    /// `if … { … } else { … }`: parenthesised wherever it is an operand.
    Conditional,
    Sum,
    Product,
    Unary,
    Postfix,
}

/// Straight-line code for several roots: `lets`, then one expression each.
pub struct Lowered {
    pub lets: Vec<TokenStream>,
    pub roots: Vec<TokenStream>,
}

/// Lowers `roots`; `symbol` names every free symbol's local variable.
/// Also how many of the `lets` the first `split` roots need: those come
/// first (the nodes are visited root by root), so code can compute the
/// first roots, then bind what the others alone read (an implicit model's
/// highest derivatives, once solved from the first).
pub fn lower_exprs_split(
    arena: &Arena,
    roots: &[ExprId],
    split: usize,
    symbol: &dyn Fn(Symbol) -> TokenStream,
    namer: &mut Namer,
) -> (Lowered, usize) {
    let prefix = sum_prefixes(arena, roots);
    let operands = |e: ExprId| -> Vec<ExprId> {
        match (prefix.get(&e), arena.node(e)) {
            (Some(&(p, len)), Node::Add(ts)) => {
                let mut v = vec![p];
                v.extend_from_slice(&ts[len..]);
                v
            }
            _ => arena.children(e),
        }
    };
    let order = postorder(roots, operands, &mut HashSet::new());
    // The nodes the first roots reach: a prefix of `order` (depth first,
    // root by root).
    let early = postorder(
        &roots[..split.min(roots.len())],
        operands,
        &mut HashSet::new(),
    )
    .len();
    let mut early_lets = 0;
    let mut uses: HashMap<ExprId, usize> = HashMap::new();
    for &e in &order {
        for c in operands(e) {
            *uses.entry(c).or_default() += 1;
        }
    }
    for &r in roots {
        *uses.entry(r).or_default() += 1;
    }
    let mut writer = Writer {
        arena,
        symbol,
        bound: HashMap::new(),
        prefix,
    };
    // `sin u` and `cos u` both needed: one `sin_cos` call (C compilers
    // do the same with `sincos`), bound where the first of them falls.
    let mut trig: HashMap<ExprId, [Option<ExprId>; 2]> = HashMap::new();
    for &e in &order {
        match arena.node(e) {
            Node::Func(Func::Sin, u) => trig.entry(*u).or_default()[0] = Some(e),
            Node::Func(Func::Cos, u) => trig.entry(*u).or_default()[1] = Some(e),
            _ => {}
        }
    }
    let mut lets = Vec::new();
    for (at, &e) in order.iter().enumerate() {
        if at == early {
            early_lets = lets.len();
        }
        if writer.bound.contains_key(&e) {
            continue;
        }
        if let Node::Func(Func::Sin | Func::Cos, u) = arena.node(e) {
            if let Some([Some(sin), Some(cos)]) = trig.get(u).copied() {
                let argument = writer.expr(*u).0;
                let (s, c) = (namer.fresh("e"), namer.fresh("e"));
                lets.push(quote! { let (#s, #c) = lagc_runtime::math::sin_cos(#argument); });
                writer.bound.insert(sin, s);
                writer.bound.insert(cos, c);
                continue;
            }
        }
        let shared = uses.get(&e).copied().unwrap_or(0) > 1;
        if shared
            && matches!(
                arena.node(e),
                Node::Add(_) | Node::Mul(_) | Node::Pow(..) | Node::Func(..) | Node::Select(..)
            )
        {
            let (code, _) = writer.expr(e);
            let name = namer.fresh("e");
            lets.push(quote! { let #name = #code; });
            writer.bound.insert(e, name);
        }
    }
    if early >= order.len() {
        early_lets = lets.len();
    }
    let roots = roots.iter().map(|&r| writer.expr(r).0).collect();
    (Lowered { lets, roots }, early_lets)
}

/// For each sum among the nodes reachable from `roots`, the longest other
/// reachable sum whose terms begin its terms (`a + b` of `a + b + c`), and
/// that prefix's length. Writing `(a + b) + c` from the prefix's value is
/// what `a + b + c` computes anyway (left to right), so the sharing changes
/// no bit of the result; it is the common sub-sum of cumulative sums (the
/// velocities of a chain's links), one addition instead of a chain.
fn sum_prefixes(arena: &Arena, roots: &[ExprId]) -> HashMap<ExprId, (ExprId, usize)> {
    let sums: HashMap<&[ExprId], ExprId> = arena
        .reachable(roots)
        .into_iter()
        .filter_map(|e| match arena.node(e) {
            Node::Add(ts) => Some((&ts[..], e)),
            _ => None,
        })
        .collect();
    let mut prefix = HashMap::new();
    for (&terms, &e) in &sums {
        if let Some((len, p)) = (2..terms.len())
            .rev()
            .find_map(|len| sums.get(&terms[..len]).map(|&p| (len, p)))
        {
            prefix.insert(e, (p, len));
        }
    }
    prefix
}

struct Writer<'a> {
    arena: &'a Arena,
    symbol: &'a dyn Fn(Symbol) -> TokenStream,
    bound: HashMap<ExprId, Ident>,
    /// [`sum_prefixes`].
    prefix: HashMap<ExprId, (ExprId, usize)>,
}

/// A float literal: `1.5_f64`, `1e-9_f64` (non-negative `v`).
fn literal(v: f64) -> TokenStream {
    if v.is_nan() {
        return quote! { f64::NAN };
    }
    if v.is_infinite() {
        return quote! { f64::INFINITY };
    }
    let lit = syn::LitFloat::new(&format!("{v:?}_f64"), Span::call_site());
    quote! { #lit }
}

/// A signed float literal as an expression: `-1.5_f64`.
pub fn signed_literal(v: f64) -> TokenStream {
    constant(v).0
}

fn constant(v: f64) -> (TokenStream, Prec) {
    if v < 0.0 {
        let lit = literal(-v);
        (quote! { -#lit }, Prec::Unary)
    } else {
        (literal(v), Prec::Postfix)
    }
}

fn wrap((code, prec): (TokenStream, Prec), at_least: Prec) -> TokenStream {
    if prec < at_least {
        quote! { (#code) }
    } else {
        code
    }
}

impl Writer<'_> {
    fn expr(&self, e: ExprId) -> (TokenStream, Prec) {
        if let Some(name) = self.bound.get(&e) {
            return (quote! { #name }, Prec::Postfix);
        }
        match self.arena.node(e) {
            Node::Const(v) => constant(*v),
            Node::Sym(s) => ((self.symbol)(*s), Prec::Postfix),
            Node::Func(f, a) => {
                let receiver = wrap(self.expr(*a), Prec::Postfix);
                let method = Ident::new(f.name(), Span::call_site());
                (quote! { #receiver.#method() }, Prec::Postfix)
            }
            Node::Pow(b, x) => self.pow(*b, *x),
            Node::Mul(fs) => self.product(fs, false),
            Node::Add(ts) => self.sum(e, ts),
            Node::Select(g, a, b) => {
                let g = wrap(self.expr(*g), Prec::Sum);
                let a = self.expr(*a).0;
                let b = self.expr(*b).0;
                let zero = literal(0.0);
                (
                    quote! { if #g < #zero { #a } else { #b } },
                    Prec::Conditional,
                )
            }
        }
    }

    fn pow(&self, base: ExprId, exp: ExprId) -> (TokenStream, Prec) {
        if self.arena.as_const(exp) == Some(-1.0) {
            let below = wrap(self.expr(base), Prec::Unary);
            let one = literal(1.0);
            return (quote! { #one / #below }, Prec::Product);
        }
        let receiver = wrap(self.expr(base), Prec::Postfix);
        if let Some(m) = self.arena.as_const(exp).and_then(half_odd_power) {
            let root = if m.abs() == 1 {
                quote! { #receiver.sqrt() }
            } else {
                let n = proc_macro2::Literal::i32_unsuffixed(m.abs());
                quote! { #receiver.powi(#n).sqrt() }
            };
            return if m < 0 {
                (quote! { #root.recip() }, Prec::Postfix)
            } else {
                (root, Prec::Postfix)
            };
        }
        match self.arena.as_const(exp) {
            Some(v) if v.fract() == 0.0 && v.abs() <= f64::from(i32::MAX) => {
                let n = proc_macro2::Literal::i32_unsuffixed((v.abs()) as i32);
                if v < 0.0 {
                    (quote! { #receiver.powi(-#n) }, Prec::Postfix)
                } else {
                    (quote! { #receiver.powi(#n) }, Prec::Postfix)
                }
            }
            _ => {
                let exponent = self.expr(exp).0;
                (quote! { #receiver.powf(#exponent) }, Prec::Postfix)
            }
        }
    }

    /// The numeric coefficient of a product or constant, if it is negative.
    fn is_negative(&self, e: ExprId) -> bool {
        if self.bound.contains_key(&e) {
            return false;
        }
        match self.arena.node(e) {
            Node::Const(v) => *v < 0.0,
            Node::Mul(fs) => self.arena.as_const(fs[0]).is_some_and(|c| c < 0.0),
            _ => false,
        }
    }

    /// `−e` for a term with `is_negative(e)`.
    fn negated(&self, e: ExprId) -> (TokenStream, Prec) {
        match self.arena.node(e) {
            Node::Const(v) => constant(-v),
            Node::Mul(fs) => self.product(fs, true),
            _ => self.expr(e),
        }
    }

    fn sum(&self, e: ExprId, terms: &[ExprId]) -> (TokenStream, Prec) {
        let mut code = TokenStream::new();
        // The value of a bound prefix sum, then the rest.
        let start = match self.prefix.get(&e) {
            Some(&(p, len)) if self.bound.contains_key(&p) => {
                code = self.expr(p).0;
                len
            }
            _ => 0,
        };
        for (i, &t) in terms.iter().enumerate().skip(start) {
            if i == 0 {
                code = wrap(self.expr(t), Prec::Sum);
            } else if self.is_negative(t) {
                let term = wrap(self.negated(t), Prec::Product);
                code = quote! { #code - #term };
            } else {
                let term = wrap(self.expr(t), Prec::Product);
                code = quote! { #code + #term };
            }
        }
        (code, Prec::Sum)
    }

    /// A product written as numerator / denominator; `flip` negates the
    /// numeric coefficient.
    fn product(&self, factors: &[ExprId], flip: bool) -> (TokenStream, Prec) {
        let (mut coefficient, rest) = match self.arena.as_const(factors[0]) {
            Some(c) => (c, &factors[1..]),
            None => (1.0, factors),
        };
        if flip {
            coefficient = -coefficient;
        }
        let mut numerator: Vec<(TokenStream, Prec)> = Vec::new();
        let mut denominator: Vec<(TokenStream, Prec)> = Vec::new();
        for &f in rest {
            match self.reciprocal(f) {
                Some(d) => denominator.push(d),
                None => numerator.push(self.expr(f)),
            }
        }
        let negative = coefficient < 0.0;
        let magnitude = coefficient.abs();
        if magnitude != 1.0 || numerator.is_empty() {
            numerator.insert(0, (literal(magnitude), Prec::Postfix));
        }
        let mut code = TokenStream::new();
        for (i, factor) in numerator.into_iter().enumerate() {
            if i == 0 {
                if negative {
                    let first = wrap(factor, Prec::Unary);
                    code = quote! { -#first };
                } else {
                    code = wrap(factor, Prec::Product);
                }
            } else {
                let factor = wrap(factor, Prec::Unary);
                code = quote! { #code * #factor };
            }
        }
        let single = denominator.len() == 1;
        let mut below = TokenStream::new();
        for (i, factor) in denominator.into_iter().enumerate() {
            if i == 0 {
                below = wrap(factor, if single { Prec::Unary } else { Prec::Product });
            } else {
                let factor = wrap(factor, Prec::Unary);
                below = quote! { #below * #factor };
            }
        }
        if !below.is_empty() {
            if single {
                code = quote! { #code / #below };
            } else {
                code = quote! { #code / (#below) };
            }
        }
        (code, Prec::Product)
    }

    /// For a factor `b^(−k)` (k = 1, 1/2 or an integer), `b^k` to divide by.
    fn reciprocal(&self, factor: ExprId) -> Option<(TokenStream, Prec)> {
        if self.bound.contains_key(&factor) {
            return None;
        }
        let Node::Pow(base, exp) = self.arena.node(factor) else {
            return None;
        };
        let v = self.arena.as_const(*exp)?;
        if v >= 0.0 {
            return None;
        }
        let receiver = || wrap(self.expr(*base), Prec::Postfix);
        if v == -1.0 {
            Some(self.expr(*base))
        } else if v == -0.5 {
            let r = receiver();
            Some((quote! { #r.sqrt() }, Prec::Postfix))
        } else if v.fract() == 0.0 && v.abs() <= f64::from(i32::MAX) {
            let r = receiver();
            let n = proc_macro2::Literal::i32_unsuffixed((-v) as i32);
            Some((quote! { #r.powi(#n) }, Prec::Postfix))
        } else {
            None
        }
    }
}
