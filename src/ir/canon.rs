//! The canonicalising constructors: every expression is built through them,
//! so equal expressions (up to the rules below) share one node.
//!
//! Rules: constant folding when the result is finite; flat sums and
//! products (a product of more than [`SEALED_PRODUCT`] factors stays one
//! factor of the products it enters), sorted by a structural order that does not depend on
//! construction history; like terms and like powers collected, a number
//! times a sum distributed when its terms collect with others;
//! `exp(a)·exp(b) → exp(a+b)`, `(e^a)^b → e^(ab)`; `(a·b)^n → a^n·b^n` and
//! `(x^a)^n → x^(an)` for integer `n`; `sqrt(x) → x^(1/2)`. Products of sums
//! are never expanded: that keeps the DAG small.

use super::expr::{Arena, ExprId, FxMap, Node, Sequence, Symbol};
use crate::syntax::ast::Func;
use std::cmp::Ordering;

/// A product with more factors than this is not flattened into a product
/// that it is a factor of: it stays one factor, shared. The chain rule
/// multiplies a derivative by one more factor per level of nesting
/// (`sin(sin(…(u)))' = cos(sin(…))·…·cos(u)·u'`); flattened, level `j`
/// would be a new product of `j` factors, and a second derivative `j` more
/// of them — `O(d³)` for a nesting `d` deep. Sealed every few factors, each
/// level adds a product of at most this many factors to the DAG. Products
/// of models written by hand stay below it, and are flat as before.
pub(crate) const SEALED_PRODUCT: usize = 12;

/// How many times `mul` may re-run on its own output when collecting powers
/// produced a new product (e.g. `(a·b)^(1/2)·(a·b)^(1/2) → a·b`).
const MUL_RENORMALISE_DEPTH: u32 = 3;

/// The value of a function at a number (shared by folding and `eval`).
pub fn apply_func(f: Func, x: f64) -> f64 {
    f.apply(x)
}

/// `base^exp` as numbers, with `powi`/`sqrt` where they are exact.
pub fn pow_value(base: f64, exp: f64) -> f64 {
    if let Some(m) = half_odd_power(exp) {
        // √(x^|m|), inverted for m < 0: a square root and a few products
        // cost a fraction of `powf`, and drag and gravity laws put
        // `(v·v)^(-1/2)` and `(r·r)^(-3/2)` into many right sides.
        let root = if m.abs() == 1 {
            base.sqrt()
        } else {
            base.powi(m.abs()).sqrt()
        };
        if m < 0 {
            root.recip()
        } else {
            root
        }
    } else if exp.fract() == 0.0 && exp.abs() <= f64::from(i32::MAX) {
        base.powi(exp as i32)
    } else {
        base.powf(exp)
    }
}

/// `m` when `exp = m/2` with `m` odd and `|m| ≤ 9`: the powers computed as
/// square roots of integer powers (`x^(-3/2) = 1/√(x³)`), by
/// [`pow_value`] and by the generated code alike.
pub fn half_odd_power(exp: f64) -> Option<i32> {
    let twice = 2.0 * exp;
    (twice.fract() == 0.0 && twice.abs() <= 9.0 && (twice as i32) % 2 != 0).then_some(twice as i32)
}

fn is_integer(v: f64) -> bool {
    v.is_finite() && v.fract() == 0.0
}

