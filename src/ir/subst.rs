//! Simultaneous substitution of symbols by expressions.

use super::expr::{Arena, ExprId, FreeSet, FxMap, Node, Symbol};
use std::collections::HashMap;

impl Arena {
    /// Replaces every symbol in `map` by its image, all at once (an image is
    /// not substituted again), and re-canonicalises. Sub-expressions free of
    /// the mapped symbols are kept as they are; shared nodes are rebuilt once.
    pub fn subst(&mut self, e: ExprId, map: &HashMap<Symbol, ExprId>) -> ExprId {
        let Some(slots) = self.slots_of(map) else {
            return e;
        };
        let mut memo = FxMap::default();
        self.subst_rec(e, map, &slots, &mut memo)
    }

    /// [`Arena::subst`] of each of `es` with one `map`, the nodes they
    /// share rebuilt once.
    pub fn subst_all(&mut self, es: &[ExprId], map: &HashMap<Symbol, ExprId>) -> Vec<ExprId> {
        let Some(slots) = self.slots_of(map) else {
            return es.to_vec();
        };
        let mut memo = FxMap::default();
        es.iter()
            .map(|&e| self.subst_rec(e, map, &slots, &mut memo))
            .collect()
    }

    /// The slots of the mapped symbols as a set, `None` when the arena
    /// holds none of them (nothing to substitute).
    fn slots_of(&self, map: &HashMap<Symbol, ExprId>) -> Option<FreeSet> {
        let mut words = Vec::new();
        for slot in map.keys().filter_map(|&s| self.symbol_slot(s)) {
            FreeSet::single(slot).or_into(&mut words);
        }
        let slots = FreeSet::from_words(&words);
        (slots != FreeSet::default()).then_some(slots)
    }

    /// Whether `e` holds a mapped symbol: one AND per 64 slots (a loop
    /// over the mapped slots cost the 100-link pendulum's jet-free terms,
    /// 100 mapped jets, a hundred look-ups per node visited).
    fn touches(&self, e: ExprId, slots: &FreeSet) -> bool {
        self.meta[e.index()].free.meets(slots)
    }

    fn subst_rec(
        &mut self,
        e: ExprId,
        map: &HashMap<Symbol, ExprId>,
        slots: &FreeSet,
        memo: &mut FxMap<ExprId, ExprId>,
    ) -> ExprId {
        if !self.touches(e, slots) {
            return e;
        }
        if let Some(&r) = memo.get(&e) {
            return r;
        }
        let r = match self.node(e).clone() {
            Node::Const(_) => e,
            Node::Sym(s) => map.get(&s).copied().unwrap_or(e),
            Node::Add(ts) => {
                let ts: Vec<ExprId> = ts
                    .iter()
                    .map(|&t| self.subst_rec(t, map, slots, memo))
                    .collect();
                self.add(&ts)
            }
            Node::Mul(fs) => {
                let fs: Vec<ExprId> = fs
                    .iter()
                    .map(|&f| self.subst_rec(f, map, slots, memo))
                    .collect();
                self.mul(&fs)
            }
            Node::Pow(a, b) => {
                let a = self.subst_rec(a, map, slots, memo);
                let b = self.subst_rec(b, map, slots, memo);
                self.pow(a, b)
            }
            Node::Func(f, a) => {
                let a = self.subst_rec(a, map, slots, memo);
                self.func(f, a)
            }
            Node::Select(g, a, b) => {
                let g = self.subst_rec(g, map, slots, memo);
                let a = self.subst_rec(a, map, slots, memo);
                let b = self.subst_rec(b, map, slots, memo);
                self.select(g, a, b)
            }
        };
        memo.insert(e, r);
        r
    }
}

impl Arena {
    /// For `e` affine in `vars`, `e = free + Σ_A coeffs[A]·vars[A]`: returns
    /// `(coeffs, free)` (each coefficient `∂e/∂x_A`, the free term `e` at
    /// `x = 0`). When `e` is not affine the coefficients still hold `x`; check
    /// with [`Arena::is_affine_in`] first where that matters.
    pub fn affine_parts(&mut self, e: ExprId, vars: &[Symbol]) -> (Vec<ExprId>, ExprId) {
        let coeffs = vars.iter().map(|&x| self.diff(e, x)).collect();
        let zero = self.zero();
        let at_zero: HashMap<Symbol, ExprId> = vars.iter().map(|&x| (x, zero)).collect();
        let free = self.subst(e, &at_zero);
        (coeffs, free)
    }

