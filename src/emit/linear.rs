//! `impl lagc_python::Linear for Model`: the linearization's symbolic half
//! ([`crate::linearize::LinearParts`], taken in `src/linearize/parts.rs`)
//! printed for a model's Python module, whose `m.linearize(at=…)` evaluates
//! it at a point as `lagc linearize` does (`python/src/linear.rs`). Only
//! the Python project carries it: the crate `lagc run` builds does not.

use super::bodies::{self, index};
use super::names::{Code, SymbolNames};
use crate::diagnostic::Diagnostic;
use crate::ir::{ExprId, Symbol};
use crate::linearize::LinearParts;
use proc_macro2::TokenStream;
use quote::quote;

/// The impl block's source text, formatted; `parts` is the model's
/// symbolic linearization or why the module cannot carry it.
pub fn linear_code(parts: &Result<LinearParts, String>) -> Result<String, Diagnostic> {
    let tokens = match parts {
        Err(why) => quote! {
            impl lagc_python::Linear for Model {
                const LAYOUT: lagc_python::LinearLayout = lagc_python::LinearLayout {
                    unavailable: Some(#why),
                    free: &[],
                    kept: &[],
                    ignorable: &[],
                    fixed: &[],
                    unknowns: 0,
                    unknown_rows: &[],
                    implicit_linear: true,
                };
            }
        },
        Ok(p) => available(p),
    };
    super::pretty(tokens)
}

fn available(p: &LinearParts) -> TokenStream {
    let list = |v: &[usize]| {
        let items = v.iter().map(|&i| index(i));
        quote! { &[#(#items),*] }
    };
    let (free, kept, ignorable) = (list(&p.free), list(&p.kept), list(&p.ignorable));
    let fixed_indices: Vec<usize> = p.fixed.iter().map(|&(k, _)| k).collect();
    let fixed = list(&fixed_indices);
    let pairs = p.unknown_rows.iter().map(|&(i, j)| {
        let (i, j) = (index(i), index(j));
        quote! { (#i, #j) }
    });
    let unknown_rows = quote! { &[#(#pairs),*] };
    let unknowns: Vec<Symbol> = p
        .implicit
        .as_ref()
        .map_or_else(Vec::new, |i| i.unknowns.clone());
    let (count, linear) = (
        index(unknowns.len()),
        p.implicit.as_ref().is_some_and(|i| i.linear),
    );
    let fixed_cells: Vec<(usize, ExprId)> = p
        .fixed
        .iter()
        .enumerate()
        .map(|(i, &(_, e))| (i, e))
        .collect();
    let printer = Printer {
        p,
        unknowns: &unknowns,
    };
    let mut items = vec![
        printer.vector("linear_stated", &p.stated),
        printer.vector("linear_fixed", &fixed_cells),
        printer.vector("linear_rates", &p.rates),
        printer.matrix("linear_a", &p.a),
        printer.matrix("linear_b", &p.b),
        printer.matrix("linear_chain", &p.chain),
    ];
    if let Some(i) = &p.implicit {
        items.push(printer.vector("linear_g", &i.residual));
        items.push(printer.matrix("linear_g_z", &i.g_z));
        items.push(printer.matrix("linear_g_x", &i.g_x));
        items.push(printer.matrix("linear_g_p", &i.g_p));
        items.push(printer.matrix("linear_d_z", &i.d_z));
    }
    quote! {
        impl lagc_python::Linear for Model {
            const LAYOUT: lagc_python::LinearLayout = lagc_python::LinearLayout {
                unavailable: None,
                free: #free,
                kept: #kept,
                ignorable: #ignorable,
                fixed: #fixed,
                unknowns: #count,
                unknown_rows: #unknown_rows,
                implicit_linear: #linear,
            };
            #(#items)*
        }
    }
}

/// Prints one function of `(t, x, z)`: the free state from `x`, the
/// implicit system's unknowns from `z`.
struct Printer<'a> {
    p: &'a LinearParts,
    unknowns: &'a [Symbol],
}

impl Printer<'_> {
    fn function(&self, name: &str, roots: &[ExprId], out_type: TokenStream) -> (TokenStream, Code) {
        let arena = &self.p.arena;
        let state = &self.p.state;
        let unknowns = self.unknowns;
        let source = |s: Symbol| {
            if let Some(k) = state.iter().position(|&v| v == s) {
                let k = index(k);
                return Some(quote! { x[#k] });
            }
            unknowns.iter().position(|&v| v == s).map(|j| {
                let j = index(j);
                quote! { z[#j] }
            })
        };
        let mut names = SymbolNames::new(arena, &[]);
        let code = names.code(arena, roots, &source);
        let reads = |set: &[Symbol]| {
            roots
                .iter()
                .any(|&r| set.iter().any(|&s| arena.depends_on(r, s)))
        };
        let (x, z) = (
            bodies::arg(reads(state), "x"),
            bodies::arg(reads(unknowns), "z"),
        );
        let out = bodies::arg(!roots.is_empty(), "out");
        let t = code.time_arg();
        let name = proc_macro2::Ident::new(name, proc_macro2::Span::call_site());
        let signature = quote! {
            fn #name(&self, #t: f64, #x: &[f64], #z: &[f64], #out: #out_type)
        };
        (signature, code)
    }

    fn vector(&self, name: &str, cells: &[(usize, ExprId)]) -> TokenStream {
        let roots: Vec<ExprId> = cells.iter().map(|&(_, e)| e).collect();
        let (signature, code) = self.function(name, &roots, quote! { &mut [f64] });
        let statements = code.statements(quote! { self.params });
        let assignments = bodies::assignments(&quote! { out }, cells, &code.roots);
        quote! { #signature { #statements #(#assignments)* } }
    }

    fn matrix(&self, name: &str, cells: &[(usize, usize, ExprId)]) -> TokenStream {
        let roots: Vec<ExprId> = cells.iter().map(|&(_, _, e)| e).collect();
        let (signature, code) = self.function(name, &roots, quote! { &mut Matrix });
        let statements = code.statements(quote! { self.params });
        let assignments = bodies::assignments(&quote! { out }, cells, &code.roots);
        quote! { #signature { #statements #(#assignments)* } }
    }
}
