//! Numeric evaluation of expressions.

use super::canon::{apply_func, pow_value};
use super::expr::{Arena, ExprId, FxMap, Node, Symbol};

impl Arena {
    /// The value of `e` with every symbol given by `env`. Shared nodes are
    /// evaluated once per call.
    pub fn eval(&self, e: ExprId, env: &dyn Fn(Symbol) -> f64) -> f64 {
        let mut memo = FxMap::default();
        self.eval_rec(e, env, &mut memo)
    }

    /// The values of several roots, sharing the work on common nodes.
    pub fn eval_many(&self, roots: &[ExprId], env: &dyn Fn(Symbol) -> f64) -> Vec<f64> {
        let mut memo = FxMap::default();
        roots
            .iter()
            .map(|&r| self.eval_rec(r, env, &mut memo))
            .collect()
    }

    fn eval_rec(
        &self,
        e: ExprId,
        env: &dyn Fn(Symbol) -> f64,
        memo: &mut FxMap<ExprId, f64>,
    ) -> f64 {
        if let Some(&v) = memo.get(&e) {
            return v;
        }
        let v = match self.node(e) {
            Node::Const(v) => *v,
            Node::Sym(s) => env(*s),
            Node::Add(ts) => ts.iter().map(|&t| self.eval_rec(t, env, memo)).sum(),
            Node::Mul(fs) => fs.iter().map(|&f| self.eval_rec(f, env, memo)).product(),
            Node::Pow(a, b) => {
                let a = self.eval_rec(*a, env, memo);
                let b = self.eval_rec(*b, env, memo);
                pow_value(a, b)
            }
            Node::Func(f, a) => apply_func(*f, self.eval_rec(*a, env, memo)),
            Node::Select(g, a, b) => {
                if self.eval_rec(*g, env, memo) < 0.0 {
                    self.eval_rec(*a, env, memo)
                } else {
                    self.eval_rec(*b, env, memo)
                }
            }
        };
        memo.insert(e, v);
        v
    }
}