    /// Whether `e` is affine in `vars` as written: no coefficient `∂e/∂x_A`
    /// depends on any `x_B`. Canonical forms do not expand, so an expression
    /// affine only after cancellation (`(x+1)^2 − x^2`) reports `false`.
    ///
    /// Nor is `e` affine in a variable that a selection in it switches on:
    /// `sign(x')`, `if x' > 0 then a else b` have the derivative 0 in `x'`
    /// on either side, yet are not `c + 0·x'` — their value at `x' = 0`
    /// is one branch, not the expression.
    pub fn is_affine_in(&mut self, e: ExprId, vars: &[Symbol]) -> bool {
        // `switches_on` for every var, with one walk of `e`.
        let switching: Vec<ExprId> = if vars.iter().any(|&x| self.depends_on(e, x)) {
            self.reachable(&[e])
                .into_iter()
                .filter_map(|n| match self.node(n) {
                    Node::Select(g, _, _) => Some(*g),
                    _ => None,
                })
                .collect()
        } else {
            Vec::new()
        };
        if vars
            .iter()
            .any(|&x| self.depends_on(e, x) && switching.iter().any(|&g| self.depends_on(g, x)))
        {
            return false;
        }
        vars.iter().all(|&x| {
            let c = self.diff(e, x);
            vars.iter().all(|&y| !self.depends_on(c, y))
        })
    }

    /// Whether a selection in `e` has a switching function depending on `x`.
    pub fn switches_on(&self, e: ExprId, x: Symbol) -> bool {
        if !self.depends_on(e, x) || !self.has_select(e) {
            return false;
        }
        self.reachable(&[e])
            .iter()
            .any(|&n| matches!(self.node(n), Node::Select(g, _, _) if self.depends_on(*g, x)))
    }
}

impl Arena {
    /// Rebuilds `e` with every selection `Select(g, a, b)` made on
    /// `switch(g')` instead of `g` (`g'` being `g` rebuilt likewise): the
    /// kernel's latching of switches to the run's regime. `memo` carries
    /// the rebuilt nodes across calls, so shared nodes are rebuilt once.
    pub(crate) fn map_selects(
        &mut self,
        e: ExprId,
        switch: &mut dyn FnMut(&mut Arena, ExprId) -> ExprId,
        memo: &mut FxMap<ExprId, ExprId>,
    ) -> ExprId {
        if let Some(&r) = memo.get(&e) {
            return r;
        }
        // Without a selection below, rebuilding gives the node back (its
        // children come back unchanged, and a canonical node is its own
        // canonical form): not rebuilt.
        if !self.meta[e.index()].selects {
            return e;
        }
        let r = match self.node(e).clone() {
            Node::Const(_) | Node::Sym(_) => e,
            Node::Add(ts) => {
                let ts: Vec<ExprId> = ts
                    .iter()
                    .map(|&t| self.map_selects(t, switch, memo))
                    .collect();
                self.add(&ts)
            }
            Node::Mul(fs) => {
                let fs: Vec<ExprId> = fs
                    .iter()
                    .map(|&f| self.map_selects(f, switch, memo))
                    .collect();
                self.mul(&fs)
            }
            Node::Pow(a, b) => {
                let a = self.map_selects(a, switch, memo);
                let b = self.map_selects(b, switch, memo);
                self.pow(a, b)
            }
            Node::Func(f, a) => {
                let a = self.map_selects(a, switch, memo);
                self.func(f, a)
            }
            Node::Select(g, a, b) => {
                let g = self.map_selects(g, switch, memo);
                let a = self.map_selects(a, switch, memo);
                let b = self.map_selects(b, switch, memo);
                let key = switch(self, g);
                self.select(key, a, b)
            }
        };
        memo.insert(e, r);
        r
    }

    /// Whether `e` holds a selection.
    pub fn has_select(&self, e: ExprId) -> bool {
        self.meta[e.index()].selects
    }
}
