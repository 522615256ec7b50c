//! The model's data in the generated library: params (defaults computed
//! in order, overridable), mass laws, the time span, the initial state and
//! the exact solution.

use super::names::{Source, SymbolNames};
use crate::check::model::Model;
use crate::diagnostic::{codes, Diagnostic};
use crate::ir::{lower, Arena, ExprId, Symbol};
use crate::mechanics::{InitialValue, ReducedSystem};
use proc_macro2::{Literal, TokenStream};
use quote::quote;
use std::collections::HashMap;

/// `struct Params` and `Params::new(overrides)`: each param is its
/// override or its expression of the params before it, so overriding one
/// recomputes the ones derived from it.
pub fn params_code(arena: &mut Arena, names: &mut SymbolNames, model: &Model) -> TokenStream {
    let fields = names.params.clone();
    let mut statements = Vec::new();
    for (i, param) in model.params.iter().enumerate() {
        let value = lower(arena, &param.value, model);
        let code = names.code(arena, &[value], &|_| None);
        let name = &fields[i];
        // Earlier params are locals here already: no bindings from `p`.
        let lets = &code.lets;
        let root = &code.roots[0];
        let k = Literal::usize_unsuffixed(i);
        let default = if lets.is_empty() {
            quote! { #root }
        } else {
            quote! { { #(#lets)* #root } }
        };
        statements.push(quote! {
            let #name = param(overrides, #k, || #default);
        });
    }
    let count = Literal::usize_unsuffixed(fields.len());
    let param_names: Vec<&str> = model.params.iter().map(|p| p.name.as_str()).collect();
    let overrides = if fields.is_empty() {
        quote! { _overrides }
    } else {
        quote! { overrides }
    };
    let param_fn = if fields.is_empty() {
        TokenStream::new()
    } else {
        param_fn()
    };
    quote! {
        /// The model's params, by their names in the model.
        pub const PARAM_NAMES: [&str; #count] = [#(#param_names),*];

        /// The params' values.
        #[derive(Clone, Debug, PartialEq)]
        pub struct Params {
            #(pub #fields: f64,)*
        }

        impl Params {
            /// The params in declaration order: `overrides[i]`, when given,
            /// replaces param `i`; the others are computed from their
            /// expressions with the values before them.
            pub fn new(#overrides: &[Option<f64>]) -> Params {
                #(#statements)*
                Params { #(#fields),* }
            }
        }

        #param_fn
    }
}

/// The override-or-default helper of `Params::new`.
fn param_fn() -> TokenStream {
    quote! {
        /// Param `i`: its override, or its default (computed only then).
        fn param(overrides: &[Option<f64>], i: usize, default: impl FnOnce() -> f64) -> f64 {
            match overrides.get(i) {
                Some(Some(value)) => *value,
                _ => default(),
            }
        }
    }
}

/// One function per mass law the reduced system still holds.
pub fn mass_code(
    arena: &mut Arena,
    names: &mut SymbolNames,
    model: &Model,
    reduced: &ReducedSystem,
) -> TokenStream {
    let mut items = Vec::new();
    for &(i, law) in &reduced.mass_laws {
        let code = names.code(arena, &[law], &|_| None);
        let statements = code.statements(quote! { params });
        let root = &code.roots[0];
        let t = code.time_arg();
        let p = if code.uses_params {
            quote! { params }
        } else {
            quote! { _params }
        };
        let f = &names.mass_fns[i as usize];
        let doc = format!(
            " The mass law `{}(t)`.",
            model.masses.get(i as usize).map_or("", |m| m.name.as_str())
        );
        items.push(quote! {
            #[doc = #doc]
            pub fn #f(#p: &Params, #t: f64) -> f64 {
                #statements
                #root
            }
        });
    }
    quote! { #(#items)* }
}

/// `time_span(p)`: the model's `time t0 .. t1`.
pub fn time_code(arena: &mut Arena, names: &mut SymbolNames, model: &Model) -> TokenStream {
    let start = lower(arena, &model.time.start, model);
    let end = lower(arena, &model.time.end, model);
    let code = names.code(arena, &[start, end], &|_| None);
    let statements = code.statements(quote! { params });
    let (t0, t1) = (&code.roots[0], &code.roots[1]);
    let p = if code.uses_params {
        quote! { params }
    } else {
        quote! { _params }
    };
    quote! {
        /// The time span `(t0, t1)`.
        pub fn time_span(#p: &Params) -> (f64, f64) {
            #statements
            (#t0, #t1)
        }
    }
}

/// `initial_state(p)`: `Given` values first, then those fixed by the
/// constraints (which use only `Given` ones), then the consistency stages
/// for k ≥ 3 in order (which may use all before them).
pub fn initial_code(
    arena: &mut Arena,
    names: &mut SymbolNames,
    reduced: &ReducedSystem,
) -> Result<TokenStream, Diagnostic> {
    let mut statements = Vec::new();
    let mut known: HashMap<Symbol, TokenStream> = HashMap::new();
    let mut uses_time = false;
    let mut uses_params = false;
    let mut emit = |arena: &mut Arena,
                    names: &mut SymbolNames,
                    s: Symbol,
                    e: ExprId,
                    known: &mut HashMap<Symbol, TokenStream>| {
        let source: Source = &|sym| known.get(&sym).cloned();
        let code = names.code(arena, &[e], source);
        let value = code.single(quote! { params });
        let name = names.ident(arena, s);
        uses_time |= code.uses_time;
        uses_params |= code.uses_params;
        statements.push(quote! { let #name = #value; });
        known.insert(s, name);
    };
    for (k, value) in reduced.initial.iter().enumerate() {
        if let InitialValue::Given(e) = value {
            emit(arena, names, reduced.state[k], *e, &mut known);
        }
    }
    for (k, value) in reduced.initial.iter().enumerate() {
        if let InitialValue::Constraint(e) = value {
            emit(arena, names, reduced.state[k], *e, &mut known);
        }
    }
    for stage in &reduced.consistency {
        let Some(explicit) = &stage.explicit else {
            return Err(Diagnostic::error(
                codes::INCONSISTENT_INITIAL,
                "the consistent initial values of the higher derivatives have no symbolic \
                 solution; the code generator cannot solve them numerically yet",
            ));
        };
        for (&s, &e) in stage.unknowns.iter().zip(explicit) {
            emit(arena, names, s, e, &mut known);
        }
    }
    let t = if uses_time {
        quote! { let t = time_span(params).0; }
    } else {
        TokenStream::new()
    };
    let mut values = Vec::new();
    for &s in &reduced.state {
        match known.get(&s) {
            Some(v) => values.push(v.clone()),
            None => {
                return Err(Diagnostic::error(
                    codes::MISSING_INITIAL,
                    format!("no initial value for `{}`", arena.symbol_name(s)),
                ))
            }
        }
    }
    // A model without params, or whose initial values use none, would
    // leave `params` unused (a warning in the generated crate).
    let params = if uses_params || uses_time {
        quote! { params }
    } else {
        quote! { _params }
    };
    Ok(quote! {
        /// The initial state (6) at `t0`.
        pub fn initial_state(#params: &Params) -> Vec<f64> {
            #t
            #(#statements)*
            vec![#(#values),*]
        }
    })
}

/// `exact_state(p, t)` and the largest error against it, only when the
/// model states an exact solution.
pub fn exact_code(
    arena: &mut Arena,
    names: &mut SymbolNames,
    model: &Model,
    reduced: &ReducedSystem,
) -> TokenStream {
    if model.exact.is_empty() {
        return quote! {
            /// The model states no exact solution.
            pub fn largest_exact_error(_params: &Params, _samples: &[(f64, Vec<f64>)]) -> Option<f64> {
                None
            }
        };
    }
    let mut roots = Vec::new();
    let mut slots = Vec::new();
    for exact in &model.exact {
        let symbol = Symbol::Jet {
            coord: exact.coord as u32,
            order: exact.order,
        };
        if let Some(k) = reduced.state.iter().position(|&s| s == symbol) {
            roots.push(lower(arena, &exact.value, model));
            slots.push(Literal::usize_unsuffixed(k));
        }
    }
    let code = names.code(arena, &roots, &|_| None);
    let statements = code.statements(quote! { params });
    let values = &code.roots;
    let n = Literal::usize_unsuffixed(reduced.state.len());
    let t = code.time_arg();
    let p = if code.uses_params {
        quote! { params }
    } else {
        quote! { _params }
    };
    quote! {
        /// The model's exact solution at `t`, for the components it gives.
        pub fn exact_state(#p: &Params, #t: f64) -> [Option<f64>; #n] {
            #statements
            let mut exact = [None; #n];
            #(exact[#slots] = Some(#values);)*
            exact
        }

        /// The largest error against the exact solution over `samples`,
        /// relative to `max(|exact|, 1)`.
        pub fn largest_exact_error(params: &Params, samples: &[(f64, Vec<f64>)]) -> Option<f64> {
            let mut largest = 0.0_f64;
            for (t, x) in samples {
                for (value, truth) in x.iter().zip(exact_state(params, *t)) {
                    if let Some(truth) = truth {
                        largest = largest.max((value - truth).abs() / truth.abs().max(1.0));
                    }
                }
            }
            Some(largest)
        }
    }
}
