//! The Jacobian of several expressions in several symbols in one pass:
//! forward mode over sparse partials.
//!
//! `diff(e, s)` walks the nodes of `e` that hold `s` once per symbol,
//! through the per-(node, symbol) memo; a Jacobian of `R` rows in `K`
//! symbols probes that table once per moving (node, symbol) pair, and on
//! large models (the N-link pendulum's residuals: about N³ pairs) the
//! probes, not the derivatives built, were most of the time. Here every
//! node below the roots that holds one of the symbols is visited once, in
//! post-order, and its partials in all the symbols are built together from
//! its children's (a sorted list of `(column, ∂node/∂symbol)`, zeros left
//! out).
//!
//! Each partial is built by the same constructor calls as [`Arena::diff`]
//! builds it (the rules are shared with `diff.rs`), so every entry is the
//! very node `diff` gives: the generated code does not change. The one
//! difference in the calls is that a sum's derivative hands `add` the
//! moving terms' partials and a single 0 for the terms that do not move,
//! where `diff` hands it one 0 per such term; `add` depends on the
//! multiset of its terms' values only, and many zeros collect into one.

use super::expr::{Arena, Derivation, ExprId, FreeSet, FxMap, Node, Symbol};

/// A node's partials: `(column, ∂node/∂wrt[column])`, sorted by column,
/// none of them zero.
type Partials = Box<[(u32, ExprId)]>;

impl Arena {
    /// `∂roots[r]/∂wrt[c]` for every `r` and `c` (row-major), each entry
    /// the node `self.diff(roots[r], wrt[c])` returns, and remembered as
    /// it would be (later `diff`s of the roots are cache hits).
    pub fn jacobian(&mut self, roots: &[ExprId], wrt: &[Symbol]) -> Vec<Vec<ExprId>> {
        let zero = self.zero();
        // Column of each symbol slot (the first column of a repeated symbol).
        let mut column_of: FxMap<u32, u32> = FxMap::default();
        for (c, &s) in wrt.iter().enumerate() {
            if let Some(slot) = self.symbol_slot(s) {
                column_of.entry(slot).or_insert(c as u32);
            }
        }
        let mut column_words = Vec::new();
        for &slot in column_of.keys() {
            FreeSet::single(slot).or_into(&mut column_words);
        }
        let columns = FreeSet::from_words(&column_words);
        let moves = |arena: &Arena, e: ExprId| arena.meta[e.index()].free.meets(&columns);
        // Post-order of the moving nodes below the roots (children first).
        let mut index: FxMap<ExprId, usize> = FxMap::default();
        let mut order: Vec<ExprId> = Vec::new();
        let mut stack: Vec<(ExprId, bool)> = roots
            .iter()
            .rev()
            .filter(|&&r| moves(self, r))
            .map(|&r| (r, false))
            .collect();
        let mut expanded: FxMap<ExprId, ()> = FxMap::default();
        while let Some((e, done)) = stack.pop() {
            if done {
                index.insert(e, order.len());
                order.push(e);
                continue;
            }
            if index.contains_key(&e) || expanded.insert(e, ()).is_some() {
                continue;
            }
            stack.push((e, true));
            for c in self.children(e).into_iter().rev() {
                if !index.contains_key(&c) && !expanded.contains_key(&c) && moves(self, c) {
                    stack.push((c, false));
                }
            }
        }
        let mut partials: Vec<Partials> = Vec::with_capacity(order.len());
        let mut work = Work {
            buckets: Buckets::new(wrt.len()),
            products: FxMap::default(),
        };
        for &e in &order {
            let p = self.partials_of(e, &column_of, &index, &partials, &mut work);
            partials.push(p);
        }
        let mut rows = Vec::with_capacity(roots.len());
        for &r in roots {
            let mut row = vec![zero; wrt.len()];
            if let Some(&i) = index.get(&r) {
                for &(c, d) in partials[i].iter() {
                    row[c as usize] = d;
                }
            }
            for (c, &s) in wrt.iter().enumerate() {
                let first = self.symbol_slot(s).and_then(|slot| column_of.get(&slot));
                if let Some(&first) = first {
                    row[c] = row[first as usize];
                    if self.depends_on(r, s) {
                        self.derivatives.insert((r, Derivation::Partial(s)), row[c]);
                    }
                }
            }
            rows.push(row);
        }
        rows
    }

