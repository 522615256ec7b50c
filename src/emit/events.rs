//! The regime of a run (SPEC §2.2): the switches' branches the right side
//! reads, the switching functions the runtime watches, `stop when`, the
//! impacts (`when`, SPEC §2.3), the `output` columns, and where the
//! constraints as written end.

use super::names::{Source, SymbolNames};
use crate::kernel::{BranchCond, Kernel};
use proc_macro2::{Literal, TokenStream};
use quote::quote;

/// The model struct's field and its initial value, when it has switches.
pub fn branch_field(kernel: &Kernel) -> (TokenStream, TokenStream) {
    let k = kernel.switches.functions.len();
    let (mut field, mut init) = (TokenStream::new(), TokenStream::new());
    if k > 0 {
        let k = Literal::usize_unsuffixed(k);
        field.extend(quote! {
            /// The sign (±1) of each switching function on the current
            /// segment: the branch every selection takes.
            branches: [f64; #k],
        });
        init.extend(quote! { branches: [1.0; #k], });
    }
    if !kernel.inputs.is_empty() {
        field.extend(quote! {
            /// The inputs on the current segment, set by the run between
            /// segments (`Model::set_inputs`): the right side reads them
            /// like params.
            inputs: lagc_runtime::model::Inputs,
        });
        init.extend(quote! {
            inputs: lagc_runtime::model::Inputs::held(
                <Model as lagc_runtime::model::Model>::INPUT_DEFAULTS,
            ),
        });
    }
    if !kernel.modes.is_empty() {
        field.extend(quote! {
            /// The reduced system in use: which candidate each implicit
            /// constraint is solved for.
            mode: usize,
        });
        init.extend(quote! { mode: 0, });
    }
    (field, init)
}

/// `SWITCHES`, `OUTPUTS`.
pub fn consts(kernel: &Kernel) -> TokenStream {
    let k = kernel.switches.functions.len();
    let switches = if k == 0 {
        TokenStream::new()
    } else {
        let k = Literal::usize_unsuffixed(k);
        quote! { const SWITCHES: usize = #k; }
    };
    let inputs = if kernel.inputs.is_empty() {
        TokenStream::new()
    } else {
        let names = kernel.inputs.iter().map(|(n, _)| n.as_str());
        let defaults = kernel
            .inputs
            .iter()
            .map(|&(_, d)| super::expr::signed_literal(d));
        quote! {
            const INPUTS: &'static [&'static str] = &[#(#names),*];
            const INPUT_DEFAULTS: &'static [f64] = &[#(#defaults),*];
            fn set_inputs(&mut self, inputs: &lagc_runtime::model::Inputs) {
                self.inputs.clone_from(inputs);
            }
        }
    };
    let outputs = if kernel.outputs.is_empty() {
        TokenStream::new()
    } else {
        let names = kernel.outputs.iter().map(|(n, _)| n.as_str());
        quote! { const OUTPUTS: &'static [&'static str] = &[#(#names),*]; }
    };
    let constraints = if kernel.candidates.is_empty() {
        TokenStream::new()
    } else {
        let entries = kernel.candidates.iter().map(|c| {
            let text = &c.text;
            let names = &c.names;
            quote! {
                lagc_runtime::model::Candidates { text: #text, names: &[#(#names),*] }
            }
        });
        quote! {
            const CONSTRAINTS: &'static [lagc_runtime::model::Candidates] = &[#(#entries),*];
        }
    };
    let impacts = if kernel.impacts.is_empty() {
        TokenStream::new()
    } else {
        let texts = kernel.impacts.iter().map(|i| i.text.as_str());
        // A model of several modes names each impact's targets: the run
        // chooses the mode after the resets and recomputes what it fixes.
        let targets = if kernel.modes.is_empty() {
            TokenStream::new()
        } else {
            let tables = kernel.impacts.iter().map(|i| {
                let slots = i.resets.iter().map(|&(k, _)| Literal::usize_unsuffixed(k));
                quote! { &[#(#slots),*] }
            });
            quote! { const IMPACT_TARGETS: &'static [&'static [usize]] = &[#(#tables),*]; }
        };
        quote! {
            const IMPACTS: &'static [&'static str] = &[#(#texts),*];
            #targets
        }
    };

    let domains = if kernel.domains.is_empty() {
        TokenStream::new()
    } else {
        let entries = kernel.domains.iter().map(|d| {
            let constraint = &d.constraint;
            let argument = &d.text;
            // The runtime's variant, by its name (the kernel holds the
            // runtime's type).
            let kind =
                proc_macro2::Ident::new(&format!("{:?}", d.kind), proc_macro2::Span::call_site());
            quote! {
                lagc_runtime::model::Domain {
                    constraint: #constraint,
                    kind: lagc_runtime::model::DomainKind::#kind,
                    argument: #argument,
                }
            }
        });
        quote! {
            const DOMAINS: &'static [lagc_runtime::model::Domain] = &[#(#entries),*];
        }
    };
    quote! { #switches #inputs #outputs #constraints #impacts #domains }
}

/// `set_regime`, `switching_functions`, `stop`, `outputs`.
pub fn items(kernel: &Kernel, names: &mut SymbolNames, from_x: Source) -> TokenStream {
    let mut items = Vec::new();
    let set_branches = if kernel.switches.functions.is_empty() {
        TokenStream::new()
    } else {
        quote! {
            for (sign, &positive) in self.branches.iter_mut().zip(&regime.branches) {
                *sign = if positive { 1.0 } else { -1.0 };
            }
        }
    };
    let set_mode = if kernel.modes.is_empty() {
        TokenStream::new()
    } else {
        quote! { self.mode = regime.mode; }
    };
    if !set_branches.is_empty() || !set_mode.is_empty() {
        items.push(quote! {
            fn set_regime(&mut self, regime: &lagc_runtime::model::Regime) {
                #set_mode
                #set_branches
            }
        });
    }
    if !kernel.candidates.is_empty() {
        let roots: Vec<_> = kernel
            .candidates
            .iter()
            .flat_map(|c| c.pivots.iter().copied())
            .collect();
        items.push(values_fn(kernel, names, from_x, &roots, "pivots", "out"));
    }
    if !kernel.domains.is_empty() {
        let roots: Vec<_> = kernel
            .domains
            .iter()
            .flat_map(|d| [d.argument, d.scale])
            .collect();
        items.push(values_fn(
            kernel,
            names,
            from_x,
            &roots,
            "domain_values",
            "out",
        ));
    }
    if !kernel.switches.functions.is_empty() {
        let roots = &kernel.switches.functions;
        items.push(values_fn(
            kernel,
            names,
            from_x,
            roots,
            "switching_functions",
            "g",
        ));
    }
    if let Some(stop) = &kernel.stop {
        let cond = condition(stop);
        items.push(quote! {
            fn stop(&self, branches: &[bool]) -> bool {
                #cond
            }
        });
    }
    if !kernel.impacts.is_empty() {
        items.push(impact_items(kernel, names, from_x));
    }
    if !kernel.outputs.is_empty() {
        let roots: Vec<_> = kernel.outputs.iter().map(|&(_, e)| e).collect();
        items.push(values_fn(kernel, names, from_x, &roots, "outputs", "out"));
    }
    quote! { #(#items)* }
}

/// `impact_holds` and `impact_reset`: each `when`'s condition on the
/// branches, and its resets (read from `x`, the state before the impact)
/// followed, in a model of one mode, by the components the constraints
/// fix (read from `out`, the state after it; a model of several modes
/// leaves them to the run, which chooses the mode first).
fn impact_items(kernel: &Kernel, names: &mut SymbolNames, from_x: Source) -> TokenStream {
    let numbers: Vec<Literal> = (0..kernel.impacts.len())
        .map(Literal::usize_unsuffixed)
        .collect();
    let conditions = kernel.impacts.iter().map(|i| condition(&i.condition));
    let (mut uses_time, mut uses_x) = (false, false);
    let mut arms = Vec::new();
    for (w, impact) in numbers.iter().zip(&kernel.impacts) {
        let roots: Vec<_> = impact.resets.iter().map(|&(_, e)| e).collect();
        let code = names.code(&kernel.arena, &roots, from_x);
        uses_time |= code.uses_time;
        uses_x |= code.uses_source;
        let statements = code.statements(quote! { self.params });
        let slots = impact
            .resets
            .iter()
            .map(|&(k, _)| Literal::usize_unsuffixed(k));
        let values = &code.roots;
        arms.push(quote! {
            if w == #w {
                #statements
                #(out[#slots] = #values;)*
            }
        });
    }
    let constrained = if kernel.constrained.is_empty() || !kernel.modes.is_empty() {
        TokenStream::new()
    } else {
        let position: std::collections::HashMap<_, _> = kernel
            .state
            .iter()
            .enumerate()
            .map(|(i, &s)| (s, Literal::usize_unsuffixed(i)))
            .collect();
        let from_out = move |s| position.get(&s).map(|i| quote! { out[#i] });
        let roots: Vec<_> = kernel.constrained.iter().map(|&(_, e)| e).collect();
        let code = names.code(&kernel.arena, &roots, &from_out);
        uses_time |= code.uses_time;
        let statements = code.statements(quote! { self.params });
        let slots = kernel
            .constrained
            .iter()
            .map(|&(k, _)| Literal::usize_unsuffixed(k));
        let values = &code.roots;
        quote! {
            // The derivatives the constraints fix, from the new state.
            {
                #statements
                #(out[#slots] = #values;)*
            }
        }
    };
    let t = if uses_time {
        quote! { t }
    } else {
        quote! { _t }
    };
    let x = if uses_x {
        quote! { x }
    } else {
        quote! { _x }
    };
    quote! {
        fn impact_holds(&self, w: usize, branches: &[bool]) -> bool {
            match w {
                #(#numbers => #conditions,)*
                _ => false,
            }
        }

        fn impact_reset(&self, w: usize, #t: f64, #x: &[f64], out: &mut [f64]) {
            #(#arms)*
            #constrained
        }
    }
}

/// A condition on the branches (`branches[k]`: `g_k > 0`), without outer
/// parentheses (a function's body with them is a rustc warning).
fn condition(cond: &BranchCond) -> TokenStream {
    match cond {
        BranchCond::Negative(k) => {
            let k = Literal::usize_unsuffixed(*k);
            quote! { !branches[#k] }
        }
        BranchCond::Not(c) => {
            let c = condition(c);
            quote! { !(#c) }
        }
        BranchCond::And(a, b) => {
            let (a, b) = (operand(a), operand(b));
            quote! { #a && #b }
        }
        BranchCond::Or(a, b) => {
            let (a, b) = (operand(a), operand(b));
            quote! { #a || #b }
        }
    }
}

/// A condition as an operand of `&&` or `||`: parenthesised when it is one
/// of them itself.
fn operand(cond: &BranchCond) -> TokenStream {
    let printed = condition(cond);
    match cond {
        BranchCond::And(..) | BranchCond::Or(..) => quote! { (#printed) },
        BranchCond::Negative(_) | BranchCond::Not(_) => printed,
    }
}

/// `fn NAME(&self, t, x, OUT: &mut [f64])` writing `roots` in order: the
/// shape of the model's pivots, switching functions and outputs.
fn values_fn(
    kernel: &Kernel,
    names: &mut SymbolNames,
    from_x: Source,
    roots: &[crate::ir::ExprId],
    name: &str,
    out: &str,
) -> TokenStream {
    let code = names.code(&kernel.arena, roots, from_x);
    let statements = code.statements(quote! { self.params });
    let t = code.time_arg();
    let x = if code.uses_source {
        quote! { x }
    } else {
        quote! { _x }
    };
    let slots = (0..code.roots.len()).map(Literal::usize_unsuffixed);
    let values = &code.roots;
    let name = proc_macro2::Ident::new(name, proc_macro2::Span::call_site());
    let out = proc_macro2::Ident::new(out, proc_macro2::Span::call_site());
    quote! {
        fn #name(&self, #t: f64, #x: &[f64], #out: &mut [f64]) {
            #statements
            #(#out[#slots] = #values;)*
        }
    }
}
