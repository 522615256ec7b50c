//! Method bodies that write a vector or a matrix of expressions — a right
//! side, its Jacobian, its time partial — shared by every system the crate
//! prints (the reduced system (7), the coefficient system).

use super::names::{Source, SymbolNames};
use crate::ir::{Arena, ExprId};
use proc_macro2::{Literal, TokenStream};
use quote::quote;

/// An index as an unsuffixed literal (`x[3]`, not `x[3usize]`).
pub fn index(i: usize) -> Literal {
    Literal::usize_unsuffixed(i)
}

/// An argument's name, `_name` when the body does not read it (no warning).
pub fn arg(used: bool, name: &str) -> TokenStream {
    let ident = proc_macro2::Ident::new(
        &if used {
            name.to_string()
        } else {
            format!("_{name}")
        },
        proc_macro2::Span::call_site(),
    );
    quote! { #ident }
}

/// The body of a method computing some entries of a vector or a matrix.
pub struct Body {
    /// The bindings and shared sub-expressions (`let p = &self.params;` …).
    pub statements: TokenStream,
    /// One `out[row] = value;` (or `out[(r, c)] = value;`) per entry.
    pub assignments: Vec<TokenStream>,
    /// The time argument (`t`, or `_t` when unused).
    pub t: TokenStream,
    /// The source argument (`x`, or `_x` when unused).
    pub source: TokenStream,
    /// The output argument (`_out` when no entry is written).
    pub out: TokenStream,
}

/// `out[row] = expr;` for every `(row, expr)`, reading symbols from
/// `source`, which is named `source_name` in the signature.
pub fn vector(
    names: &mut SymbolNames,
    arena: &Arena,
    entries: &[(usize, ExprId)],
    from: Source,
    source_name: &str,
    out_name: &str,
) -> Body {
    let roots: Vec<ExprId> = entries.iter().map(|&(_, e)| e).collect();
    body(
        names,
        arena,
        &roots,
        from,
        source_name,
        out_name,
        |out, values| {
            entries
                .iter()
                .zip(values)
                .map(|(&(row, _), value)| {
                    let row = index(row);
                    quote! { #out[#row] = #value; }
                })
                .collect()
        },
    )
}

/// `out[(row, column)] = expr;` for every `(row, column, expr)`.
pub fn matrix(
    names: &mut SymbolNames,
    arena: &Arena,
    entries: &[(usize, usize, ExprId)],
    from: Source,
    source_name: &str,
    out_name: &str,
) -> Body {
    let roots: Vec<ExprId> = entries.iter().map(|&(_, _, e)| e).collect();
    body(
        names,
        arena,
        &roots,
        from,
        source_name,
        out_name,
        |out, values| cells(out, entries, values),
    )
}

/// The body computing `roots` from `source`: their shared sub-expressions
/// named in a scope of their own, and `assign(out, values)` writing the
/// printed values into the output argument.
fn body(
    names: &mut SymbolNames,
    arena: &Arena,
    roots: &[ExprId],
    from: Source,
    source_name: &str,
    out_name: &str,
    assign: impl FnOnce(&TokenStream, &[TokenStream]) -> Vec<TokenStream>,
) -> Body {
    let code = names.code(arena, roots, from);
    let out = arg(true, out_name);
    let assignments = assign(&out, &code.roots);
    Body {
        statements: code.statements(quote! { self.params }),
        assignments,
        t: code.time_arg(),
        source: arg(code.uses_source, source_name),
        out: arg(!roots.is_empty(), out_name),
    }
}

/// `out[(row, column)] = value;` for the entries and their printed values.
pub fn cells(
    out: &TokenStream,
    entries: &[(usize, usize, ExprId)],
    values: &[TokenStream],
) -> Vec<TokenStream> {
    entries
        .iter()
        .zip(values)
        .map(|(&(r, c, _), v)| {
            let (r, c) = (index(r), index(c));
            quote! { #out[(#r, #c)] = #v; }
        })
        .collect()
}
