//! Models with implicit constraints of several candidates (SPEC §2.2) have
//! one reduced system per mode. Each mode's motion becomes inherent methods
//! `rhs_mode1`, …, and the trait's methods dispatch on the current mode.

use crate::ir::Symbol;
use crate::kernel::switches::switch_index;
use crate::kernel::Kernel;
use proc_macro2::{Group, Ident, Span, TokenStream, TokenTree};
use quote::quote;
use std::collections::HashMap;

/// The motion's methods (trait items and their inherent helpers).
const METHODS: [&str; 13] = [
    "rhs",
    "constrained",
    "kept_gradient",
    "mass_matrix",
    "jacobian",
    "time_partial",
    "linearize",
    "linearized",
    "mass_system",
    "highest",
    "highest_factored",
    "residual",
    "param_jacobian",
];

/// The trait methods a mode implements, with their argument lists.
const DISPATCHED: [(&str, &[&str]); 7] = [
    ("rhs", &["t", "x", "dx"]),
    ("constrained", &["t", "x", "kept"]),
    ("kept_gradient", &["t", "x", "jac"]),
    ("jacobian", &["t", "x", "jac"]),
    ("time_partial", &["t", "x", "dxdt"]),
    ("linearize", &["t", "x", "dx", "jac"]),
    ("param_jacobian", &["t", "x", "jac"]),
];

/// Mode `mode`'s items as inherent methods: every definition and every
/// `self.` call of a motion method renamed `NAME_modeM`.
pub fn renamed(trait_items: &TokenStream, helpers: &TokenStream, mode: usize) -> TokenStream {
    let items = rename(trait_items.clone(), mode);
    let helpers = rename(helpers.clone(), mode);
    quote! { #items #helpers }
}

fn rename(tokens: TokenStream, mode: usize) -> TokenStream {
    let mut out = Vec::new();
    let mut previous: Vec<String> = Vec::new();
    for tree in tokens {
        let tree = match tree {
            TokenTree::Group(g) => {
                let mut inner = Group::new(g.delimiter(), rename(g.stream(), mode));
                inner.set_span(g.span());
                TokenTree::Group(inner)
            }
            TokenTree::Ident(ident) => {
                let name = ident.to_string();
                let defined = previous.last().is_some_and(|p| p == "fn");
                let called = previous.len() >= 2
                    && previous[previous.len() - 1] == "."
                    && previous[previous.len() - 2] == "self";
                if METHODS.contains(&name.as_str()) && (defined || called) {
                    TokenTree::Ident(Ident::new(&format!("{name}_mode{mode}"), ident.span()))
                } else {
                    TokenTree::Ident(ident)
                }
            }
            other => other,
        };
        previous.push(tree.to_string());
        out.push(tree);
    }
    out.into_iter().collect()
}

/// Whether `items` define `fn name`.
fn defines(items: &TokenStream, name: &str) -> bool {
    let mut after_fn = false;
    for tree in items.clone() {
        if let TokenTree::Ident(ident) = &tree {
            if after_fn && ident == name {
                return true;
            }
            after_fn = ident == "fn";
        } else {
            after_fn = false;
        }
    }
    false
}

/// The trait methods, each a `match self.mode` over the modes.
pub fn dispatch(trait_items: &TokenStream, modes: usize) -> TokenStream {
    let mut items = Vec::new();
    for (name, args) in DISPATCHED {
        if !defines(trait_items, name) {
            continue;
        }
        let method = Ident::new(name, proc_macro2::Span::call_site());
        let arg_idents: Vec<Ident> = args
            .iter()
            .map(|a| Ident::new(a, proc_macro2::Span::call_site()))
            .collect();
        let arms = (0..modes).map(|m| {
            let target = Ident::new(&format!("{name}_mode{m}"), proc_macro2::Span::call_site());
            let pattern = if m + 1 == modes {
                quote! { _ }
            } else {
                let m = proc_macro2::Literal::usize_unsuffixed(m);
                quote! { #m }
            };
            quote! { #pattern => self.#target(#(#arg_idents),*), }
        });
        let signature = match name {
            "rhs" => quote! { t: f64, x: &[f64], dx: &mut [f64] },
            "constrained" => quote! { t: f64, x: &[f64], kept: &mut [f64] },
            "jacobian" | "kept_gradient" | "param_jacobian" => {
                quote! { t: f64, x: &[f64], jac: &mut Matrix }
            }
            "time_partial" => quote! { t: f64, x: &[f64], dxdt: &mut [f64] },
            _ => quote! { t: f64, x: &[f64], dx: &mut [f64], jac: &mut Matrix },
        };
        items.push(quote! {
            fn #method(&self, #signature) -> Result<(), Failure> {
                match self.mode {
                    #(#arms)*
                }
            }
        });
    }
    quote! { #(#items)* }
}

/// `mass_matrix` over the modes: each mode's own (`conditions[m]`, empty
/// when the mode has none) as an inherent `mass_matrix_modeM`, the trait's
/// method dispatching on the current mode. `(trait item, inherent items)`.
pub fn mass_dispatch(conditions: &[TokenStream]) -> (TokenStream, TokenStream) {
    if conditions.iter().all(TokenStream::is_empty) {
        return (TokenStream::new(), TokenStream::new());
    }
    let mut inherent = TokenStream::new();
    let mut arms = Vec::new();
    for (m, condition) in conditions.iter().enumerate() {
        let pattern = proc_macro2::Literal::usize_unsuffixed(m);
        if condition.is_empty() {
            continue;
        }
        inherent.extend(rename(condition.clone(), m));
        let target = Ident::new(&format!("mass_matrix_mode{m}"), Span::call_site());
        arms.push(quote! { #pattern => self.#target(t, x), });
    }
    let item = quote! {
        fn mass_matrix(&self, t: f64, x: &[f64]) -> Option<Matrix> {
            match self.mode {
                #(#arms)*
                _ => None,
            }
        }
    };
    (item, inherent)
}

/// A mode's branch symbols mapped to the first mode's switches: the same
/// switching function (by its text: every mode lowers the same statements)
/// reads the same branch. `pipeline` has checked that each one has a match.
pub fn shared_branches(first: &Kernel, mode: &Kernel) -> HashMap<Symbol, usize> {
    let index = switch_index(first);
    mode.switches
        .symbols
        .iter()
        .zip(&mode.switches.functions)
        .filter_map(|(&s, &g)| {
            index
                .get(&mode.arena.display(g).to_string())
                .map(|&k| (s, k))
        })
        .collect()
}