impl Arena {
    /// The canonical sum of `terms`. Equal terms may come many times (a
    /// Jacobian's sum of the `O(N)` equal partials `c·∂S_k/∂x` of a row):
    /// everything that builds or interns nodes is done once per distinct
    /// term and remembered, and only the cheap part — copying ids and
    /// adding coefficients, in the order of the terms — is done per copy.
    /// The result is that of doing it all per copy: the memos hold values
    /// of pure functions of the arena, and the coefficients are summed in
    /// the same order.
    pub fn add(&mut self, terms: &[ExprId]) -> ExprId {
        // One term is its own sum (most of the calls of a Jacobian's
        // product rule, where one factor moves): returned before the
        // general path rebuilds and re-interns it. (That path would also
        // intern `a·b` on splitting `c·a·b`, a node nothing refers to.)
        if let [t] = *terms {
            if self.sum_of_itself(t) {
                return t;
            }
        }
        // (rest, coefficient): a term is `coefficient · rest`; a constant has
        // rest = 1. `index` maps a rest to its entry while merging is finite.
        let mut entries: Vec<(ExprId, f64)> = Vec::new();
        let mut flat = Vec::with_capacity(terms.len());
        for &t in terms {
            match self.node(t) {
                Node::Add(ts) => flat.extend_from_slice(ts),
                _ => flat.push(t),
            }
        }
        self.distribute_collecting(&mut flat);
        // Sized for every term at once: grown from empty, the tables of
        // the large sums (a few hundred terms) were rehashed eight times,
        // about 6 % of `lagc derive` of the 100-link pendulum.
        let mut index: FxMap<ExprId, usize> = fx_map_with_capacity(flat.len());
        // Splitting `c·a·b` interns `a·b`: done once per such term.
        let mut split: FxMap<ExprId, (f64, ExprId)> = FxMap::default();
        let count = flat.len();
        for t in flat {
            let (c, rest) = match self.node(t) {
                Node::Mul(fs) if fs.len() > 2 => match split.get(&t) {
                    Some(&known) => known,
                    None => {
                        let known = self.split_coefficient(t);
                        if split.capacity() == 0 {
                            split.reserve(count);
                        }
                        split.insert(t, known);
                        known
                    }
                },
                _ => self.split_coefficient(t),
            };
            match index.get(&rest) {
                Some(&i) if (entries[i].1 + c).is_finite() => entries[i].1 += c,
                _ => {
                    index.insert(rest, entries.len());
                    entries.push((rest, c));
                }
            }
        }
        entries.retain(|&(_, c)| c != 0.0);
        entries.sort_by(|a, b| self.cmp(a.0, b.0).then(a.1.total_cmp(&b.1)));
        let built: Vec<ExprId> = entries
            .into_iter()
            .map(|(rest, c)| self.scaled(c, rest))
            .collect();
        match built.len() {
            0 => self.zero(),
            1 => built[0],
            _ => self.intern_sequence(Sequence::Add, &built),
        }
    }

