//! Derivations of expressions: the partial derivative with respect to one
//! symbol, and (through the same walk) the total time derivative of `jet.rs`.
//!
//! Both are derivations (linear, Leibniz, chain rule); they differ only at the
//! leaves, so one memoised walk serves both. A node that does not depend on
//! the variable is skipped in O(log n) through its cached free symbols.

use super::expr::{Arena, Derivation, ExprId, Node, Symbol};
use crate::syntax::ast::Func;

impl Arena {
    /// `∂e/∂wrt`, memoised per (node, symbol) for the life of the arena.
    pub fn diff(&mut self, e: ExprId, wrt: Symbol) -> ExprId {
        self.derive(e, Derivation::Partial(wrt))
    }

    /// `∂e/∂wrt` when [`Arena::diff`] would find it without building
    /// anything: `e` does not hold `wrt`, or the partial is remembered.
    pub(crate) fn known_partial(&mut self, e: ExprId, wrt: Symbol) -> Option<ExprId> {
        if !self.depends_on(e, wrt) {
            return Some(self.zero());
        }
        self.derivatives
            .get(&(e, Derivation::Partial(wrt)))
            .copied()
    }

    pub(crate) fn derive(&mut self, e: ExprId, d: Derivation) -> ExprId {
        let moves = match d {
            Derivation::Partial(s) => self.depends_on(e, s),
            Derivation::Total => self.varies_in_time(e),
        };
        if !moves {
            return self.zero();
        }
        if let Some(&r) = self.derivatives.get(&(e, d)) {
            return r;
        }
        let r = match self.node(e).clone() {
            Node::Const(_) => self.zero(),
            Node::Sym(s) => self.derive_leaf(s, d),
            Node::Add(ts) => {
                let ds: Vec<ExprId> = ts.iter().map(|&t| self.derive(t, d)).collect();
                self.add(&ds)
            }
            Node::Mul(fs) => {
                let mut terms = Vec::new();
                for i in 0..fs.len() {
                    let di = self.derive(fs[i], d);
                    if self.is_zero(di) {
                        continue;
                    }
                    let mut factors: Vec<ExprId> = fs.to_vec();
                    factors[i] = di;
                    terms.push(self.mul(&factors));
                }
                self.add(&terms)
            }
            Node::Pow(a, b) => self.derive_pow(e, a, b, d),
            // Away from its switch a selection is one of its branches.
            Node::Select(g, a, b) => {
                let da = self.derive(a, d);
                let db = self.derive(b, d);
                self.select(g, da, db)
            }
            Node::Func(f, u) => {
                let du = self.derive(u, d);
                let outer = self.func_derivative(f, u);
                self.mul(&[outer, du])
            }
        };
        self.derivatives.insert((e, d), r);
        r
    }

    fn derive_leaf(&mut self, s: Symbol, d: Derivation) -> ExprId {
        match d {
            Derivation::Partial(wrt) if wrt == s => self.one(),
            Derivation::Partial(_) => self.zero(),
            Derivation::Total => match s {
                Symbol::Time => self.one(),
                Symbol::Jet { coord, order } => self.jet(coord, order.saturating_add(1)),
                // Params, aux symbols and mass laws are constant under D
                // (mass laws frozen: SPEC §1.1).
                Symbol::Param(_) | Symbol::Mass(_) | Symbol::Aux(_) => self.zero(),
                // An input is a line in `t` between the restarts at its
                // changes; its rate is constant there.
                Symbol::Input(i) => self.symbol(Symbol::InputRate(i)),
                Symbol::InputRate(_) => self.zero(),
            },
        }
    }

    /// `(a^b)' = b·a^(b−1)·a' + a^b·ln(a)·b'`; the second term only when the
    /// exponent moves, so `x^2` never grows a `ln(x)`.
    fn derive_pow(&mut self, e: ExprId, a: ExprId, b: ExprId, d: Derivation) -> ExprId {
        let da = self.derive(a, d);
        let db = self.derive(b, d);
        self.power_rule(e, a, b, da, db)
    }

    /// The derivative of `e = a^b` from those of its base and exponent
    /// (also `jacobian.rs`'s rule, so both build the same node).
    pub(super) fn power_rule(
        &mut self,
        e: ExprId,
        a: ExprId,
        b: ExprId,
        da: ExprId,
        db: ExprId,
    ) -> ExprId {
        let mut terms = Vec::with_capacity(2);
        if !self.is_zero(da) {
            let minus_one = self.constant(-1.0);
            let b1 = self.add(&[b, minus_one]);
            let p = self.pow(a, b1);
            terms.push(self.mul(&[b, p, da]));
        }
        if !self.is_zero(db) {
            let ln_a = self.func(Func::Ln, a);
            terms.push(self.mul(&[e, ln_a, db]));
        }
        self.add(&terms)
    }

    /// `f'(u)`.
    pub(super) fn func_derivative(&mut self, f: Func, u: ExprId) -> ExprId {
        match f {
            Func::Sin => self.func(Func::Cos, u),
            Func::Cos => {
                let s = self.func(Func::Sin, u);
                self.neg(s)
            }
            Func::Tan => {
                let c = self.func(Func::Cos, u);
                self.powi(c, -2)
            }
            Func::Asin | Func::Acos => {
                // ±(1 − u²)^(−1/2)
                let u2 = self.powi(u, 2);
                let one = self.one();
                let inner = self.sub(one, u2);
                let half = self.constant(-0.5);
                let r = self.pow(inner, half);
                if f == Func::Asin {
                    r
                } else {
                    self.neg(r)
                }
            }
            Func::Atan => {
                let u2 = self.powi(u, 2);
                let one = self.one();
                let inner = self.add(&[one, u2]);
                self.powi(inner, -1)
            }
            Func::Sinh => self.func(Func::Cosh, u),
            Func::Cosh => self.func(Func::Sinh, u),
            Func::Tanh => {
                let c = self.func(Func::Cosh, u);
                self.powi(c, -2)
            }
            Func::Exp => self.func(Func::Exp, u),
            Func::Ln => self.powi(u, -1),
            Func::Sqrt => {
                let half = self.constant(0.5);
                let p = self.constant(-0.5);
                let r = self.pow(u, p);
                self.mul(&[half, r])
            }
        }
    }
}
