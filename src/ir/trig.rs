//! `sin²u + cos²u = 1`: the one trigonometric identity that kinetic
//! energies written with vectors produce everywhere (`|d/dt (l sin a, −l cos
//! a)|² = l² a'² (cos² a + sin² a)`). Applied to the Lagrangian before
//! differentiation, it removes those terms from every equation downstream.

use super::expr::{Arena, ExprId, FxMap, Node};
use crate::syntax::ast::Func;

impl Arena {
    /// `e` with every pair of terms `c·X·sin(u)²` and `c·X·cos(u)²` of a
    /// sum replaced by `c·X`. An identity: the value never changes.
    pub fn pythagoras(&mut self, e: ExprId) -> ExprId {
        let mut memo = FxMap::default();
        self.pythagoras_rec(e, &mut memo)
    }

    /// [`Arena::pythagoras`] of each of `es`, the nodes they share
    /// rewritten once (a mass matrix's entries share most of theirs).
    pub fn pythagoras_all(&mut self, es: &[ExprId]) -> Vec<ExprId> {
        let mut memo = FxMap::default();
        es.iter()
            .map(|&e| self.pythagoras_rec(e, &mut memo))
            .collect()
    }

    /// [`Arena::pythagoras`] through a memo kept by the caller across
    /// calls (the rewrite of a node does not depend on where it is).
    pub(crate) fn pythagoras_rec(&mut self, e: ExprId, memo: &mut FxMap<ExprId, ExprId>) -> ExprId {
        if let Some(&r) = memo.get(&e) {
            return r;
        }
        let r = match self.node(e).clone() {
            Node::Const(_) | Node::Sym(_) => e,
            Node::Add(ts) => {
                let ts: Vec<ExprId> = ts.iter().map(|&t| self.pythagoras_rec(t, memo)).collect();
                let ts = self.pair_squares(ts);
                self.add(&ts)
            }
            Node::Mul(fs) => {
                let fs: Vec<ExprId> = fs.iter().map(|&f| self.pythagoras_rec(f, memo)).collect();
                self.mul(&fs)
            }
            Node::Pow(a, b) => {
                let a = self.pythagoras_rec(a, memo);
                let b = self.pythagoras_rec(b, memo);
                self.pow(a, b)
            }
            Node::Func(f, a) => {
                let a = self.pythagoras_rec(a, memo);
                self.func(f, a)
            }
            Node::Select(g, a, b) => {
                let g = self.pythagoras_rec(g, memo);
                let a = self.pythagoras_rec(a, memo);
                let b = self.pythagoras_rec(b, memo);
                self.select(g, a, b)
            }
        };
        memo.insert(e, r);
        r
    }

    /// The factors of a term, and which of them is `sin(u)²` or `cos(u)²`.
    fn factors(&self, t: ExprId) -> Vec<ExprId> {
        match self.node(t) {
            Node::Mul(fs) => fs.to_vec(),
            _ => vec![t],
        }
    }

    /// `(k, u)` for the first factor `k` of a term that is `sin(u)²`, read
    /// in place (most terms have none, and a copy of every term's factors
    /// was most of the allocations of the tidy forms' pairing).
    fn first_sin_square(&self, t: ExprId) -> Option<(usize, ExprId)> {
        let pick = |(k, &f): (usize, &ExprId)| match self.trig_square(f) {
            Some((Func::Sin, u)) => Some((k, u)),
            _ => None,
        };
        match self.node(t) {
            Node::Mul(fs) => fs.iter().enumerate().find_map(pick),
            _ => pick((0, &t)),
        }
    }

    /// `(f, u)` for a factor `f(u)²` with `f` sine or cosine.
    fn trig_square(&self, factor: ExprId) -> Option<(Func, ExprId)> {
        let Node::Pow(base, exp) = self.node(factor) else {
            return None;
        };
        if self.as_const(*exp) != Some(2.0) {
            return None;
        }
        match self.node(*base) {
            Node::Func(f @ (Func::Sin | Func::Cos), u) => Some((*f, *u)),
            _ => None,
        }
    }

    /// Replaces pairs `X·sin(u)², X·cos(u)²` among `terms` by `X`.
    fn pair_squares(&mut self, mut terms: Vec<ExprId>) -> Vec<ExprId> {
        let mut i = 0;
        while i < terms.len() {
            let Some((k, u)) = self.first_sin_square(terms[i]) else {
                i += 1;
                continue;
            };
            let factors = self.factors(terms[i]);
            let mut rest = factors.clone();
            rest.remove(k);
            let sin_u = self.func(Func::Cos, u);
            let cos_square = self.powi(sin_u, 2);
            let mut partner_factors = rest.clone();
            partner_factors.push(cos_square);
            let partner = self.mul(&partner_factors);
            match terms.iter().position(|&t| t == partner) {
                Some(j) if j != i => {
                    let merged = self.mul(&rest);
                    let (hi, lo) = if i > j { (i, j) } else { (j, i) };
                    terms.remove(hi);
                    terms.remove(lo);
                    terms.push(merged);
                    i = 0;
                }
                _ => i += 1,
            }
        }
        terms
    }
}
