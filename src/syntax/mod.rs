//! Stage 1: `.lag` text → AST (pest grammar in `grammar/lag.pest`).
//!
//! [`parse`] never panics and never overflows the stack: parentheses are
//! pre-scanned against [`MAX_PAREN_DEPTH`] before pest (which recurses on
//! them) sees the text, and expression trees are folded iteratively and
//! rejected past [`MAX_EXPR_DEPTH`], so every later recursive pass (and
//! `Drop`) over an AST works within a bounded depth.

pub mod ast;
mod depth;
mod grammar;
mod parser;
mod syntax_error;

pub use depth::{MAX_EXPR_DEPTH, MAX_PAREN_DEPTH};
pub use parser::parse;
