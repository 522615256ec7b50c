//! Names for the common subexpressions of printed expressions: the text
//! of `lagc derive` writes a node that several printed places share, and
//! that would be long written out, once as a named value (`w3 = …`) and
//! uses the name everywhere else. The DAG shares `sin(sin(…(u)))` and the
//! products of the chain rule; a tree printed without names repeats them
//! (a nesting 120 deep printed 28 MB, with names it prints kilobytes).

use super::expr::{postorder, Arena, ExprId, FxMap, Node};

/// A node is named when naming it saves at least this many nodes of the
/// printed tree: its size (with the names of its named parts, each one
/// node) times its uses beyond the first. Small shared parts (`sin(th)`,
/// `m*R^2`) stay written out.
pub const MIN_NAMED_SAVING: usize = 40;
/// Nor is a node of fewer than this many nodes ever named, however often
/// it is used: `cos(th)` reads better than a name for it.
pub const MIN_NAMED_SIZE: usize = 8;

/// Names of shared subexpressions, in an order in which each definition
/// uses only names defined before it.
#[derive(Debug, Clone, Default)]
pub struct SharedNames {
    names: FxMap<ExprId, String>,
    order: Vec<ExprId>,
}

impl SharedNames {
    /// No names: every expression written out in full.
    pub fn none() -> SharedNames {
        SharedNames::default()
    }

    pub fn get(&self, e: ExprId) -> Option<&str> {
        self.names.get(&e).map(String::as_str)
    }

    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// `(name, node)` in definition order.
    pub fn definitions(&self) -> impl Iterator<Item = (&str, ExprId)> + '_ {
        self.order.iter().map(|&e| (self.names[&e].as_str(), e))
    }
}

impl Arena {
    /// `first`, or `first` with its last letter repeated until no name of
    /// the model (params, coordinates, masses, inputs, auxiliary symbols,
    /// `more`) is the prefix followed by digits: the shared names never
    /// read as a name of the model.
    pub fn fresh_prefix(&self, first: &str, more: &[&str]) -> String {
        let n = &self.names;
        let taken: Vec<&str> = n
            .params
            .iter()
            .chain(&n.coords)
            .chain(&n.masses)
            .chain(&n.inputs)
            .chain(&self.aux_names)
            .map(String::as_str)
            .chain(more.iter().copied())
            .collect();
        let mut prefix = first.to_string();
        let last = first.chars().last().unwrap_or('w');
        while taken.iter().any(|t| {
            t.strip_prefix(prefix.as_str())
                .is_some_and(|rest| !rest.is_empty() && rest.chars().all(|c| c.is_ascii_digit()))
        }) {
            prefix.push(last);
        }
        prefix
    }

    /// Names (`{prefix}1`, `{prefix}2`, …) for the nodes of `roots` that
    /// are printed in several places and are long enough to be worth a
    /// name (`MIN_NAMED_SIZE`, `MIN_NAMED_SAVING`): a node's uses are its
    /// parents in the DAG below `roots` (and each time it is a root); its
    /// size is that of its tree with each named part counted as one. What
    /// the text still repeats is short, so its length follows the DAG's
    /// size rather than the tree's.
    pub fn shared_names(&self, roots: &[ExprId], prefix: &str) -> SharedNames {
        let mut seen = vec![false; self.nodes.len()];
        let order = postorder(roots, |e| self.children(e), &mut seen);
        let mut uses: FxMap<ExprId, usize> = FxMap::default();
        for &r in roots {
            *uses.entry(r).or_default() += 1;
        }
        for &e in &order {
            for c in self.children(e) {
                *uses.entry(c).or_default() += 1;
            }
        }
        let mut size: FxMap<ExprId, usize> = FxMap::default();
        let mut shared = SharedNames::default();
        for &e in &order {
            let s = 1 + self
                .children(e)
                .iter()
                .map(|c| size.get(c).copied().unwrap_or(1))
                .sum::<usize>();
            // Only nodes the writer reaches as a whole (a power is written
            // through its base and exponent, a leaf is short).
            let nameable = matches!(
                self.node(e),
                Node::Add(_) | Node::Mul(_) | Node::Func(..) | Node::Select(..)
            );
            let extra_uses = uses.get(&e).copied().unwrap_or(0).saturating_sub(1);
            if nameable && s >= MIN_NAMED_SIZE && s * extra_uses >= MIN_NAMED_SAVING {
                shared
                    .names
                    .insert(e, format!("{prefix}{}", shared.order.len() + 1));
                shared.order.push(e);
                size.insert(e, 1);
            } else {
                size.insert(e, s);
            }
        }
        shared
    }
}