    /// Replaces each term `c·S` (a number times a sum) of `flat` by the
    /// terms of `S` times `c` when one of them is like a term outside `S`
    /// (`2·(a + b) − 3·(a + c) → −a + 2b − 3c`): the rewrite that lets like
    /// terms collect, and only then — a numeric factor over a sum whose
    /// terms collect with nothing is one multiplication, distributed it is
    /// one per term. Repeats while distributing brings new such terms in.
    /// Depends on the multiset of terms only, never on their order.
    ///
    /// Worked on the distinct terms (in order of first appearance): a term
    /// that comes twice is like itself, so every copy of a `c·S` that
    /// comes more than once is distributed, as the term-by-term rule
    /// would distribute each copy.
    fn distribute_collecting(&mut self, flat: &mut Vec<ExprId>) {
        loop {
            if !flat.iter().any(|&t| self.scaled_sum(t).is_some()) {
                return;
            }
            // The distinct terms of `flat`, first appearance first, and how
            // often each comes; `which[p]`: the distinct term at position
            // `p` of `flat`.
            let mut slot: FxMap<ExprId, usize> = fx_map_with_capacity(flat.len());
            let mut distinct: Vec<(ExprId, u32)> = Vec::new();
            let mut which: Vec<usize> = Vec::with_capacity(flat.len());
            for &t in flat.iter() {
                let i = *slot.entry(t).or_insert(distinct.len());
                if i == distinct.len() {
                    distinct.push((t, 0));
                }
                distinct[i].1 += 1;
                which.push(i);
            }
            // `scaled[i]`: distinct term `i` as `(c, S)` when it is `c·S`.
            let scaled: Vec<Option<(f64, ExprId)>> =
                distinct.iter().map(|&(t, _)| self.scaled_sum(t)).collect();
            // rest → the first distinct term contributing it (itself, or
            // for `c·S` one of the terms of `S`); `hit[i]`: a copy of term
            // `i` shares a rest with another term of `flat` (another copy
            // of itself included).
            let mut owner: FxMap<ExprId, usize> = fx_map_with_capacity(flat.len());
            let mut hit: Vec<bool> = distinct.iter().map(|&(_, n)| n > 1).collect();
            for i in 0..distinct.len() {
                let inner = match scaled[i] {
                    Some((_, sum)) => self.children(sum),
                    None => vec![distinct[i].0],
                };
                for t in inner {
                    let (_, rest) = self.split_coefficient(t);
                    match owner.get(&rest) {
                        Some(&j) if j != i => {
                            hit[i] = true;
                            hit[j] = true;
                        }
                        Some(_) => {}
                        None => {
                            owner.insert(rest, i);
                        }
                    }
                }
            }
            if !(0..distinct.len()).any(|i| hit[i] && scaled[i].is_some()) {
                return;
            }
            // Each distributed term's replacement, built at its first copy.
            let mut spread: Vec<Option<Vec<ExprId>>> = vec![None; distinct.len()];
            let mut out = Vec::with_capacity(flat.len());
            for (&t, &i) in flat.iter().zip(&which) {
                match scaled[i] {
                    Some((c, sum)) if hit[i] => {
                        if spread[i].is_none() {
                            let k = self.constant(c);
                            let terms: Vec<ExprId> = self
                                .children(sum)
                                .into_iter()
                                .map(|u| self.mul(&[k, u]))
                                .collect();
                            spread[i] = Some(terms);
                        }
                        out.extend_from_slice(spread[i].as_deref().unwrap_or_default());
                    }
                    _ => out.push(t),
                }
            }
            *flat = out;
        }
    }

    /// `t` as `(c, S)` when it is a number times a sum.
    fn scaled_sum(&self, t: ExprId) -> Option<(f64, ExprId)> {
        match self.node(t) {
            Node::Mul(fs) if fs.len() == 2 => match (self.node(fs[0]), self.node(fs[1])) {
                (Node::Const(c), Node::Add(_)) => Some((*c, fs[1])),
                _ => None,
            },
            _ => None,
        }
    }

    /// Whether the sum of the one term `t` is `t` itself, as the general
    /// path would build it: every node but a sum, and but a number times a
    /// product (`c·P`, whose factors the general path would flatten into
    /// `c·p1·p2…`).
    fn sum_of_itself(&self, t: ExprId) -> bool {
        match self.node(t) {
            Node::Add(_) => false,
            Node::Mul(fs) => match fs[..] {
                [c, p] => {
                    !(matches!(self.node(c), Node::Const(_))
                        && matches!(self.node(p), Node::Mul(_)))
                }
                _ => true,
            },
            _ => true,
        }
    }

    /// `t = c · rest` with `rest` free of a numeric coefficient.
    fn split_coefficient(&mut self, t: ExprId) -> (f64, ExprId) {
        match self.node(t) {
            Node::Const(v) => (*v, self.one()),
            Node::Mul(fs) => match self.node(fs[0]) {
                Node::Const(c) => {
                    let c = *c;
                    let rest = if fs.len() == 2 {
                        fs[1]
                    } else {
                        self.intern_product_tail(t)
                    };
                    (c, rest)
                }
                _ => (1.0, t),
            },
            _ => (1.0, t),
        }
    }

    /// `c · rest` for a canonical coefficient-free `rest`.
    fn scaled(&mut self, c: f64, rest: ExprId) -> ExprId {
        if c == 1.0 {
            return rest;
        }
        if self.is_one(rest) {
            return self.constant(c);
        }
        let k = self.constant(c);
        let mut factors = std::mem::take(&mut self.scratch);
        factors.clear();
        factors.push(k);
        match self.node(rest) {
            Node::Mul(fs) => factors.extend_from_slice(fs),
            _ => factors.push(rest),
        }
        let product = self.intern_sequence(Sequence::Mul, &factors);
        self.scratch = factors;
        product
    }

