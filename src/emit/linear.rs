//! `impl lagc_python::Linear for Model`: the linearization's symbolic half
//! ([`crate::linearize::LinearParts`], taken in `src/linearize/parts.rs`)
//! printed for a model's Python module, whose `m.linearize(at=…)` evaluates
//! it at a point as `lagc linearize` does (`python/src/linear.rs`). Only
//! the Python project carries it: the crate `lagc run` builds does not.
//! Every function takes the mode (the candidates' choice of dependents)
//! and matches on it; a model of one mode has mode 0 only.

use super::bodies::{self, index};
use super::names::SymbolNames;
use crate::diagnostic::Diagnostic;
use crate::ir::{ExprId, Symbol};
use crate::linearize::LinearParts;
use proc_macro2::TokenStream;
use quote::quote;

/// The impl block's source text, formatted; `parts` is the symbolic
/// linearization of every mode, or why the module cannot carry it.
pub fn linear_code(parts: &Result<Vec<LinearParts>, String>) -> Result<String, Diagnostic> {
    let tokens = match parts {
        Err(why) => quote! {
            impl lagc_python::Linear for Model {
                const UNAVAILABLE: Option<&'static str> = Some(#why);
                const LAYOUTS: &'static [lagc_python::LinearLayout] = &[];
            }
        },
        Ok(modes) => available(modes),
    };
    super::pretty(tokens)
}

fn available(modes: &[LinearParts]) -> TokenStream {
    let layouts = modes.iter().map(layout);
    let fixed_cells: Vec<Vec<(usize, ExprId)>> = modes
        .iter()
        .map(|p| {
            p.fixed
                .iter()
                .enumerate()
                .map(|(i, &(_, e))| (i, e))
                .collect()
        })
        .collect();
    let vector = |name: &str, cells: &dyn Fn(usize) -> Vec<(usize, ExprId)>| {
        function(modes, name, quote! { &mut [f64] }, &|m| {
            cells(m).into_iter().map(|(r, e)| (r, None, e)).collect()
        })
    };
    let matrix = |name: &str, cells: &dyn Fn(usize) -> Vec<(usize, usize, ExprId)>| {
        function(modes, name, quote! { &mut Matrix }, &|m| {
            cells(m)
                .into_iter()
                .map(|(r, c, e)| (r, Some(c), e))
                .collect()
        })
    };
    let implicit = |m: usize| modes[m].implicit.as_ref();
    let closure = |m: usize| modes[m].closure.as_ref();
    let items = vec![
        vector("linear_stated", &|m| modes[m].stated.clone()),
        vector("linear_fixed", &|m| fixed_cells[m].clone()),
        vector("linear_rates", &|m| modes[m].rates.clone()),
        matrix("linear_a", &|m| modes[m].a.clone()),
        matrix("linear_b", &|m| modes[m].b.clone()),
        matrix("linear_chain", &|m| modes[m].chain.clone()),
        vector("linear_g", &|m| {
            implicit(m).map_or_else(Vec::new, |i| i.residual.clone())
        }),
        matrix("linear_g_z", &|m| {
            implicit(m).map_or_else(Vec::new, |i| i.g_z.clone())
        }),
        matrix("linear_g_x", &|m| {
            implicit(m).map_or_else(Vec::new, |i| i.g_x.clone())
        }),
        matrix("linear_g_p", &|m| {
            implicit(m).map_or_else(Vec::new, |i| i.g_p.clone())
        }),
        matrix("linear_d_z", &|m| {
            implicit(m).map_or_else(Vec::new, |i| i.d_z.clone())
        }),
        vector("linear_f", &|m| {
            closure(m).map_or_else(Vec::new, |c| c.residual.clone())
        }),
        matrix("linear_f_z", &|m| {
            closure(m).map_or_else(Vec::new, |c| c.f_z.clone())
        }),
        matrix("linear_f_x", &|m| {
            closure(m).map_or_else(Vec::new, |c| c.f_x.clone())
        }),
        matrix("linear_f_p", &|m| {
            closure(m).map_or_else(Vec::new, |c| c.f_p.clone())
        }),
    ];
    quote! {
        impl lagc_python::Linear for Model {
            const UNAVAILABLE: Option<&'static str> = None;
            const LAYOUTS: &'static [lagc_python::LinearLayout] = &[#(#layouts),*];
            #(#items)*
        }
    }
}

