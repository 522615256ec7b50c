//! Stage 1: `.lag` text → AST (pest grammar in `grammar/lag.pest`).
//!
//! [`parse`] never panics and never overflows the stack: parentheses are
//! pre-scanned against [`MAX_PAREN_DEPTH`] before pest (which recurses on
//! them) sees the text, and expression trees are folded iteratively and
//! rejected past [`MAX_EXPR_DEPTH`] levels of nesting (a flat chain is one)
//! or [`MAX_TREE_HEIGHT`] levels of tree, so every later recursive pass (and
//! `Drop`) over an AST works within a bounded depth — on the front end's big
//! stack (`on_big_stack`) for the longest chains.

pub mod ast;
mod depth;
mod grammar;
mod parser;
mod syntax_error;

pub use depth::{MAX_EXPR_DEPTH, MAX_PAREN_DEPTH, MAX_TREE_HEIGHT};
pub use parser::parse;