    pub fn mul(&mut self, factors: &[ExprId]) -> ExprId {
        self.mul_depth(factors, 0)
    }

    fn mul_depth(&mut self, factors: &[ExprId], depth: u32) -> ExprId {
        let mut coefficient = 1.0;
        // Constants whose product with `coefficient` would overflow.
        let mut loose: Vec<f64> = Vec::new();
        let mut bases: Vec<(ExprId, Vec<ExprId>)> = Vec::new();
        let mut exp_args: Vec<ExprId> = Vec::new();
        let mut flat = Vec::with_capacity(factors.len());
        for &f in factors {
            match self.node(f) {
                Node::Mul(fs) if fs.len() <= SEALED_PRODUCT => flat.extend_from_slice(fs),
                // A long product stays one factor (its number comes out).
                Node::Mul(fs) => match self.node(fs[0]) {
                    Node::Const(_) => {
                        flat.push(fs[0]);
                        let rest = self.intern_product_tail(f);
                        flat.push(rest);
                    }
                    _ => flat.push(f),
                },
                _ => flat.push(f),
            }
        }
        let mut index: FxMap<ExprId, usize> = fx_map_with_capacity(flat.len());
        for f in flat {
            let (base, exp) = match self.node(f) {
                Node::Const(c) => {
                    let c = *c;
                    if c == 0.0 {
                        return self.zero();
                    }
                    if (coefficient * c).is_finite() {
                        coefficient *= c;
                    } else {
                        loose.push(c);
                    }
                    continue;
                }
                Node::Func(Func::Exp, a) => {
                    exp_args.push(*a);
                    continue;
                }
                Node::Pow(b, e) => (*b, *e),
                _ => (f, self.one()),
            };
            match index.get(&base) {
                Some(&i) => bases[i].1.push(exp),
                None => {
                    index.insert(base, bases.len());
                    bases.push((base, vec![exp]));
                }
            }
        }
        let mut out: Vec<ExprId> = Vec::with_capacity(bases.len() + 1);
        let mut renormalise = false;
        for (base, exps) in bases {
            let exp = if exps.len() == 1 {
                exps[0]
            } else {
                self.add(&exps)
            };
            let p = self.pow(base, exp);
            renormalise |= match self.node(p) {
                Node::Const(_) | Node::Mul(_) | Node::Func(Func::Exp, _) => true,
                Node::Pow(b, _) => *b != base,
                _ => p != base,
            };
            out.push(p);
        }
        if !exp_args.is_empty() {
            let sum = self.add(&exp_args);
            let e = self.func(Func::Exp, sum);
            renormalise |= !matches!(self.node(e), Node::Func(Func::Exp, _));
            out.push(e);
        }
        if renormalise && depth < MUL_RENORMALISE_DEPTH {
            let c = self.constant(coefficient);
            out.push(c);
            for v in loose {
                let k = self.constant(v);
                out.push(k);
            }
            return self.mul_depth(&out, depth + 1);
        }
        out.retain(|&p| !self.is_one(p));
        out.sort_by(|&a, &b| self.cmp(a, b));
        if loose.is_empty() && out.is_empty() {
            return self.constant(coefficient);
        }
        if loose.is_empty() && coefficient == 1.0 && out.len() == 1 {
            return out[0];
        }
        let mut all: Vec<ExprId> = Vec::with_capacity(out.len() + 1 + loose.len());
        if coefficient != 1.0 {
            all.push(self.constant(coefficient));
        }
        for v in loose {
            all.push(self.constant(v));
        }
        all.extend(out);
        if all.len() == 1 {
            return all[0];
        }
        self.intern_sequence(Sequence::Mul, &all)
    }

