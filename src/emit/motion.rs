//! The reduced system (7) as trait items: `rhs`, `jacobian`,
//! `time_partial`, `linearize` and `mass_matrix`, printed from
//! the kernel (no calculus here).
//!
//! Explicit systems print their expressions; `linearize` prints `X` and
//! `∂X/∂x` as one block so they share their subexpressions. Implicit ones
//! solve `G(t, x, z) = 0` for the highest derivatives — one solve of the
//! mass matrix on the stack when `G` is affine in `z`, Newton otherwise —
//! and get `∂z/∂x = −G_z⁻¹ G_x` by implicit differentiation at run time;
//! affine ones print `jacobian` and `linearize` as one body that evaluates
//! the mass system once and factors it on the stack.

use super::bodies::{self, arg, index};
use super::names::{Source, SymbolNames};
use crate::ir::{ExprId, Symbol};
use crate::kernel::{Explicit, Implicit, Kernel, Motion};
use proc_macro2::{Literal, TokenStream};
use quote::{quote, ToTokens};
use std::collections::HashMap;

/// `(items of the trait impl, items of the inherent impl)`.
pub fn motion_code(kernel: &Kernel, names: &mut SymbolNames) -> (TokenStream, TokenStream) {
    let position: HashMap<Symbol, usize> = kernel
        .state
        .iter()
        .enumerate()
        .map(|(i, &s)| (s, i))
        .collect();
    let from_x = move |s: Symbol| {
        position.get(&s).map(|&i| {
            let i = index(i);
            quote! { x[#i] }
        })
    };
    // A second right side over lanes for the models that can run a
    // non-affine ensemble (one mode, no switches, not affine).
    let lanes = kernel.modes.is_empty()
        && kernel.coefficients.is_none()
        && kernel.switches.functions.is_empty();
    let (trait_items, inherent) = motion_of(kernel, names, &from_x, lanes);
    let condition = mass_condition(kernel, names, &from_x);
    let events = super::events::items(kernel, names, &from_x);
    // The same in every mode: one trait item.
    let closure = closure_kept(kernel, names);
    let events = quote! { #events #closure };
    if kernel.modes.is_empty() {
        let params = super::sensitivity::param_jacobian_code(kernel, names, &from_x);
        return (quote! { #trait_items #condition #events #params }, inherent);
    }
    // Several modes: each mode's motion as inherent methods `…_modeM`,
    // the trait's methods dispatching on the current mode. `∂X/∂p` too,
    // when every mode has it (the sensitivities follow the run's changes
    // of candidates: the state is the same in every mode).
    let mut modes = vec![(
        trait_items,
        inherent,
        super::sensitivity::param_jacobian_method(kernel, names, &from_x),
    )];
    for mode in &kernel.modes {
        let mut mode_names = SymbolNames::new(&mode.arena, &mode.state);
        mode_names.branches = super::modes::shared_branches(kernel, mode);
        let (items, helpers) = motion_of(mode, &mut mode_names, &from_x, false);
        let params = super::sensitivity::param_jacobian_method(mode, &mut mode_names, &from_x);
        modes.push((items, helpers, params));
    }
    let every_mode_params = modes.iter().all(|(_, _, p)| p.is_some());
    let mut all_inherent = TokenStream::new();
    let mut first_items = TokenStream::new();
    for (m, (items, helpers, params)) in modes.into_iter().enumerate() {
        let items = match params {
            Some(params) if every_mode_params => quote! { #items #params },
            _ => items,
        };
        all_inherent.extend(super::modes::renamed(&items, &helpers, m));
        if m == 0 {
            first_items = items;
        }
    }
    let mut dispatch = super::modes::dispatch(&first_items, kernel.modes.len() + 1);
    if every_mode_params {
        dispatch.extend(quote! { const PARAM_JACOBIAN: bool = true; });
    }
    // The mass matrix is the current mode's too (mode 0's alone named
    // `mass_system`, which the modes rename: rustc E0599).
    let mut conditions = vec![condition];
    for mode in &kernel.modes {
        let mut mode_names = SymbolNames::new(&mode.arena, &mode.state);
        mode_names.branches = super::modes::shared_branches(kernel, mode);
        conditions.push(mass_condition(mode, &mut mode_names, &from_x));
    }
    let (condition, condition_inherent) = super::modes::mass_dispatch(&conditions);
    all_inherent.extend(condition_inherent);
    (quote! { #dispatch #condition #events }, all_inherent)
}

/// The motion's items: `(trait items, inherent helpers)`.
fn motion_of(
    kernel: &Kernel,
    names: &mut SymbolNames,
    from_x: Source,
    lanes: bool,
) -> (TokenStream, TokenStream) {
    let n = kernel.state.len();
    let c = kernel.coordinates;
    let shifted = n.saturating_sub(c);
    let shift_rows: Vec<Literal> = (0..shifted).map(index).collect();
    let shift_cols: Vec<Literal> = (0..shifted).map(|i| index(i + c)).collect();
    let shifts = quote! { #(dx[#shift_rows] = x[#shift_cols];)* };
    let shift_jacobian = quote! { #(jac[(#shift_rows, #shift_cols)] = 1.0;)* };
    let kept = kept_code(kernel, names, from_x);
    let (items, helpers) = match &kernel.motion {
        Motion::Explicit(e) => (
            explicit(kernel, names, e, from_x, &shifts, &shift_jacobian, lanes),
            TokenStream::new(),
        ),
        Motion::Implicit(i) => implicit(kernel, names, i, from_x, &shifts, &shift_jacobian),
    };
    (quote! { #items #kept }, helpers)
}

/// `constrained`: the values the constraints require of the components
/// they fix (nothing for a model without first-order constraints).
fn kept_code(kernel: &Kernel, names: &mut SymbolNames, from_x: Source) -> TokenStream {
    if kernel.kept.is_empty() {
        return TokenStream::new();
    }
    let body = bodies::body(names, &kernel.arena, &kernel.kept, from_x, "x", "kept");
    let (t, x, statements, rows) = (&body.t, &body.source, &body.statements, &body.assignments);
    let gradient = bodies::body(
        names,
        &kernel.arena,
        &kernel.kept_gradient,
        from_x,
        "x",
        "jac",
    );
    let (g_t, g_x, g_out, g_statements, g_cells) = (
        &gradient.t,
        &gradient.source,
        &gradient.out,
        &gradient.statements,
        &gradient.assignments,
    );
    quote! {
        fn constrained(&self, #t: f64, #x: &[f64], kept: &mut [f64]) -> Result<(), Failure> {
            #statements
            #(#rows)*
            Ok(())
        }

        fn kept_gradient(&self, #g_t: f64, #g_x: &[f64], #g_out: &mut Matrix) -> Result<(), Failure> {
            #g_statements
            #(#g_cells)*
            Ok(())
        }
    }
}

/// `project_closure` of a model with holonomic constraints (SPEC §2.3):
/// the state projected onto them along their normals — Gauss–Newton on
/// `f(t, q) = 0` with the smallest correction of the positions, then each
/// derivative `q^(r)` onto `D^r f = 0` (linear in it, the same normals) —
/// in place, or partitioned by the dependents the runtime's keeper passes
/// (`closure::project` does either). The same code in every mode; the
/// keeper then keeps the velocities the mode's constraints fix
/// (`constrained`).
fn closure_kept(kernel: &Kernel, names: &mut SymbolNames) -> TokenStream {
    let Some(closure) = &kernel.closure else {
        return TokenStream::new();
    };
    let arena = &kernel.arena;
    let state = names.namer.fresh("closure_x");
    let level = names.namer.fresh("closure_level");
    let f = names.namer.fresh("closure_f");
    let normals = names.namer.fresh("closure_normals");
    let partition = names.namer.fresh("closure_partition");
    let position: HashMap<Symbol, usize> = kernel
        .state
        .iter()
        .enumerate()
        .map(|(i, &s)| (s, i))
        .collect();
    let lookup = |s: Symbol| {
        position.get(&s).map(|&i| {
            let i = index(i);
            quote! { #state[#i] }
        })
    };
    let m = closure.residual.len();
    let mut roots = closure.residual.clone();
    roots.extend(closure.normals.iter().map(|&(_, _, e)| e));
    let code = names.code(arena, &roots, &lookup);
    let statements = code.statements(quote! { self.params });
    let rows = (0..m).map(|r| {
        let (i, value) = (index(r), &code.roots[r]);
        quote! { #f[#i] = #value; }
    });
    let entries = closure.normals.iter().enumerate().map(|(e, &(r, c, _))| {
        let (r, c, value) = (index(r), index(c), &code.roots[m + e]);
        quote! { #normals[(#r, #c)] = #value; }
    });
    let mut arms = vec![quote! {
        0 => {
            #statements
            #(#rows)*
            #(#entries)*
        }
    }];
    for (r, residuals) in closure.levels.iter().enumerate() {
        let code = names.code(arena, residuals, &lookup);
        let statements = code.statements(quote! { self.params });
        let rows = code.roots.iter().enumerate().map(|(i, value)| {
            let i = index(i);
            quote! { #f[#i] = #value; }
        });
        let pattern = if r + 1 == closure.levels.len() {
            quote! { _ }
        } else {
            let r = index(r + 1);
            quote! { #r }
        };
        arms.push(quote! { #pattern => { #statements #(#rows)* } });
    }
    let text = &closure.text;
    let coordinates = index(kernel.coordinates);
    let levels = index(closure.levels.len());
    let rows = index(m);
    quote! {
        fn project_closure(
            &self,
            t: f64,
            x: &mut [f64],
            #partition: Option<lagc_runtime::closure::Dependents>,
        ) -> Result<(), Failure> {
            lagc_runtime::closure::project(
                t,
                x,
                #partition,
                (#rows, #coordinates, #levels),
                #text,
                &mut |#state: &[f64], #level: usize, #f: &mut [f64], #normals: &mut Matrix| {
                    match #level {
                        #(#arms)*
                    }
                },
            )
        }
    }
}

fn explicit(
    kernel: &Kernel,
    names: &mut SymbolNames,
    e: &Explicit,
    from_x: Source,
    shifts: &TokenStream,
    shift_jacobian: &TokenStream,
    lanes: bool,
) -> TokenStream {
    let arena = &kernel.arena;
    let rows: Vec<usize> = (0..e.rhs.len())
        .map(|j| kernel.highest_row(j as u32))
        .collect();
    let rates: Vec<(usize, ExprId)> = rows.iter().copied().zip(e.rhs.iter().copied()).collect();
    let rhs = bodies::body(names, arena, &rates, from_x, "x", "dx");
    let (rhs_t, rhs_statements, rhs_rows) = (&rhs.t, &rhs.statements, &rhs.assignments);
    let jac = bodies::body(names, arena, &e.jacobian, from_x, "x", "jac");
    let (jac_t, jac_x, jac_statements, jac_cells) =
        (&jac.t, &jac.source, &jac.statements, &jac.assignments);
    let tp = bodies::body(names, arena, &e.time_partial, from_x, "x", "dxdt");
    let (tp_t, tp_x, tp_out, tp_statements, tp_rows) =
        (&tp.t, &tp.source, &tp.out, &tp.statements, &tp.assignments);
    let rows: Vec<Literal> = rows.into_iter().map(index).collect();
    let jac_roots: Vec<ExprId> = e.jacobian.iter().map(|&(_, _, d)| d).collect();

    // X and ∂X/∂x together: one block, shared subexpressions computed once.
    let mut both = e.rhs.clone();
    both.extend(&jac_roots);
    let lin = names.code(arena, &both, from_x);
    let lin_statements = lin.statements(quote! { self.params });
    let (lin_rhs, lin_jac) = lin.roots.split_at(e.rhs.len());
    let lin_cells = bodies::assignments(&quote! { jac }, &e.jacobian, lin_jac);
    let lin_t = lin.time_arg();
    let rhs_lanes = if lanes && !selects(arena, &e.rhs) {
        rhs_over_lanes(&rhs, &rows, shifts)
    } else {
        TokenStream::new()
    };
    quote! {
        #rhs_lanes

        fn rhs(&self, #rhs_t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
            #rhs_statements
            #shifts
            #(#rhs_rows)*
            Ok(())
        }

        fn jacobian(&self, #jac_t: f64, #jac_x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
            #shift_jacobian
            #jac_statements
            #(#jac_cells)*
            Ok(())
        }

        fn time_partial(&self, #tp_t: f64, #tp_x: &[f64], #tp_out: &mut [f64]) -> Result<(), Failure> {
            #tp_statements
            #(#tp_rows)*
            Ok(())
        }

        fn linearize(&self, #lin_t: f64, x: &[f64], dx: &mut [f64], jac: &mut Matrix) -> Result<(), Failure> {
            #lin_statements
            #shifts
            #(dx[#rows] = #lin_rhs;)*
            #shift_jacobian
            #(#lin_cells)*
            Ok(())
        }
    }
}

/// Whether `roots` need what the lane type does not print: a `Select`
/// (an `if` over the state), or a power with an exponent that is not a
/// number (`f64::powf` of a lane value would not type-check when the
/// base is a param).
fn selects(arena: &crate::ir::Arena, roots: &[ExprId]) -> bool {
    arena
        .reachable(roots)
        .into_iter()
        .any(|e| match arena.node(e) {
            crate::ir::Node::Select(..) => true,
            crate::ir::Node::Pow(_, x) => arena.as_const(*x).is_none(),
            _ => false,
        })
}

/// `rhs_lanes`: the right side's body printed again with the state and
/// its temporaries as lanes (`lagc_runtime::lanes::Lanes`: each operation
/// the `f64` one lane by lane, so each lane is bit for bit `rhs`), a row
/// that reads no state splatted.
fn rhs_over_lanes(rhs: &bodies::Body, rows: &[Literal], shifts: &TokenStream) -> TokenStream {
    let (t, statements) = (&rhs.t, &rhs.statements);
    let values = &rhs.values;
    quote! {
        const LANES: bool = true;

        fn rhs_lanes(
            &self,
            #t: f64,
            x: &[lagc_runtime::lanes::Lanes],
            dx: &mut [lagc_runtime::lanes::Lanes],
        ) -> Result<(), Failure> {
            #statements
            #shifts
            #(dx[#rows] = lagc_runtime::lanes::lanes(#values);)*
            Ok(())
        }
    }
}

/// An implicit system's source of values: its unknown highest derivatives
/// as `z[k]`, every other symbol as `from_x` gives it.
pub(super) fn from_unknowns<'a>(
    unknowns: &[Symbol],
    from_x: Source<'a>,
) -> impl Fn(Symbol) -> Option<TokenStream> + 'a {
    let unknown_at: HashMap<Symbol, usize> =
        unknowns.iter().enumerate().map(|(k, &s)| (s, k)).collect();
    move |s: Symbol| {
        unknown_at
            .get(&s)
            .map(|&k| {
                let k = index(k);
                quote! { z[#k] }
            })
            .or_else(|| from_x(s))
    }
}

fn implicit(
    kernel: &Kernel,
    names: &mut SymbolNames,
    i: &Implicit,
    from_x: Source,
    shifts: &TokenStream,
    shift_jacobian: &TokenStream,
) -> (TokenStream, TokenStream) {
    let arena = &kernel.arena;
    let m = i.unknowns.len();
    let n = kernel.state.len();
    let size = index(m);
    let from_xz = from_unknowns(&i.unknowns, from_x);
    let g_z_cells = |target: TokenStream, values: &[TokenStream]| -> Vec<TokenStream> {
        i.g_z
            .iter()
            .zip(values)
            .map(|(&(r, c, _), v)| {
                let (r, c) = (index(r), index(c));
                quote! { #target[#r][#c] = #v; }
            })
            .collect()
    };
    // Solving for z: the stack path for the right side, the factored path
    // for the Jacobians.
    let (solve, factored) = if i.linear {
        let mut roots = i.free.clone();
        roots.extend(i.g_z.iter().map(|&(_, _, e)| e));
        let code = names.code(arena, &roots, from_x);
        let statements = code.statements(quote! { self.params });
        let (free, cells) = code.roots.split_at(i.free.len());
        let cells = g_z_cells(quote! { a }, cells);
        let t = code.time_arg();
        let x = arg(code.uses_source, "x");
        let solver = if i.symmetric {
            quote! { lagc_runtime::highest::solve_symmetric_fixed_checked }
        } else {
            quote! { lagc_runtime::highest::solve_fixed_checked }
        };
        (
            quote! {
                /// The mass matrix of the highest derivatives and the
                /// equations' free part: `a z + g = 0`.
                fn mass_system(&self, #t: f64, #x: &[f64]) -> ([[f64; #size]; #size], [f64; #size]) {
                    #statements
                    let mut a = [[0.0; #size]; #size];
                    #(#cells)*
                    (a, [#(#free),*])
                }

                /// The independent highest derivatives: one solve on the stack.
                fn highest(&self, t: f64, x: &[f64]) -> Result<[f64; #size], Failure> {
                    let (a, g) = self.mass_system(t, x);
                    #solver(t, a, g)
                }

                /// The highest derivatives with the factors of the mass matrix.
                fn highest_factored(&self, t: f64, x: &[f64]) -> Result<(Vec<f64>, Lu), Failure> {
                    let (a, g) = self.mass_system(t, x);
                    lagc_runtime::highest::solve_linear(t, Matrix::from_array(&a), &g)
                }

            },
            quote! { self.highest_factored(t, x)? },
        )
    } else {
        let mut roots = i.residual.clone();
        roots.extend(i.g_z.iter().map(|&(_, _, e)| e));
        let code = names.code(arena, &roots, &from_xz);
        let statements = code.statements(quote! { self.params });
        let (residual, cells) = code.roots.split_at(i.residual.len());
        let cells = bodies::assignments(&quote! { g_z }, &i.g_z, cells);
        let rows: Vec<Literal> = (0..residual.len()).map(index).collect();
        let t = code.time_arg();
        let uses_state = roots
            .iter()
            .any(|&r| kernel.state.iter().any(|&s| arena.depends_on(r, s)));
        let x = arg(uses_state, "x");
        (
            quote! {
                /// The residual `G(t, x, z)` of the highest derivatives and
                /// `∂G/∂z` (zeroed by the caller).
                fn residual(&self, #t: f64, #x: &[f64], z: &[f64], g: &mut [f64], g_z: &mut Matrix) -> Result<(), Failure> {
                    #statements
                    #(g[#rows] = #residual;)*
                    #(#cells)*
                    Ok(())
                }

                /// The independent highest derivatives by Newton's method
                /// (they enter the equations non-linearly), with the
                /// factors of `∂G/∂z` at the root.
                fn highest_factored(&self, t: f64, x: &[f64]) -> Result<(Vec<f64>, Lu), Failure> {
                    lagc_runtime::highest::newton(t, vec![0.0; #size], |z, g, g_z| {
                        self.residual(t, x, z, g, g_z)
                    })
                }

                fn highest(&self, t: f64, x: &[f64]) -> Result<Vec<f64>, Failure> {
                    Ok(self.highest_factored(t, x)?.0)
                }
            },
            quote! { self.highest_factored(t, x)? },
        )
    };
    // The dependent highest derivatives D(t, x, z), their partials.
    let dep_roots: Vec<ExprId> = i.dependent.iter().map(|d| d.value).collect();
    let dep = names.code(arena, &dep_roots, &from_xz);
    let dep_statements = dep.statements(quote! { self.params });
    let dep_values = &dep.roots;
    let dep_rows: Vec<Literal> = i
        .dependent
        .iter()
        .map(|d| index(kernel.highest_row(d.coord)))
        .collect();
    let (ind_rows, ind_k): (Vec<Literal>, Vec<Literal>) = i
        .unknowns
        .iter()
        .enumerate()
        .filter_map(|(k, s)| match s {
            Symbol::Jet { coord, .. } => Some((index(kernel.highest_row(*coord)), index(k))),
            _ => None,
        })
        .unzip();
    let z_binding = quote! { let z = self.highest(t, x)?; };
    let uses_unknowns = |roots: &[ExprId]| {
        roots
            .iter()
            .any(|&r| i.unknowns.iter().any(|&u| arena.depends_on(r, u)))
    };

    // ∂G/∂x (with z), then ∂z/∂x; the dependent rows' total derivatives.
    let gx_roots: Vec<ExprId> = i.g_x.iter().map(|&(_, _, e)| e).collect();
    let mut d_roots = Vec::new();
    for d in &i.dependent {
        d_roots.extend(d.d_x.iter().map(|&(_, e)| e));
        d_roots.extend(d.d_z.iter().map(|&(_, e)| e));
    }
    let mut jac_roots = gx_roots.clone();
    jac_roots.extend(&d_roots);
    let jac = names.code(arena, &jac_roots, &from_xz);
    let jac_statements = jac.statements(quote! { self.params });
    let n_lit = index(n);
    let (gx_cells, dep_jac) = jacobian_cells(kernel, i, &jac.roots, false);
    // ∂G/∂t, then ∂z/∂t; the dependent rows'.
    let mut tp_roots: Vec<ExprId> = i.g_t.iter().map(|&(_, e)| e).collect();
    let mut dep_t_roots = Vec::new();
    for d in &i.dependent {
        dep_t_roots.push(d.d_t);
        dep_t_roots.extend(d.d_z.iter().map(|&(_, e)| e));
    }
    let g_t_count = tp_roots.len();
    tp_roots.extend(&dep_t_roots);
    let tp = names.code(arena, &tp_roots, &from_xz);
    let tp_statements = tp.statements(quote! { self.params });
    let (g_t_values, dep_t_values) = tp.roots.split_at(g_t_count);
    let g_t_rows: Vec<Literal> = i.g_t.iter().map(|&(r, _)| index(r)).collect();
    let mut dep_tp = Vec::new();
    let mut at = 0;
    for d in &i.dependent {
        let row = index(kernel.highest_row(d.coord));
        let d_t = dep_t_values[at].clone();
        at += 1;
        let mut d_z = vec![quote! { 0.0 }; m];
        for &(k, _) in &d.d_z {
            d_z[k] = dep_t_values[at].clone();
            at += 1;
        }
        dep_tp.push(quote! {
            {
                let d_z: [f64; #size] = [#(#d_z),*];
                dxdt[#row] = #d_t + (0..#size).map(|k| d_z[k] * g_t[(k, 0)]).sum::<f64>();
            }
        });
    }
    let ind_rows_t = ind_rows.clone();
    let ind_k_t = ind_k.clone();
    let jac_z = arg(uses_unknowns(&jac_roots), "z");
    let tp_z = arg(uses_unknowns(&tp_roots), "z");
    let jacobian_item = if i.linear {
        // `linearized`'s, without the right side.
        quote! {
            fn jacobian(&self, t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
                self.linearized(t, x, None, jac)
            }
        }
    } else {
        quote! {
            fn jacobian(&self, t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
                let (#jac_z, lu) = #factored;
                #jac_statements
                let mut g_x = Matrix::zeros(#size, #n_lit);
                #(#gx_cells)*
                lagc_runtime::highest::implicit_derivatives(&lu, &mut g_x);
                #shift_jacobian
                for c in 0..#n_lit {
                    #(jac[(#ind_rows_t, c)] = g_x[(#ind_k_t, c)];)*
                }
                #(#dep_jac)*
                Ok(())
            }
        }
    };
    let trait_items = quote! {
        fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
            #z_binding
            #dep_statements
            #shifts
            #(dx[#ind_rows] = z[#ind_k];)*
            #(dx[#dep_rows] = #dep_values;)*
            Ok(())
        }

        #jacobian_item

        fn time_partial(&self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), Failure> {
            let (#tp_z, lu) = #factored;
            #tp_statements
            let mut g_t = Matrix::zeros(#size, 1);
            #(g_t[(#g_t_rows, 0)] = #g_t_values;)*
            lagc_runtime::highest::implicit_derivatives(&lu, &mut g_t);
            #(dxdt[#ind_rows] = g_t[(#ind_k, 0)];)*
            #(#dep_tp)*
            Ok(())
        }
    };
    let (linearize, linearized) = if i.linear {
        let ind = (&ind_rows[..], &ind_k[..]);
        let dep = (
            &dep_statements,
            &dep_rows[..],
            &dep_values[..],
            dep.uses_source,
        );
        let helper = linearize_linear(
            kernel,
            names,
            i,
            from_x,
            &jac_roots,
            ind,
            dep,
            shifts,
            shift_jacobian,
        );
        let item = quote! {
            fn linearize(&self, t: f64, x: &[f64], dx: &mut [f64], jac: &mut Matrix) -> Result<(), Failure> {
                self.linearized(t, x, Some(dx), jac)
            }
        };
        (item, helper)
    } else {
        // Newton's: the trait's default, printed so that every kind of
        // motion defines it (the modes dispatch on the first mode's items).
        let item = quote! {
            fn linearize(&self, t: f64, x: &[f64], dx: &mut [f64], jac: &mut Matrix) -> Result<(), Failure> {
                self.rhs(t, x, dx)?;
                self.jacobian(t, x, jac)
            }
        };
        (item, TokenStream::new())
    };
    let inherent = quote! { #solve #linearized };
    (quote! { #trait_items #linearize }, inherent)
}

/// `g_x[(r, c)] = …;` for each cell of `∂G/∂x`, and the dependent rows'
/// Jacobian blocks, from the printed values of the roots `∂G/∂x`'s cells,
/// then each dependent row's `d_x` and `d_z` (in [`implicit`]'s order).
/// `columns`: `g_x` is an array of columns on the stack, `g_x[c][r]`.
fn jacobian_cells(
    kernel: &Kernel,
    i: &Implicit,
    values: &[TokenStream],
    columns: bool,
) -> (Vec<TokenStream>, Vec<TokenStream>) {
    let cell = |r: TokenStream, c: TokenStream| {
        if columns {
            quote! { g_x[#c][#r] }
        } else {
            quote! { g_x[(#r, #c)] }
        }
    };
    let (n, m) = (kernel.state.len(), i.unknowns.len());
    let (n_lit, size) = (index(n), index(m));
    let (gx_values, d_values) = values.split_at(i.g_x.len().min(values.len()));
    let gx_cells: Vec<TokenStream> = i
        .g_x
        .iter()
        .zip(gx_values)
        .map(|(&(r, c, _), v)| {
            let g_x = cell(index(r).into_token_stream(), index(c).into_token_stream());
            quote! { #g_x = #v; }
        })
        .collect();
    let g_x_kc = cell(quote! { k }, quote! { c });
    let mut dep_jac = Vec::new();
    let mut values = d_values.iter();
    let mut next = || {
        values
            .next()
            .cloned()
            .unwrap_or_else(|| quote! { f64::NAN })
    };
    for d in &i.dependent {
        let row = index(kernel.highest_row(d.coord));
        let mut d_x = vec![quote! { 0.0 }; n];
        for &(c, _) in &d.d_x {
            d_x[c] = next();
        }
        let mut d_z = vec![quote! { 0.0 }; m];
        for &(k, _) in &d.d_z {
            d_z[k] = next();
        }
        dep_jac.push(quote! {
            {
                let d_x: [f64; #n_lit] = [#(#d_x),*];
                let d_z: [f64; #size] = [#(#d_z),*];
                for c in 0..#n_lit {
                    jac[(#row, c)] = d_x[c] + (0..#size).map(|k| d_z[k] * #g_x_kc).sum::<f64>();
                }
            }
        });
    }
    (gx_cells, dep_jac)
}

/// `linearized`, the `jacobian` of a motion affine in its highest
/// derivatives and with `dx` its `linearize`: what `rhs` then the heap
/// path's `jacobian` compute, with the same operations in the same order
/// (bit for bit), but the mass system evaluated once and its common
/// subexpressions with `∂G/∂x` and the dependent rows' partials computed
/// once (the field linearises the motion at every stage). The right side
/// takes its solve on the stack (`rhs`'s `highest`), the Jacobian the
/// factored one, on the stack too (`highest::fixed`: `Lu`'s bits without
/// allocating), from the same matrix. One body for both methods: the
/// generated crate holds `∂G/∂x`'s code once.
#[allow(clippy::too_many_arguments)]
fn linearize_linear(
    kernel: &Kernel,
    names: &mut SymbolNames,
    i: &Implicit,
    from_x: Source,
    jac_roots: &[ExprId],
    (ind_rows, ind_k): (&[Literal], &[Literal]),
    (dep_statements, dep_rows, dep_values, dep_reads_x): (
        &TokenStream,
        &[Literal],
        &[TokenStream],
        bool,
    ),
    shifts: &TokenStream,
    shift_jacobian: &TokenStream,
) -> TokenStream {
    let arena = &kernel.arena;
    let (m, n) = (i.unknowns.len(), kernel.state.len());
    let (size, n_lit) = (index(m), index(n));
    let from_xz = from_unknowns(&i.unknowns, from_x);
    let mut roots = i.free.clone();
    roots.extend(i.g_z.iter().map(|&(_, _, e)| e));
    let split = roots.len();
    roots.extend(jac_roots);
    let (code, at) = names.code_split(arena, &roots, split, &from_xz);
    let (mass_statements, jac_statements) = code.split_statements(quote! { self.params }, at);
    let (mass, jac_values) = code.roots.split_at(split);
    let (free, cells) = mass.split_at(i.free.len());
    let cells: Vec<TokenStream> = i
        .g_z
        .iter()
        .zip(cells)
        .map(|(&(r, c, _), v)| {
            let (r, c) = (index(r), index(c));
            quote! { a[#r][#c] = #v; }
        })
        .collect();
    let (gx_cells, dep_jac) = jacobian_cells(kernel, i, jac_values, true);
    let solver = if i.symmetric {
        quote! { lagc_runtime::highest::solve_symmetric_fixed_checked }
    } else {
        quote! { lagc_runtime::highest::solve_fixed_checked }
    };
    let uses_z = jac_roots
        .iter()
        .any(|&r| i.unknowns.iter().any(|&u| arena.depends_on(r, u)));
    let z = arg(uses_z, "z");
    let x = arg(code.uses_source || dep_reads_x || !shifts.is_empty(), "x");
    quote! {
        /// `jacobian`, and with `dx` the right side (`linearize`).
        fn linearized(&self, t: f64, #x: &[f64], dx: Option<&mut [f64]>, jac: &mut Matrix) -> Result<(), Failure> {
            #mass_statements
            let mut a = [[0.0; #size]; #size];
            #(#cells)*
            let g = [#(#free),*];
            if let Some(dx) = dx {
                let z = #solver(t, a, g)?;
                #dep_statements
                #shifts
                #(dx[#ind_rows] = z[#ind_k];)*
                #(dx[#dep_rows] = #dep_values;)*
            }
            let (#z, lu) = lagc_runtime::highest::solve_linear_fixed(t, &a, &g)?;
            #jac_statements
            let mut g_x = [[0.0_f64; #size]; #n_lit];
            #(#gx_cells)*
            lu.implicit_derivatives(&mut g_x);
            #shift_jacobian
            for c in 0..#n_lit {
                #(jac[(#ind_rows, c)] = g_x[c][#ind_k];)*
            }
            #(#dep_jac)*
            Ok(())
        }
    }
}

/// `mass_matrix`, for diagnosing a failure: the mass matrix is
/// evaluated only then.
fn mass_condition(kernel: &Kernel, names: &mut SymbolNames, from_x: Source) -> TokenStream {
    match &kernel.motion {
        Motion::Implicit(i) if i.linear => quote! {
            fn mass_matrix(&self, t: f64, x: &[f64]) -> Option<Matrix> {
                Some(Matrix::from_array(&self.mass_system(t, x).0))
            }
        },
        Motion::Explicit(_) if !kernel.mass_matrix.is_empty() => {
            let arena = &kernel.arena;
            // Solved symbolically: the matrix does not hold the unknowns.
            let cells: Vec<(usize, usize, ExprId)> = kernel
                .mass_matrix
                .iter()
                .enumerate()
                .flat_map(|(r, row)| row.iter().enumerate().map(move |(c, &e)| (r, c, e)))
                .collect();
            let roots: Vec<ExprId> = cells.iter().map(|&(_, _, e)| e).collect();
            let code = names.code(arena, &roots, from_x);
            let statements = code.statements(quote! { self.params });
            let size = index(kernel.mass_matrix.len());
            let assigns: Vec<TokenStream> = cells
                .iter()
                .zip(&code.roots)
                .map(|(&(r, c, _), v)| {
                    let (r, c) = (index(r), index(c));
                    quote! { m[(#r, #c)] = #v; }
                })
                .collect();
            let t = code.time_arg();
            let x = arg(code.uses_source, "x");
            quote! {
                fn mass_matrix(&self, #t: f64, #x: &[f64]) -> Option<Matrix> {
                    #statements
                    let mut m = Matrix::zeros(#size, #size);
                    #(#assigns)*
                    Some(m)
                }
            }
        }
        _ => TokenStream::new(),
    }
}
