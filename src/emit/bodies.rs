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
    /// The printed value of each entry, in order.
    pub values: Vec<TokenStream>,
    /// The time argument (`t`, or `_t` when unused).
    pub t: TokenStream,
    /// The source argument (`x`, or `_x` when unused).
    pub source: TokenStream,
    /// The output argument (`_out` when no entry is written).
    pub out: TokenStream,
}

/// An entry of a vector, `(row, expr)`, or of a matrix, `(row, column,
/// expr)`.
pub trait Entry: Copy {
    fn expr(self) -> ExprId;
    /// `out[row] = value;` or `out[(row, column)] = value;`.
    fn assign(self, out: &TokenStream, value: &TokenStream) -> TokenStream;
}

impl Entry for (usize, ExprId) {
    fn expr(self) -> ExprId {
        self.1
    }
    fn assign(self, out: &TokenStream, value: &TokenStream) -> TokenStream {
        let row = index(self.0);
        quote! { #out[#row] = #value; }
    }
}

impl Entry for (usize, usize, ExprId) {
    fn expr(self) -> ExprId {
        self.2
    }
    fn assign(self, out: &TokenStream, value: &TokenStream) -> TokenStream {
        let (r, c) = (index(self.0), index(self.1));
        quote! { #out[(#r, #c)] = #value; }
    }
}

/// The body computing `entries` from `source`, which is named
/// `source_name` in the signature: their shared sub-expressions named in a
/// scope of their own, then one assignment per entry into the output
/// argument `out_name`.
pub fn body(
    names: &mut SymbolNames,
    arena: &Arena,
    entries: &[impl Entry],
    from: Source,
    source_name: &str,
    out_name: &str,
) -> Body {
    let roots: Vec<ExprId> = entries.iter().map(|e| e.expr()).collect();
    let code = names.code(arena, &roots, from);
    let out = arg(true, out_name);
    let assignments = assignments(&out, entries, &code.roots);
    Body {
        statements: code.statements(quote! { self.params }),
        assignments,
        t: code.time_arg(),
        source: arg(code.uses_source, source_name),
        out: arg(!roots.is_empty(), out_name),
        values: code.roots,
    }
}

/// `out[…] = value;` for the entries and their printed values.
pub fn assignments(
    out: &TokenStream,
    entries: &[impl Entry],
    values: &[TokenStream],
) -> Vec<TokenStream> {
    entries
        .iter()
        .zip(values)
        .map(|(e, v)| e.assign(out, v))
        .collect()
}
