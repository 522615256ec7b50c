//! Nesting limits that keep parsing and every recursive pass bounded.

use crate::diagnostic::{codes, Diagnostic};
use crate::span::Span;

/// The deepest parenthesis nesting accepted. pest recurses once per level
/// (through several rules), so deeper input is rejected before parsing.
pub const MAX_PAREN_DEPTH: usize = 256;

/// The deepest nesting accepted: a chain `a + b + …` of one operator is one
/// level however long (a 50-link pendulum's potential has 1,275 terms).
pub const MAX_EXPR_DEPTH: usize = 1000;

/// The highest expression tree accepted: later stages recurse over the
/// tree (a chain of n terms is n high), on the front end's big stack.
pub const MAX_TREE_HEIGHT: usize = 10_000;

/// Finds the first `(` nested deeper than [`MAX_PAREN_DEPTH`], skipping
/// `//` comments, and reports it.
pub fn check_paren_depth(source: &str) -> Result<(), Diagnostic> {
    let bytes = source.as_bytes();
    let mut depth = 0usize;
    let mut conditionals = 0usize;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                while i < bytes.len() && !matches!(bytes[i], b'\n' | b'\r') {
                    i += 1;
                }
                continue;
            }
            b'(' => {
                depth += 1;
                if depth > MAX_PAREN_DEPTH {
                    return Err(too_deep_parens(Span::new(i, i + 1)));
                }
            }
            b')' => depth = depth.saturating_sub(1),
            b';' => conditionals = 0,
            b'i' if is_if_keyword(bytes, i) => {
                // `if … else if … else …` nests in the grammar as a
                // parenthesis does; count it with them, per statement.
                conditionals += 1;
                if depth + conditionals > MAX_PAREN_DEPTH {
                    return Err(too_deep_conditionals(Span::new(i, i + 2)));
                }
            }
            _ => {}
        }
        i += 1;
    }
    Ok(())
}

fn is_if_keyword(bytes: &[u8], i: usize) -> bool {
    let ident = |b: u8| b.is_ascii_alphanumeric() || b == b'_' || b == b'\'';
    bytes.get(i + 1) == Some(&b'f')
        && !bytes.get(i + 2).copied().is_some_and(ident)
        && !(i > 0 && ident(bytes[i - 1]))
}

fn too_deep_conditionals(span: Span) -> Diagnostic {
    Diagnostic::error(
        codes::NESTING_TOO_DEEP,
        format!("conditionals and parentheses are nested more than {MAX_PAREN_DEPTH} levels deep"),
    )
    .with_primary(span, format!("this `if` is level {}", MAX_PAREN_DEPTH + 1))
    .with_help("write a long chain of cases as a sum of shorter ones; lagc limits nesting so that no input can exhaust its stack")
}

fn too_deep_parens(span: Span) -> Diagnostic {
    Diagnostic::error(
        codes::NESTING_TOO_DEEP,
        format!("parentheses are nested more than {MAX_PAREN_DEPTH} levels deep"),
    )
    .with_primary(span, format!("this is level {}", MAX_PAREN_DEPTH + 1))
    .with_help(
        "simplify the expression; lagc limits nesting so that no input can exhaust its stack",
    )
}

/// The diagnostic for an expression tree deeper than [`MAX_EXPR_DEPTH`];
/// `span` is the operator or call at which the limit was crossed.
pub fn too_deep_expr(span: Span) -> Diagnostic {
    Diagnostic::error(
        codes::NESTING_TOO_DEEP,
        format!("expression is nested more than {MAX_EXPR_DEPTH} levels deep"),
    )
    .with_primary(span, "the limit is crossed here")
    .with_note("each parenthesis, function call, sign, power and `if` is a level; a chain `a + b + …` of one operator is one")
    .with_help("split the expression; lagc limits nesting so that no input can exhaust its stack")
}

/// The diagnostic for an expression tree higher than [`MAX_TREE_HEIGHT`].
pub fn too_long_chain(span: Span) -> Diagnostic {
    Diagnostic::error(
        codes::NESTING_TOO_DEEP,
        format!("expression has more than {MAX_TREE_HEIGHT} terms in a chain"),
    )
    .with_primary(span, "the limit is crossed here")
    .with_help("split the expression with `let`; lagc limits expressions so that no input can exhaust its stack")
}
