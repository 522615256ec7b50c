//! `Params`: the model's params by their own names, with `Default` (the
//! file's values), overrides that recompute the params derived from them,
//! and the conversions the runtime's by-index view needs.

use super::names::SymbolNames;
use crate::kernel::Kernel;
use proc_macro2::{Literal, TokenStream};
use quote::quote;

pub fn params_code(kernel: &Kernel, names: &mut SymbolNames) -> TokenStream {
    let locals = names.params.clone();
    let fields = names.param_fields.clone();
    // `Params { k: k_2 }`, or the shorthand where the names agree (clippy's
    // `redundant_field_names`).
    let initialisers: Vec<TokenStream> = fields
        .iter()
        .zip(&locals)
        .map(|(f, l)| {
            if f == l {
                quote! { #f }
            } else {
                quote! { #f: #l }
            }
        })
        .collect();
    let mut statements = Vec::new();
    for (i, param) in kernel.params.iter().enumerate() {
        let code = names.code(&kernel.arena, &[param.value], &|_| None);
        let name = &locals[i];
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
    let docs: Vec<String> = kernel
        .params
        .iter()
        .map(|p| format!(" `{}` = `{}`", p.name, kernel.arena.display(p.value)))
        .collect();
    let indices: Vec<Literal> = (0..fields.len()).map(Literal::usize_unsuffixed).collect();
    let (overrides, values) = if fields.is_empty() {
        (quote! { _overrides }, quote! { _values })
    } else {
        (quote! { overrides }, quote! { values })
    };
    let param_fn = if fields.is_empty() {
        TokenStream::new()
    } else {
        quote! {
            /// Param `i`: its override, or its default (computed only then).
            fn param(overrides: &[Option<f64>], i: usize, default: impl FnOnce() -> f64) -> f64 {
                match overrides.get(i) {
                    Some(Some(value)) => *value,
                    _ => default(),
                }
            }
        }
    };
    quote! {
        /// The model's params, by their names in the model. `Default` gives
        /// the model's values; a changed param does not recompute the
        /// params computed from it — use [`Params::with_overrides`] for that.
        #[derive(Clone, Debug, PartialEq)]
        pub struct Params {
            #(#[doc = #docs] pub #fields: f64,)*
        }

        impl Default for Params {
            fn default() -> Params {
                Params::with_overrides(&[])
            }
        }

        impl Params {
            /// The params in declaration order: `overrides[i]`, when given,
            /// replaces param `i`; the others are computed from their
            /// expressions with the values before them.
            pub fn with_overrides(#overrides: &[Option<f64>]) -> Params {
                #(#statements)*
                Params { #(#initialisers),* }
            }

            /// The params from their values in declaration order.
            pub fn from_values(#values: &[f64]) -> Params {
                Params { #(#fields: values[#indices]),* }
            }

            /// The values in declaration order.
            pub fn values(&self) -> Vec<f64> {
                vec![#(self.#fields),*]
            }
        }

        #param_fn
    }
}
