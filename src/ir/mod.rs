//! The symbolic core: a hash-consed DAG of canonical expressions with exact
//! partial and total derivatives, substitution, evaluation and text forms.
//!
//! Invariants: every [`ExprId`] names a canonical node (built only through
//! the constructors of `canon.rs`), so two ids are equal iff the expressions
//! are equal up to canonicalisation; the canonical order of terms depends on
//! structure only, never on the order in which things were built; products
//! of sums are never expanded.
//!
//! | file | what |
//! |---|---|
//! | `expr.rs` | ids, symbols, nodes, the arena, free-symbol facts, sizes |
//! | `free.rs` | a node's free symbols as a bit set |
//! | `canon.rs` | canonicalising constructors and the canonical order |
//! | `diff.rs` | `∂/∂symbol` (and the walk shared with `D`) |
//! | `jacobian.rs` | many expressions' partials in many symbols, one pass |
//! | `jet.rs` | the total time derivative `D` |
//! | `subst.rs` | simultaneous substitution |
//! | `eval.rs` | numbers |
//! | `display.rs` | text and LaTeX |
//! | `shared.rs` | names for the shared subexpressions of printed text |
//! | `lower.rs` | AST → IR |

mod canon;
mod diff;
mod display;
mod eval;
mod expr;
mod free;
mod jacobian;
mod jet;
mod lower;
mod shared;
mod subst;
mod trig;

pub use crate::syntax::ast::Func;
pub use canon::{apply_func, half_odd_power, pow_value};
pub use display::ExprDisplay;
pub(crate) use expr::FxMap;
pub use expr::{postorder, Arena, ExprId, Names, Node, Seen, Symbol};
pub use lower::{
    lower, names_of, select, try_lower, try_lower_components, try_lower_condition, Cond, LowerError,
};
pub use shared::{SharedNames, MIN_NAMED_SAVING, MIN_NAMED_SIZE};