    /// The partials of `e` from its children's (`partials[index[child]]`;
    /// a child not in `index` does not move).
    fn partials_of(
        &mut self,
        e: ExprId,
        column_of: &FxMap<u32, u32>,
        index: &FxMap<ExprId, usize>,
        partials: &[Partials],
        work: &mut Work,
    ) -> Partials {
        let Work { buckets, products } = work;
        let of = |c: ExprId| -> &[(u32, ExprId)] {
            match index.get(&c) {
                Some(&i) => &partials[i],
                None => &[],
            }
        };
        let zero = self.zero();
        match self.node(e).clone() {
            Node::Const(_) => Box::new([]),
            Node::Sym(s) => {
                let slot = self
                    .symbol_slot(s)
                    .expect("a symbol of the arena has a slot");
                match column_of.get(&slot) {
                    Some(&c) => Box::new([(c, self.one())]),
                    None => Box::new([]),
                }
            }
            Node::Add(ts) => {
                for &t in ts.iter() {
                    for &(c, d) in of(t) {
                        buckets.push(c, d);
                    }
                }
                buckets.build(self, |arena, terms| {
                    // The terms that do not move (or whose partial is 0)
                    // stand as one 0: `diff` passes one per term.
                    if terms.len() < ts.len() {
                        terms.push(zero);
                    }
                    arena.add(terms)
                })
            }
            Node::Mul(fs) => {
                let mut factors: Vec<ExprId> = fs.to_vec();
                for (i, &f) in fs.iter().enumerate() {
                    for &(c, d) in of(f) {
                        factors[i] = d;
                        let term = self.product(&factors, products);
                        buckets.push(c, term);
                    }
                    factors[i] = f;
                }
                buckets.build(self, |arena, terms| arena.add(terms))
            }
            Node::Pow(a, b) => self.merge_partials(of(a), of(b), |arena, da, db| {
                arena.power_rule(e, a, b, da, db)
            }),
            Node::Select(g, a, b) => {
                self.merge_partials(of(a), of(b), |arena, da, db| arena.select(g, da, db))
            }
            Node::Func(f, u) => {
                let pu = of(u).to_vec();
                if pu.is_empty() {
                    return Box::new([]);
                }
                let outer = self.func_derivative(f, u);
                pu.into_iter()
                    .filter_map(|(c, du)| {
                        let d = self.product(&[outer, du], products);
                        (!self.is_zero(d)).then_some((c, d))
                    })
                    .collect()
            }
        }
    }
}

impl Arena {
    /// The partials of a node of two children `a`, `b`, column by column:
    /// `rule(∂a, ∂b)` wherever either moves (the other's partial 0 there),
    /// the zero results left out.
    fn merge_partials(
        &mut self,
        pa: &[(u32, ExprId)],
        pb: &[(u32, ExprId)],
        mut rule: impl FnMut(&mut Arena, ExprId, ExprId) -> ExprId,
    ) -> Partials {
        let zero = self.zero();
        let mut out = Vec::new();
        let (mut i, mut j) = (0, 0);
        while i < pa.len() || j < pb.len() {
            let ca = pa.get(i).map_or(u32::MAX, |p| p.0);
            let cb = pb.get(j).map_or(u32::MAX, |p| p.0);
            let c = ca.min(cb);
            let da = if ca == c {
                i += 1;
                pa[i - 1].1
            } else {
                zero
            };
            let db = if cb == c {
                j += 1;
                pb[j - 1].1
            } else {
                zero
            };
            let d = rule(self, da, db);
            if !self.is_zero(d) {
                out.push((c, d));
            }
        }
        out.into_boxed_slice()
    }

    /// `self.mul(factors)`, remembered for the Jacobian's pass: the same
    /// product recurs for many nodes (`c·∂S_k/∂x` is one node for every
    /// `k` where the partial of the inner sum `S_k` is), and a lookup costs
    /// a fraction of canonicalising it again.
    fn product(&mut self, factors: &[ExprId], products: &mut Products) -> ExprId {
        if let Some(&p) = products.get(factors) {
            return p;
        }
        let p = self.mul(factors);
        products.insert(factors.into(), p);
        p
    }
}

type Products = FxMap<Box<[ExprId]>, ExprId>;

/// The pass's scratch space.
struct Work {
    buckets: Buckets,
    products: Products,
}

/// The terms of each column's partial, gathered child by child.
struct Buckets {
    terms: Vec<Vec<ExprId>>,
    touched: Vec<u32>,
}

impl Buckets {
    fn new(columns: usize) -> Buckets {
        Buckets {
            terms: vec![Vec::new(); columns],
            touched: Vec::new(),
        }
    }

    fn push(&mut self, c: u32, term: ExprId) {
        let bucket = &mut self.terms[c as usize];
        if bucket.is_empty() {
            self.touched.push(c);
        }
        bucket.push(term);
    }

    /// Each touched column's partial by `combine` (in column order), the
    /// zeros left out; the buckets are left empty.
    fn build(
        &mut self,
        arena: &mut Arena,
        mut combine: impl FnMut(&mut Arena, &mut Vec<ExprId>) -> ExprId,
    ) -> Partials {
        self.touched.sort_unstable();
        let mut out = Vec::with_capacity(self.touched.len());
        for &c in &self.touched {
            let terms = &mut self.terms[c as usize];
            let d = combine(arena, terms);
            terms.clear();
            if !arena.is_zero(d) {
                out.push((c, d));
            }
        }
        self.touched.clear();
        out.into_boxed_slice()
    }
}