    pub fn pow(&mut self, base: ExprId, exp: ExprId) -> ExprId {
        let (b, e) = (self.as_const(base), self.as_const(exp));
        if e == Some(0.0) {
            return self.one();
        }
        if e == Some(1.0) {
            return base;
        }
        if let (Some(b), Some(e)) = (b, e) {
            let v = pow_value(b, e);
            if v.is_finite() {
                return self.constant(v);
            }
        }
        if b == Some(1.0) {
            return self.one();
        }
        let integer_exp = e.filter(|&n| is_integer(n));
        match (self.node(base).clone(), integer_exp) {
            (Node::Func(Func::Exp, a), _) => {
                let arg = self.mul(&[a, exp]);
                self.func(Func::Exp, arg)
            }
            (Node::Pow(b0, e0), Some(_)) => {
                let e = self.mul(&[e0, exp]);
                self.pow(b0, e)
            }
            (Node::Mul(fs), Some(_)) => {
                let powered: Vec<ExprId> = fs.iter().map(|&f| self.pow(f, exp)).collect();
                self.mul(&powered)
            }
            _ => self.intern(Node::Pow(base, exp)),
        }
    }

    pub fn powi(&mut self, base: ExprId, n: i32) -> ExprId {
        let e = self.constant(f64::from(n));
        self.pow(base, e)
    }

    pub fn func(&mut self, f: Func, arg: ExprId) -> ExprId {
        if f == Func::Sqrt {
            let half = self.constant(0.5);
            return self.pow(arg, half);
        }
        if let Some(x) = self.as_const(arg) {
            let v = apply_func(f, x);
            if v.is_finite() {
                return self.constant(v);
            }
        }
        match (f, self.node(arg)) {
            (Func::Exp, Node::Func(Func::Ln, x)) | (Func::Ln, Node::Func(Func::Exp, x)) => *x,
            _ => self.intern(Node::Func(f, arg)),
        }
    }

    /// `if g < 0 then a else b`: one branch when both are equal or `g` is
    /// a number.
    pub fn select(&mut self, g: ExprId, a: ExprId, b: ExprId) -> ExprId {
        if a == b {
            return a;
        }
        if let Some(v) = self.as_const(g) {
            return if v < 0.0 { a } else { b };
        }
        self.intern(Node::Select(g, a, b))
    }

    pub fn neg(&mut self, a: ExprId) -> ExprId {
        let m = self.constant(-1.0);
        self.mul(&[m, a])
    }

    pub fn sub(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let nb = self.neg(b);
        self.add(&[a, nb])
    }

    pub fn div(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let inv = self.powi(b, -1);
        self.mul(&[a, inv])
    }

    /// The canonical order of sibling terms and factors: structural, so it
    /// never depends on the order in which nodes were built. A factor is
    /// ordered by its base first (`x` next to `x^2`), then its exponent.
    pub(crate) fn cmp(&self, a: ExprId, b: ExprId) -> Ordering {
        if a == b {
            return Ordering::Equal;
        }
        let (ba, ea) = self.base_exp(a);
        let (bb, eb) = self.base_exp(b);
        if ba != bb {
            return self.cmp_base(ba, bb);
        }
        match (ea, eb) {
            (Some(x), Some(y)) => self.cmp(x, y),
            (None, Some(y)) => self.cmp_with_one(y).reverse(),
            (Some(x), None) => self.cmp_with_one(x),
            (None, None) => Ordering::Equal,
        }
    }

    fn base_exp(&self, e: ExprId) -> (ExprId, Option<ExprId>) {
        match self.node(e) {
            Node::Pow(b, x) => (*b, Some(*x)),
            _ => (e, None),
        }
    }

    /// `e` compared with the constant 1 (an implied exponent).
    fn cmp_with_one(&self, e: ExprId) -> Ordering {
        match self.node(e) {
            Node::Const(v) => v.total_cmp(&1.0),
            _ => Ordering::Greater,
        }
    }

