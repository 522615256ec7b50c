//! The reduced system (7) as a `Motion`: the right side, `∂X/∂x`, `∂X/∂t`.
//!
//! Explicit systems get symbolic Jacobians. Implicit ones solve for the
//! highest derivatives at run time — one LU solve when the residual is
//! affine in them, Newton with the symbolic `∂G/∂z` otherwise — and their
//! `∂X/∂x`, `∂X/∂t` are central finite differences of the right side
//! (implicit differentiation would need `∂G/∂x` per entry; the Jacobian is
//! used only by the stiff integrator and the local field method, which
//! tolerate its `O(h²)` error).

use super::names::SymbolNames;
use crate::ir::{Arena, ExprId, Symbol};
use crate::mechanics::{Highest, ReducedSystem};
use proc_macro2::{Literal, TokenStream};
use quote::quote;
use std::collections::HashMap;

/// What the motion code needs that the emitter reports back.
pub struct MotionCode {
    pub items: TokenStream,
    /// A dense linear solve (nalgebra LU) is emitted.
    pub linear_solve: bool,
    /// Newton's method is emitted.
    pub newton: bool,
}

fn index(i: usize) -> Literal {
    Literal::usize_unsuffixed(i)
}

pub fn motion_code(
    arena: &mut Arena,
    names: &mut SymbolNames,
    reduced: &ReducedSystem,
) -> MotionCode {
    let n_state = reduced.state.len();
    let position: HashMap<Symbol, usize> = reduced
        .state
        .iter()
        .enumerate()
        .map(|(i, &s)| (s, i))
        .collect();
    let coords = n_state / reduced.order.max(1) as usize;
    let highest_row = |coord: u32| (reduced.order as usize - 1) * coords + coord as usize;
    let from_x = |s: Symbol| {
        position.get(&s).map(|&i| {
            let i = index(i);
            quote! { x[#i] }
        })
    };
    let shifts: Vec<TokenStream> = (0..n_state.saturating_sub(coords))
        .map(|i| {
            let (row, col) = (index(i), index(i + coords));
            quote! { dx[#row] = x[#col]; }
        })
        .collect();
    let shift_jacobian: Vec<TokenStream> = (0..n_state.saturating_sub(coords))
        .map(|i| {
            let (row, col) = (index(i), index(i + coords));
            quote! { jac[(#row, #col)] = 1.0; }
        })
        .collect();
    match &reduced.highest {
        Highest::Explicit(highest) => {
            let rhs = names.code(arena, highest, &from_x);
            let rows: Vec<TokenStream> = (0..highest.len())
                .map(|j| {
                    let row = index(highest_row(j as u32));
                    quote! { #row }
                })
                .collect();
            let values = &rhs.roots;
            let rhs_statements = rhs.statements(quote! { &self.params });
            let t_rhs = rhs.time_arg();

            let mut entries: Vec<(usize, usize, ExprId)> = Vec::new();
            for (j, &h) in highest.iter().enumerate() {
                for (k, &s) in reduced.state.iter().enumerate() {
                    let d = arena.diff(h, s);
                    if !arena.is_zero(d) {
                        entries.push((highest_row(j as u32), k, d));
                    }
                }
            }
            let jacobian = entry_code(arena, names, &entries, &from_x, |r, c| {
                quote! { jac[(#r, #c)] }
            });
            let mut partials: Vec<(usize, usize, ExprId)> = Vec::new();
            for (j, &h) in highest.iter().enumerate() {
                let d = arena.diff(h, Symbol::Time);
                if !arena.is_zero(d) {
                    partials.push((highest_row(j as u32), 0, d));
                }
            }
            let time_partial = entry_code(arena, names, &partials, &from_x, |r, _| {
                quote! { dxdt[#r] }
            });
            let (jac_t, jac_x, jac_body) = jacobian;
            let (tp_t, tp_x, tp_body) = time_partial;
            let dxdt = if partials.is_empty() {
                quote! { _dxdt }
            } else {
                quote! { dxdt }
            };
            let items = quote! {
                impl Motion for System {
                    fn dim(&self) -> usize { STATE_NAMES.len() }

                    fn rhs(&self, #t_rhs: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
                        #rhs_statements
                        #(#shifts)*
                        #(dx[#rows] = #values;)*
                        Ok(())
                    }

                    fn jacobian(&self, #jac_t: f64, #jac_x: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
                        #(#shift_jacobian)*
                        #jac_body
                        Ok(())
                    }

                    fn time_partial(&self, #tp_t: f64, #tp_x: &[f64], #dxdt: &mut [f64]) -> Result<(), Failure> {
                        #tp_body
                        Ok(())
                    }

                    fn component_name(&self, i: usize) -> String {
                        STATE_NAMES.get(i).map_or_else(|| format!("x{}", i + 1), |s| s.to_string())
                    }
                }
            };
            MotionCode {
                items,
                linear_solve: false,
                newton: false,
            }
        }
        Highest::Implicit {
            unknowns,
            residual,
            jacobian,
            linear,
            dependent,
        } => {
            let unknown_at: HashMap<Symbol, usize> =
                unknowns.iter().enumerate().map(|(k, &s)| (s, k)).collect();
            let from_xz = |s: Symbol| {
                unknown_at
                    .get(&s)
                    .map(|&k| {
                        let k = index(k);
                        quote! { z[#k] }
                    })
                    .or_else(|| from_x(s))
            };
            let size = index(unknowns.len());
            let solve = if *linear {
                let zero = arena.zero();
                let at_zero: HashMap<Symbol, ExprId> =
                    unknowns.iter().map(|&s| (s, zero)).collect();
                let mut roots: Vec<ExprId> =
                    residual.iter().map(|&r| arena.subst(r, &at_zero)).collect();
                let (cells, entries) = nonzero_cells(arena, jacobian);
                roots.extend(entries);
                let code = names.code(arena, &roots, &from_x);
                let statements = code.statements(quote! { &self.params });
                let free: Vec<TokenStream> = code.roots[..residual.len()].to_vec();
                let cell_code =
                    cell_assignments(&quote! { a }, &cells, &code.roots[residual.len()..]);
                quote! {
                    /// The independent highest derivatives from `A z = b`
                    /// (the equations are affine in them): one LU solve.
                    fn highest(&self, t: f64, x: &[f64]) -> Result<DVector<f64>, Failure> {
                        #statements
                        let mut a = DMatrix::<f64>::zeros(#size, #size);
                        #(#cell_code)*
                        let b = DVector::from_vec(vec![#(-(#free)),*]);
                        solve_mass_matrix(t, a, b, &self.mass_matrix)
                    }
                }
            } else {
                let mut roots: Vec<ExprId> = residual.clone();
                let (cells, entries) = nonzero_cells(arena, jacobian);
                roots.extend(entries);
                let code = names.code(arena, &roots, &from_xz);
                let statements = code.statements(quote! { &self.params });
                let residual_values: Vec<TokenStream> = code.roots[..residual.len()].to_vec();
                let cell_code =
                    cell_assignments(&quote! { g_z }, &cells, &code.roots[residual.len()..]);
                let t = code.time_arg();
                let x = if uses_any(arena, &roots, &reduced.state) {
                    quote! { x }
                } else {
                    quote! { _x }
                };
                let z = if uses_any(arena, &roots, unknowns) {
                    quote! { z }
                } else {
                    quote! { _z }
                };
                quote! {
                    /// The residual `G(t, x, z)` of the highest derivatives and
                    /// its Jacobian `∂G/∂z`.
                    fn residual(&self, #t: f64, #x: &[f64], #z: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>) {
                        #statements
                        let mut g_z = DMatrix::<f64>::zeros(#size, #size);
                        #(#cell_code)*
                        (DVector::from_vec(vec![#(#residual_values),*]), g_z)
                    }

                    /// The independent highest derivatives by Newton's method
                    /// (they enter the equations non-linearly).
                    fn highest(&self, t: f64, x: &[f64]) -> Result<DVector<f64>, Failure> {
                        newton(t, DVector::zeros(#size), |z| self.residual(t, x, z))
                    }
                }
            };
            let dependent_exprs: Vec<ExprId> = dependent.iter().map(|&(_, e)| e).collect();
            let dep_code = names.code(arena, &dependent_exprs, &from_xz);
            let dep_statements = dep_code.statements(quote! { &self.params });
            let dep_values = &dep_code.roots;
            let dep_rows: Vec<Literal> = dependent
                .iter()
                .map(|&(c, _)| index(highest_row(c)))
                .collect();
            let (ind_rows, ind_k): (Vec<Literal>, Vec<Literal>) = unknowns
                .iter()
                .enumerate()
                .filter_map(|(k, s)| match s {
                    Symbol::Jet { coord, .. } => Some((index(highest_row(*coord)), index(k))),
                    _ => None,
                })
                .unzip();
            let n = index(n_state);
            let items = quote! {
                impl System {
                    #solve
                }

                impl Motion for System {
                    fn dim(&self) -> usize { STATE_NAMES.len() }

                    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
                        let z = self.highest(t, x)?;
                        #dep_statements
                        #(#shifts)*
                        #(dx[#ind_rows] = z[#ind_k];)*
                        #(dx[#dep_rows] = #dep_values;)*
                        Ok(())
                    }

                    fn jacobian(&self, t: f64, x: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
                        finite_difference_jacobian(self, t, x, #n, jac)
                    }

                    fn time_partial(&self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), Failure> {
                        finite_difference_time_partial(self, t, x, #n, dxdt)
                    }

                    fn component_name(&self, i: usize) -> String {
                        STATE_NAMES.get(i).map_or_else(|| format!("x{}", i + 1), |s| s.to_string())
                    }
                }
            };
            MotionCode {
                items,
                linear_solve: *linear,
                newton: !*linear,
            }
        }
    }
}

/// `target(row, col) = value;` for every entry, with the bindings they
/// need; returns the names of the time and state arguments (`_t`, `_x`
/// when unused) and the statements.
fn entry_code(
    arena: &Arena,
    names: &mut SymbolNames,
    entries: &[(usize, usize, ExprId)],
    source: super::names::Source,
    target: impl Fn(Literal, Literal) -> TokenStream,
) -> (TokenStream, TokenStream, TokenStream) {
    let roots: Vec<ExprId> = entries.iter().map(|&(_, _, e)| e).collect();
    let code = names.code(arena, &roots, source);
    let statements = code.statements(quote! { &self.params });
    let assignments: Vec<TokenStream> = entries
        .iter()
        .zip(&code.roots)
        .map(|(&(r, c, _), v)| {
            let place = target(index(r), index(c));
            quote! { #place = #v; }
        })
        .collect();
    let x = if code.uses_source {
        quote! { x }
    } else {
        quote! { _x }
    };
    (code.time_arg(), x, quote! { #statements #(#assignments)* })
}

fn uses_any(arena: &Arena, roots: &[ExprId], symbols: &[Symbol]) -> bool {
    roots
        .iter()
        .any(|&r| symbols.iter().any(|&s| arena.depends_on(r, s)))
}

/// The non-zero entries of `matrix`: their `(row, column)`, and their
/// expressions in the same order.
fn nonzero_cells(arena: &Arena, matrix: &[Vec<ExprId>]) -> (Vec<(usize, usize)>, Vec<ExprId>) {
    let mut cells = Vec::new();
    let mut entries = Vec::new();
    for (r, row) in matrix.iter().enumerate() {
        for (c, &entry) in row.iter().enumerate() {
            if !arena.is_zero(entry) {
                cells.push((r, c));
                entries.push(entry);
            }
        }
    }
    (cells, entries)
}

/// `matrix[(r, c)] = value;` for every cell and its value's code.
fn cell_assignments(
    matrix: &TokenStream,
    cells: &[(usize, usize)],
    values: &[TokenStream],
) -> Vec<TokenStream> {
    cells
        .iter()
        .zip(values)
        .map(|(&(r, c), v)| {
            let (r, c) = (index(r), index(c));
            quote! { #matrix[(#r, #c)] = #v; }
        })
        .collect()
}