fn layout(p: &LinearParts) -> TokenStream {
    let list = |v: &[usize]| {
        let items = v.iter().map(|&i| index(i));
        quote! { &[#(#items),*] }
    };
    let (free, kept, ignorable) = (list(&p.free), list(&p.kept), list(&p.ignorable));
    let fixed_indices: Vec<usize> = p.fixed.iter().map(|&(k, _)| k).collect();
    let fixed = list(&fixed_indices);
    let bound = list(p.closure.as_ref().map_or(&[][..], |c| &c.bound[..]));
    let pairs = p.unknown_rows.iter().map(|&(i, j)| {
        let (i, j) = (index(i), index(j));
        quote! { (#i, #j) }
    });
    let count = index(p.implicit.as_ref().map_or(0, |i| i.unknowns.len()));
    let linear = p.implicit.as_ref().is_none_or(|i| i.linear);
    quote! {
        lagc_python::LinearLayout {
            free: #free,
            kept: #kept,
            ignorable: #ignorable,
            fixed: #fixed,
            bound: #bound,
            unknowns: #count,
            unknown_rows: &[#(#pairs),*],
            implicit_linear: #linear,
        }
    }
}

/// One function of `(mode, t, x, z)` writing `cells(mode)` into `out`: the
/// free state from `x`, the implicit system's unknowns from `z`, a `match`
/// on the mode when there are several.
fn function(
    modes: &[LinearParts],
    name: &str,
    out_type: TokenStream,
    cells: &dyn Fn(usize) -> Vec<(usize, Option<usize>, ExprId)>,
) -> TokenStream {
    let (mut uses_t, mut uses_x, mut uses_z, mut writes) = (false, false, false, false);
    let mut arms = Vec::new();
    for (m, p) in modes.iter().enumerate() {
        let arena = &p.arena;
        let state = &p.state;
        let unknowns: Vec<Symbol> = p
            .implicit
            .as_ref()
            .map_or_else(Vec::new, |i| i.unknowns.clone());
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
        let cells = cells(m);
        let roots: Vec<ExprId> = cells.iter().map(|&(_, _, e)| e).collect();
        let mut names = SymbolNames::new(arena, &[]);
        let code = names.code(arena, &roots, &source);
        let reads = |set: &[Symbol]| {
            roots
                .iter()
                .any(|&r| set.iter().any(|&s| arena.depends_on(r, s)))
        };
        uses_t |= code.uses_time;
        uses_x |= reads(state);
        uses_z |= reads(&unknowns);
        writes |= !roots.is_empty();
        let statements = code.statements(quote! { self.params });
        let assignments: Vec<TokenStream> = cells
            .iter()
            .zip(&code.roots)
            .map(|(&(r, c, _), v)| {
                let r = index(r);
                match c {
                    Some(c) => {
                        let c = index(c);
                        quote! { out[(#r, #c)] = #v; }
                    }
                    None => quote! { out[#r] = #v; },
                }
            })
            .collect();
        arms.push((m, quote! { #statements #(#assignments)* }));
    }
    let arms: Vec<(usize, TokenStream)> = arms.into_iter().filter(|(_, b)| !b.is_empty()).collect();
    let body = match arms.as_slice() {
        [] => TokenStream::new(),
        [(_, b)] if modes.len() == 1 => b.clone(),
        [(m, b)] => {
            let m = index(*m);
            quote! { if mode == #m { #b } }
        }
        _ => {
            let arms = arms.iter().map(|(m, b)| {
                let m = index(*m);
                quote! { #m => { #b } }
            });
            quote! {
                match mode {
                    #(#arms)*
                    _ => {}
                }
            }
        }
    };
    let mode = bodies::arg(modes.len() > 1 && writes, "mode");
    let t = bodies::arg(uses_t, "t");
    let (x, z) = (bodies::arg(uses_x, "x"), bodies::arg(uses_z, "z"));
    let out = bodies::arg(writes, "out");
    let name = proc_macro2::Ident::new(name, proc_macro2::Span::call_site());
    quote! {
        fn #name(&self, #mode: usize, #t: f64, #x: &[f64], #z: &[f64], #out: #out_type) {
            #body
        }
    }
}