    fn cmp_base(&self, a: ExprId, b: ExprId) -> Ordering {
        if a == b {
            return Ordering::Equal;
        }
        let rank = self.rank(a).cmp(&self.rank(b));
        if rank != Ordering::Equal {
            return rank;
        }
        if !matches!(self.node(a), Node::Const(_) | Node::Sym(_)) {
            let key = (a.min(b), a.max(b));
            let known = self.order_memo.borrow().get(&key).copied();
            let order = match known {
                Some(order) => order,
                None => {
                    let order = self.cmp_composite(key.0, key.1);
                    self.order_memo.borrow_mut().insert(key, order);
                    order
                }
            };
            return if a < b { order } else { order.reverse() };
        }
        self.cmp_composite(a, b)
    }

    /// [`Arena::cmp_base`] of two nodes of one rank, by their structure.
    fn cmp_composite(&self, a: ExprId, b: ExprId) -> Ordering {
        match (self.node(a), self.node(b)) {
            (Node::Const(x), Node::Const(y)) => x.total_cmp(y),
            (Node::Sym(s), Node::Sym(t)) => self.cmp_symbol(*s, *t),
            (Node::Func(f, x), Node::Func(g, y)) => f.cmp(g).then_with(|| self.cmp(*x, *y)),
            (Node::Func(..), Node::Select(..)) => Ordering::Less,
            (Node::Select(..), Node::Func(..)) => Ordering::Greater,
            (Node::Select(g1, a1, b1), Node::Select(g2, a2, b2)) => self
                .cmp(*g1, *g2)
                .then_with(|| self.cmp(*a1, *a2))
                .then_with(|| self.cmp(*b1, *b2)),
            (Node::Pow(b1, e1), Node::Pow(b2, e2)) => {
                self.cmp(*b1, *b2).then_with(|| self.cmp(*e1, *e2))
            }
            (Node::Add(xs), Node::Add(ys)) | (Node::Mul(xs), Node::Mul(ys)) => xs
                .iter()
                .zip(ys.iter())
                .map(|(&x, &y)| self.cmp(x, y))
                .find(|o| *o != Ordering::Equal)
                .unwrap_or_else(|| xs.len().cmp(&ys.len())),
            _ => Ordering::Equal,
        }
    }

    /// Kind order for display: numbers, params/masses, `t`, composite
    /// expressions, and the jet variables last (`M*t*q1'`).
    fn rank(&self, e: ExprId) -> u8 {
        match self.node(e) {
            Node::Const(_) => 0,
            Node::Sym(Symbol::Jet { .. }) => 7,
            Node::Sym(Symbol::Time) => 2,
            Node::Sym(_) => 1,
            Node::Func(..) | Node::Select(..) => 3,
            Node::Pow(..) => 4,
            Node::Mul(_) => 5,
            Node::Add(_) => 6,
        }
    }
}

/// Symbols by kind, then index; auxiliary symbols by name, because their
/// indices follow the order in which they were registered.
fn symbol_key(s: Symbol) -> (u8, u32, u32) {
    match s {
        Symbol::Param(i) => (0, i, 0),
        Symbol::Mass(i) => (1, i, 0),
        Symbol::Aux(i) => (2, i, 0),
        Symbol::Time => (3, 0, 0),
        Symbol::Jet { coord, order } => (4, coord, order),
        Symbol::Input(i) => (5, i, 0),
        Symbol::InputRate(i) => (6, i, 0),
    }
}

impl Arena {
    fn cmp_symbol(&self, s: Symbol, t: Symbol) -> Ordering {
        match (s, t) {
            (Symbol::Aux(i), Symbol::Aux(j)) => self.aux_name(i).cmp(&self.aux_name(j)),
            _ => symbol_key(s).cmp(&symbol_key(t)),
        }
    }
}

/// An empty table with room for `n` entries without rehashing.
fn fx_map_with_capacity<K, V>(n: usize) -> FxMap<K, V> {
    FxMap::with_capacity_and_hasher(n, Default::default())
}
