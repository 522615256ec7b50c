//! `param_jacobian`: `∂X/∂p` of the reduced system (7), printed from the
//! kernel's [`crate::kernel::ParamPartials`] for the forward sensitivities.
//! An implicit system's independent highest derivatives move with the
//! params by implicit differentiation at run time, `∂z/∂p = −G_z⁻¹ G_p`, as
//! its `∂z/∂x` does (`motion.rs`).

use super::bodies::{self, index};
use super::names::{Source, SymbolNames};
use crate::ir::{ExprId, Symbol};
use crate::kernel::{Kernel, Motion};
use proc_macro2::{Literal, TokenStream};
use quote::quote;

/// The `PARAM_JACOBIAN` const and `param_jacobian` of a model of one mode
/// (nothing for a model without the partials: sensitivities are then not
/// available, and the runtime says so).
pub fn param_jacobian_code(
    kernel: &Kernel,
    names: &mut SymbolNames,
    from_x: Source,
) -> TokenStream {
    match param_jacobian_method(kernel, names, from_x) {
        Some(method) => quote! {
            const PARAM_JACOBIAN: bool = true;
            #method
        },
        None => TokenStream::new(),
    }
}

/// `fn param_jacobian` of one mode's motion (`kernel` itself, its `modes`
/// not read: a model of several modes prints each mode's, renamed, and
/// dispatches on the mode as for `jacobian`, `emit/motion.rs`); `None`
/// without the partials or without params.
pub fn param_jacobian_method(
    kernel: &Kernel,
    names: &mut SymbolNames,
    from_x: Source,
) -> Option<TokenStream> {
    let partials = kernel.param_partials.as_ref()?;
    if kernel.params.is_empty() {
        return None;
    }
    let arena = &kernel.arena;
    let body = match &kernel.motion {
        Motion::Explicit(_) => {
            let body = bodies::body(names, arena, &partials.cells, from_x, "x", "jac");
            let (t, x, out, statements, cells) = (
                &body.t,
                &body.source,
                &body.out,
                &body.statements,
                &body.assignments,
            );
            quote! {
                fn param_jacobian(&self, #t: f64, #x: &[f64], #out: &mut Matrix) -> Result<(), Failure> {
                    #statements
                    #(#cells)*
                    Ok(())
                }
            }
        }
        Motion::Implicit(i) => {
            let m = i.unknowns.len();
            let size = index(m);
            let np = index(kernel.params.len());
            let from_xz = super::motion::from_unknowns(&i.unknowns, from_x);
            let mut roots: Vec<ExprId> = partials.cells.iter().map(|&(_, _, e)| e).collect();
            let mut dep_cells = Vec::new();
            for d in &i.dependent {
                for &(_, e) in &d.d_z {
                    roots.push(e);
                }
            }
            for row in &partials.dependent {
                for &(_, e) in row {
                    roots.push(e);
                }
            }
            let code = names.code(arena, &roots, &from_xz);
            let statements = code.statements(quote! { self.params });
            let (g_p, rest) = code.roots.split_at(partials.cells.len());
            let g_p_cells = bodies::assignments(&quote! { g_p }, &partials.cells, g_p);
            let (d_z_values, d_p_values) =
                rest.split_at(i.dependent.iter().map(|d| d.d_z.len()).sum());
            let (mut at_z, mut at_p) = (0, 0);
            for (d, row) in i.dependent.iter().zip(&partials.dependent) {
                let target = index(kernel.highest_row(d.coord));
                let mut d_z = vec![quote! { 0.0 }; m];
                for &(k, _) in &d.d_z {
                    d_z[k] = d_z_values[at_z].clone();
                    at_z += 1;
                }
                let mut d_p = vec![quote! { 0.0 }; kernel.params.len()];
                for &(p, _) in row {
                    d_p[p] = d_p_values[at_p].clone();
                    at_p += 1;
                }
                dep_cells.push(quote! {
                    {
                        let d_z: [f64; #size] = [#(#d_z),*];
                        let d_p: [f64; #np] = [#(#d_p),*];
                        for c in 0..#np {
                            jac[(#target, c)] = d_p[c] + (0..#size).map(|k| d_z[k] * g_p[(k, c)]).sum::<f64>();
                        }
                    }
                });
            }
            let (ind_rows, ind_k): (Vec<Literal>, Vec<Literal>) = i
                .unknowns
                .iter()
                .enumerate()
                .filter_map(|(k, s)| match s {
                    Symbol::Jet { coord, .. } => {
                        Some((index(kernel.highest_row(*coord)), index(k)))
                    }
                    _ => None,
                })
                .unzip();
            let uses_z = roots
                .iter()
                .any(|&r| i.unknowns.iter().any(|&u| arena.depends_on(r, u)));
            let z = bodies::arg(uses_z, "z");
            quote! {
                fn param_jacobian(&self, t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
                    let (#z, lu) = self.highest_factored(t, x)?;
                    #statements
                    let mut g_p = Matrix::zeros(#size, #np);
                    #(#g_p_cells)*
                    lagc_runtime::highest::implicit_derivatives(&lu, &mut g_p);
                    for c in 0..#np {
                        #(jac[(#ind_rows, c)] = g_p[(#ind_k, c)];)*
                    }
                    #(#dep_cells)*
                    Ok(())
                }
            }
        }
    };
    Some(body)
}
