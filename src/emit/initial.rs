//! `Initial`: the initial state (6) by the model's names, each value an
//! `Option<f64>` (`None`: the model's own value), for the library API.
//! Fields: a coordinate by its name, its derivatives `q_dot`, `q_ddot`,
//! then `q_d3`, `q_d4`, … (through the one namer, in a namespace of their
//! own: a coordinate that is itself called `q_dot` keeps its name and the
//! derivative becomes `q_dot_2`).

use super::namer::Namer;
use crate::ir::Symbol;
use crate::kernel::{InitialKind, InitialSource, Kernel};
use proc_macro2::{Ident, TokenStream};
use quote::quote;

/// The field name a state symbol wants (before clashes are resolved).
fn wanted(kernel: &Kernel, s: Symbol) -> String {
    match s {
        Symbol::Jet { coord, order } => {
            let q = kernel
                .arena
                .names()
                .coords
                .get(coord as usize)
                .cloned()
                .unwrap_or_else(|| format!("q{coord}"));
            // The stem as the namer would write it, so that `self'` gives
            // `self_dot`, not `self__dot`.
            let q = super::namer::sanitize(&q);
            let q = q.trim_end_matches('_');
            match order {
                0 => q.to_string(),
                1 => format!("{q}_dot"),
                2 => format!("{q}_ddot"),
                k => format!("{q}_d{k}"),
            }
        }
        other => kernel.arena.symbol_name(other),
    }
}

/// The field names, in state order (coordinates first, so a coordinate
/// keeps its own name when a derivative's would clash with it).
pub fn field_names(kernel: &Kernel) -> Vec<Ident> {
    let mut namer = Namer::empty();
    kernel
        .state
        .iter()
        .map(|&s| namer.fresh(&wanted(kernel, s)))
        .collect()
}

/// The doc comment of component `k`: its model name and where its value
/// comes from.
fn field_doc(kernel: &Kernel, k: usize) -> String {
    let arena = &kernel.arena;
    let name = arena.symbol_name(kernel.state[k]);
    let stated = kernel
        .initial
        .stated
        .iter()
        .find(|&&(i, _)| i == k)
        .map(|&(_, e)| {
            format!(
                " The model states `{}`, checked the same way.",
                arena.display(e)
            )
        })
        .unwrap_or_default();
    match kernel.initial.kinds.get(k) {
        Some(InitialKind::Given) => {
            let value = kernel.initial.sources.iter().find_map(|s| match *s {
                InitialSource::Given { index, value } if index == k => Some(value),
                _ => None,
            });
            match value {
                Some(v) => format!(
                    " `{name}` at `t0`; `None`: the model's value, `{}`.",
                    arena.display(v)
                ),
                None => format!(" `{name}` at `t0`; `None`: the model's value."),
            }
        }
        Some(InitialKind::Constraint) => {
            let value = kernel.initial.sources.iter().find_map(|s| match *s {
                InitialSource::Constraint { index, value } if index == k => Some(value),
                _ => None,
            });
            let rule = value
                .map(|v| format!(" as `{name} = {}`", arena.display(v)))
                .unwrap_or_default();
            format!(
                " `{name}` at `t0`: fixed by the constraints{rule}, from the other values. \
                 `None` computes it; a value must agree with it (to 1e-9 relative), or \
                 `solve` fails with an inconsistent initial value.{stated}"
            )
        }
        Some(InitialKind::Solved) | None => format!(
            " `{name}` at `t0`: fixed by the equations of motion and the constraints \
             (the consistent initial values of a constraint of order k ≥ 3). `None` \
             computes it; a value must agree with it (to 1e-9 relative), or `solve` \
             fails with an inconsistent initial value.{stated}"
        ),
    }
}

/// `text` as doc lines of at most about 76 characters, broken at spaces
/// outside code spans (each line one `#[doc]` attribute, as `///` lines).
fn wrapped(text: &str) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    let mut in_code = false;
    let mut word = String::new();
    let flush = |word: &mut String, line: &mut String, lines: &mut Vec<String>| {
        if !line.is_empty() && line.len() + 1 + word.len() > 76 {
            lines.push(format!(" {line}"));
            line.clear();
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
        word.clear();
    };
    for c in text.trim().chars() {
        if c == '`' {
            in_code = !in_code;
        }
        if c == ' ' && !in_code {
            if !word.is_empty() {
                flush(&mut word, &mut line, &mut lines);
            }
        } else {
            word.push(c);
        }
    }
    if !word.is_empty() {
        flush(&mut word, &mut line, &mut lines);
    }
    if !line.is_empty() {
        lines.push(format!(" {line}"));
    }
    lines
}

/// The `Initial` struct with `Default` (all `None`) and its by-index view.
pub fn initial_code(kernel: &Kernel) -> TokenStream {
    let fields = field_names(kernel);
    let docs: Vec<Vec<String>> = (0..fields.len())
        .map(|k| wrapped(&field_doc(kernel, k)))
        .collect();
    let columns: Vec<String> = kernel
        .state
        .iter()
        .map(|&s| format!("`{}`", kernel.arena.symbol_name(s)))
        .collect();
    let doc = format!(
        " The initial state (6) at `t0` by the model's names ({}): `None` keeps the \
         model's own value, so `Initial::default()` is the model's initial state. A \
         derivative `q'` is the field `q_dot`, `q''` `q_ddot`, `q'''` `q_d3`. Values the \
         constraints fix may be left `None`; a value given for them is checked, not \
         imposed.",
        columns.join(", ")
    );
    let doc = wrapped(&doc);
    quote! {
        #(#[doc = #doc])*
        #[derive(Clone, Copy, Debug, Default, PartialEq)]
        pub struct Initial {
            #(#(#[doc = #docs])* pub #fields: Option<f64>,)*
        }

        impl Initial {
            /// The values in the order of the state (the CSV columns after
            /// `t`, `<Model as lagc_runtime::model::Model>::STATE`).
            pub fn values(&self) -> Vec<Option<f64>> {
                vec![#(self.#fields),*]
            }
        }
    }
}
