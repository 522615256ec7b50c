//! The model's data as trait items: identity constants, params, the time
//! span, the initial state (with the stated values of dependent components
//! checked after overrides), the exact solution and the mass laws.

use super::bodies::index;
use super::names::{Source, SymbolNames};
use crate::ir::Symbol;
use crate::kernel::{InitialKind, InitialSource, Kernel};
use proc_macro2::{Literal, TokenStream};
use quote::quote;
use std::collections::HashMap;

/// One free function per mass law, `mass_<name>(p, t)`, or
/// `mass_<name>(p, t, x)` for a law of the state (its coordinates from `x`).
pub fn mass_fns(kernel: &Kernel, names: &mut SymbolNames) -> TokenStream {
    let mut items = Vec::new();
    for (i, (name, law)) in kernel.masses.iter().enumerate() {
        let of_state = kernel.state_laws.contains(&(i as u32));
        let from_x = |s: Symbol| match s {
            Symbol::Jet { coord, order: 0 } => {
                let k = index(coord as usize);
                Some(quote! { x[#k] })
            }
            _ => None,
        };
        let code = names.code(&kernel.arena, &[*law], &from_x);
        let statements = code.statements_in_p();
        let root = &code.roots[0];
        let t = code.time_arg();
        let p = if code.uses_params {
            quote! { p }
        } else {
            quote! { _p }
        };
        let f = &names.mass_fns[i];
        let (args, state) = if of_state {
            ("t, q", quote! { , x: &[f64] })
        } else {
            ("t", TokenStream::new())
        };
        let doc = format!(
            " The mass law `{name}({args}) = {}`.",
            kernel.arena.display(*law)
        );
        items.push(quote! {
            #[doc = #doc]
            fn #f(#p: &Params, #t: f64 #state) -> f64 {
                #statements
                #root
            }
        });
    }
    quote! { #(#items)* }
}

/// `time_span`, `initial_state`, `exact`, `masses`.
pub fn data_items(kernel: &Kernel, names: &mut SymbolNames) -> TokenStream {
    let arena = &kernel.arena;
    let span = names.code(arena, &[kernel.time_span.0, kernel.time_span.1], &|_| None);
    let span_statements = span.statements(quote! { self.params });
    let (t0, t1) = (&span.roots[0], &span.roots[1]);
    let initial = initial_state(kernel, names);
    let exact = if kernel.exact.is_empty() {
        TokenStream::new()
    } else {
        let roots: Vec<_> = kernel.exact.iter().map(|&(_, e)| e).collect();
        let code = names.code(arena, &roots, &|_| None);
        let statements = code.statements(quote! { self.params });
        let slots: Vec<Literal> = kernel.exact.iter().map(|&(k, _)| index(k)).collect();
        let values = &code.roots;
        let t = code.time_arg();
        quote! {
            fn exact(&self, #t: f64, out: &mut [Option<f64>]) {
                #statements
                #(out[#slots] = Some(#values);)*
            }
        }
    };
    let masses = if kernel.masses.is_empty() {
        TokenStream::new()
    } else if kernel.state_laws.is_empty() {
        let fns = &names.mass_fns;
        let slots: Vec<Literal> = (0..fns.len()).map(index).collect();
        quote! {
            fn masses(&self, t: f64, out: &mut [f64]) {
                #(out[#slots] = #fns(&self.params, t);)*
            }
        }
    } else {
        // Laws of the state: the masses at `(t, x)`.
        let values = names.mass_fns.iter().enumerate().map(|(i, f)| {
            let slot = index(i);
            if kernel.state_laws.contains(&(i as u32)) {
                quote! { out[#slot] = #f(&self.params, t, x); }
            } else {
                quote! { out[#slot] = #f(&self.params, t); }
            }
        });
        quote! {
            fn masses_at(&self, t: f64, x: &[f64], out: &mut [f64]) {
                #(#values)*
            }
        }
    };
    quote! {
        fn time_span(&self) -> (f64, f64) {
            #span_statements
            (#t0, #t1)
        }

        #initial
        #exact
        #masses
    }
}

/// `initial_state(given)`: given values (overridable) first, then those the
/// constraints fix, then the consistency stages for k ≥ 3; then the values
/// the model states for fixed components are checked against them.
fn initial_state(kernel: &Kernel, names: &mut SymbolNames) -> TokenStream {
    let arena = &kernel.arena;
    let mut statements = Vec::new();
    let mut known: HashMap<Symbol, TokenStream> = HashMap::new();
    let mut uses_time = false;
    let mut uses_given = false;
    let stated: HashMap<usize, _> = kernel.initial.stated.iter().copied().collect();
    for source in &kernel.initial.sources {
        let (symbol, value, given) = match *source {
            InitialSource::Given { index: k, value } => (kernel.state[k], value, Some(k)),
            InitialSource::Constraint { index: k, value } => (kernel.state[k], value, None),
            InitialSource::Solved { symbol, value } => (symbol, value, None),
            InitialSource::Closure => {
                if let Some(closure) = &kernel.closure {
                    statements.push(closure_newton(kernel, names, closure, &known));
                    uses_time = true;
                }
                continue;
            }
        };
        let lookup: Source = &|s| known.get(&s).cloned();
        let code = names.code(arena, &[value], lookup);
        uses_time |= code.uses_time;
        let value = code.single(quote! { self.params });
        let name = names.ident(arena, symbol);
        // A value the model states for a component its first candidate
        // fixes stands where that candidate's pivot vanishes (a pendulum
        // in `x, y` released level, `y' = -x x'/y` = 0/0); the run checks
        // it against the constraints in the mode it starts in.
        let stated_here = match *source {
            InitialSource::Constraint { index: k, .. } => stated.get(&k).copied(),
            _ => None,
        };
        if let Some(stated) = stated_here {
            let code = names.code(arena, &[stated], &|_| None);
            uses_time |= code.uses_time;
            let stated = code.single(quote! { self.params });
            statements.push(quote! {
                let #name = lagc_runtime::model::finite_or_stated(#value, #stated);
            });
            known.insert(symbol, name);
            continue;
        }
        statements.push(match given {
            Some(k) => {
                uses_given = true;
                let slot = if k == 0 {
                    quote! { given.first() }
                } else {
                    let k = index(k);
                    quote! { given.get(#k) }
                };
                quote! { let #name = #slot.copied().flatten().unwrap_or(#value); }
            }
            None => quote! { let #name = #value; },
        });
        known.insert(symbol, name);
    }
    let mut checks = Vec::new();
    for &(k, stated) in &kernel.initial.stated {
        let code = names.code(arena, &[stated], &|_| None);
        uses_time |= code.uses_time;
        let value = code.single(quote! { self.params });
        let label = arena.symbol_name(kernel.state[k]);
        let required = known
            .get(&kernel.state[k])
            .cloned()
            .unwrap_or_else(|| quote! { f64::NAN });
        checks.push(quote! {
            lagc_runtime::model::check_stated(t, #label, #value, #required)?;
        });
    }
    let values: Vec<TokenStream> = kernel
        .state
        .iter()
        .map(|s| known.get(s).cloned().unwrap_or_else(|| quote! { f64::NAN }))
        .collect();
    let t = if uses_time || !checks.is_empty() {
        quote! { let t = self.time_span().0; }
    } else {
        TokenStream::new()
    };
    let given = if uses_given {
        quote! { given }
    } else {
        quote! { _given }
    };
    quote! {
        fn initial_state(&self, #given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
            #t
            #(#statements)*
            #(#checks)*
            Ok(vec![#(#values),*])
        }
    }
}

/// Newton on the holonomic constraints from the given positions (in
/// scope by their names in `known`): the dependent ones are rebound to
/// the root.
fn closure_newton(
    kernel: &Kernel,
    names: &mut SymbolNames,
    closure: &crate::kernel::KernelClosure,
    known: &HashMap<Symbol, TokenStream>,
) -> TokenStream {
    let arena = &kernel.arena;
    let z = names.namer.fresh("closure_z");
    let f = names.namer.fresh("closure_f");
    let jac = names.namer.fresh("closure_jac");
    let unknowns: Vec<Symbol> = closure.unknowns.iter().map(|&k| kernel.state[k]).collect();
    let lookup = |s: Symbol| match unknowns.iter().position(|&u| u == s) {
        Some(i) => {
            let i = index(i);
            Some(quote! { #z[#i] })
        }
        None => known.get(&s).cloned(),
    };
    let mut roots = closure.residual.clone();
    roots.extend(closure.jacobian.iter().map(|&(_, _, e)| e));
    let code = names.code(arena, &roots, &lookup);
    let statements = code.statements(quote! { self.params });
    let m = closure.residual.len();
    let rows = (0..m).map(|r| {
        let (i, value) = (index(r), &code.roots[r]);
        quote! { #f[#i] = #value; }
    });
    let entries = closure.jacobian.iter().enumerate().map(|(e, &(r, c, _))| {
        let (r, c, value) = (index(r), index(c), &code.roots[m + e]);
        quote! { #jac[(#r, #c)] = #value; }
    });
    let starts: Vec<TokenStream> = unknowns
        .iter()
        .map(|s| known.get(s).cloned().unwrap_or_else(|| quote! { f64::NAN }))
        .collect();
    let rebound = unknowns.iter().enumerate().map(|(i, s)| {
        let name = known.get(s).cloned().unwrap_or_else(|| quote! { _unused });
        let i = index(i);
        quote! { let #name = #z[#i]; }
    });
    let text = &closure.text;
    quote! {
        let mut #z = [#(#starts),*];
        lagc_runtime::closure::initial(
            t,
            &mut #z,
            #text,
            &mut |#z: &[f64], #f: &mut [f64], #jac: &mut Matrix| {
                #statements
                #(#rows)*
                #(#entries)*
            },
        )?;
        #(#rebound)*
    }
}

/// Whether the reduced system's right side and its Jacobian (what
/// `linearize` computes) read nothing that moves with time: no `t`, no
/// mass law, no input. One mode only (a model with candidates dispatches
/// `linearize` on its mode) and an explicit motion; anything else is
/// reported as not autonomous, which costs only speed
/// (the runtime's `Model::AUTONOMOUS`).
fn autonomous(kernel: &Kernel) -> bool {
    let crate::kernel::Motion::Explicit(e) = &kernel.motion else {
        return false;
    };
    if !kernel.modes.is_empty() {
        return false;
    }
    let arena = &kernel.arena;
    let roots = e.rhs.iter().chain(e.jacobian.iter().map(|(_, _, d)| d));
    roots.into_iter().all(|&r| {
        arena
            .free_symbols(r)
            .iter()
            .all(|s| matches!(s, Symbol::Param(_) | Symbol::Jet { .. }))
    })
}

/// The consts of the trait impl.
pub fn consts(kernel: &Kernel, model_name: &str, source_hash: &str) -> TokenStream {
    let arena = &kernel.arena;
    let params: Vec<&str> = kernel.params.iter().map(|p| p.name.as_str()).collect();
    let state: Vec<String> = kernel.state.iter().map(|&s| arena.symbol_name(s)).collect();
    let coordinates = index(kernel.coordinates);
    let initial: Vec<TokenStream> = kernel
        .initial
        .kinds
        .iter()
        .map(|k| match k {
            InitialKind::Given => quote! { lagc_runtime::model::Initial::Given },
            InitialKind::Constraint => quote! { lagc_runtime::model::Initial::Constraint },
            InitialKind::Solved => quote! { lagc_runtime::model::Initial::Solved },
        })
        .collect();
    let masses: Vec<&str> = kernel.masses.iter().map(|(n, _)| n.as_str()).collect();
    let masses = if masses.is_empty() {
        TokenStream::new()
    } else {
        quote! { const MASSES: &'static [&'static str] = &[#(#masses),*]; }
    };
    let integrator = match kernel.integrator {
        None => TokenStream::new(),
        Some(choice) => {
            // The runtime's variant of the same type, by its name.
            let variant =
                proc_macro2::Ident::new(&format!("{choice:?}"), proc_macro2::Span::call_site());
            quote! {
                const DECLARED_INTEGRATOR: Option<lagc_runtime::method::IntegratorChoice> =
                    Some(lagc_runtime::method::IntegratorChoice::#variant);
            }
        }
    };
    let affine = match &kernel.coefficients {
        Some(c) => {
            let linear = c.linear;
            let autonomous = if autonomous(kernel) {
                quote! { const AUTONOMOUS: bool = true; }
            } else {
                TokenStream::new()
            };
            quote! {
                const AFFINE: bool = true;
                const COEFFICIENTS_LINEAR: bool = #linear;
                #autonomous
            }
        }
        None => TokenStream::new(),
    };
    let exact = if kernel.exact.is_empty() {
        TokenStream::new()
    } else {
        quote! { const EXACT: bool = true; }
    };
    let kept = if kernel.kept.is_empty() {
        TokenStream::new()
    } else {
        quote! { const KEEPS_CONSTRAINTS: bool = true; }
    };
    let keeps = if kernel.closure.is_some() {
        quote! { const KEEPS_POSITIONS: bool = true; }
    } else {
        TokenStream::new()
    };
    // Which components each mode fixes: with groups of constraints solved
    // together (or holonomic ones), a mode's are not found from the first
    // mode's by the candidates' names.
    let modes = std::iter::once(kernel).chain(&kernel.modes);
    // A single mode states its table only when its fixed components are
    // not those the initial values take from the constraints (a raised
    // constraint's candidate is given, and kept).
    let from_initial: Vec<usize> = kernel
        .initial
        .kinds
        .iter()
        .enumerate()
        .filter(|(_, k)| matches!(k, crate::kernel::InitialKind::Constraint))
        .map(|(i, _)| i)
        .collect();
    let single_as_initial = kernel.modes.is_empty()
        && kernel.kept.iter().map(|&(i, _)| i).collect::<Vec<_>>() == from_initial;
    let fixed = if single_as_initial || modes.clone().all(|k| k.kept.is_empty()) {
        TokenStream::new()
    } else {
        let tables = modes.map(|k| {
            let indices = k.kept.iter().map(|&(i, _)| index(i));
            quote! { &[#(#indices),*] }
        });
        quote! { const FIXED: &'static [&'static [usize]] = &[#(#tables),*]; }
    };
    quote! {
        const NAME: &'static str = #model_name;
        const SOURCE_HASH: &'static str = #source_hash;
        const PARAMS: &'static [&'static str] = &[#(#params),*];
        const STATE: &'static [&'static str] = &[#(#state),*];
        const COORDINATES: usize = #coordinates;
        const INITIAL: &'static [lagc_runtime::model::Initial] = &[#(#initial),*];
        #masses
        #integrator
        #affine
        #exact
        #kept
        #keeps
        #fixed
    }
}
