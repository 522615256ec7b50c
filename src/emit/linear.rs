//! `impl lagc_python::Linear for Model`: the linearization's symbolic half
//! ([`crate::linearize::LinearParts`], taken in `src/linearize/parts.rs`)
//! printed for a model's Python module, whose `m.linearize(at=…)` evaluates
//! it at a point as `lagc linearize` does (`python/src/linear.rs`). Only
//! the Python project carries it: the crate `lagc run` builds does not.

use super::bodies::{self, index};
use super::names::SymbolNames;
use crate::diagnostic::Diagnostic;
use crate::ir::Symbol;
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
    let state = p.state.clone();
    let from_x = move |s: Symbol| {
        state.iter().position(|&v| v == s).map(|k| {
            let k = index(k);
            quote! { x[#k] }
        })
    };
    let arena = &p.arena;
    let fixed_cells: Vec<(usize, crate::ir::ExprId)> = p
        .fixed
        .iter()
        .enumerate()
        .map(|(i, &(_, e))| (i, e))
        .collect();
    let vector = |name: &str, cells: &[(usize, crate::ir::ExprId)]| {
        let mut names = SymbolNames::new(arena, &[]);
        let body = bodies::body(&mut names, arena, cells, &from_x, "x", "out");
        let (t, x, out, statements, assignments) = (
            &body.t,
            &body.source,
            &body.out,
            &body.statements,
            &body.assignments,
        );
        let name = proc_macro2::Ident::new(name, proc_macro2::Span::call_site());
        quote! {
            fn #name(&self, #t: f64, #x: &[f64], #out: &mut [f64]) {
                #statements
                #(#assignments)*
            }
        }
    };
    let matrix = |name: &str, cells: &[(usize, usize, crate::ir::ExprId)]| {
        let mut names = SymbolNames::new(arena, &[]);
        let body = bodies::body(&mut names, arena, cells, &from_x, "x", "out");
        let (t, x, out, statements, assignments) = (
            &body.t,
            &body.source,
            &body.out,
            &body.statements,
            &body.assignments,
        );
        let name = proc_macro2::Ident::new(name, proc_macro2::Span::call_site());
        quote! {
            fn #name(&self, #t: f64, #x: &[f64], #out: &mut Matrix) {
                #statements
                #(#assignments)*
            }
        }
    };
    let stated = vector("linear_stated", &p.stated);
    let fixed_fn = vector("linear_fixed", &fixed_cells);
    let rates = vector("linear_rates", &p.rates);
    let a = matrix("linear_a", &p.a);
    let b = matrix("linear_b", &p.b);
    let chain = matrix("linear_chain", &p.chain);
    quote! {
        impl lagc_python::Linear for Model {
            const LAYOUT: lagc_python::LinearLayout = lagc_python::LinearLayout {
                unavailable: None,
                free: #free,
                kept: #kept,
                ignorable: #ignorable,
                fixed: #fixed,
            };
            #stated
            #fixed_fn
            #rates
            #a
            #b
            #chain
        }
    }
}
