//! The coefficient system `f' = F(t, f)` of the field method as a
//! `CoefficientSystem`: only for systems where the linear ansatz is a
//! complete solution. Coefficients with `F_A ≡ 0` are folded: they keep
//! their anchor values `c_A`, and no equation is emitted for them.

use super::names::SymbolNames;
use crate::field::FieldSystem;
use crate::ir::{Arena, ExprId};
use proc_macro2::{Literal, TokenStream};
use quote::quote;

fn index(i: usize) -> Literal {
    Literal::usize_unsuffixed(i)
}

pub fn coefficient_code(
    arena: &Arena,
    names: &mut SymbolNames,
    field: &FieldSystem,
) -> Option<TokenStream> {
    let system = field.coefficient_system.as_ref()?;
    let position = |s| field.coefficients.iter().position(|&c| c == s);
    let from_f = |s| {
        position(s).map(|k| {
            let k = index(k);
            quote! { f[#k] }
        })
    };
    let moving: Vec<usize> = (0..system.rhs.len())
        .filter(|&a| !system.constant[a])
        .collect();
    let rhs_roots: Vec<ExprId> = moving.iter().map(|&a| system.rhs[a]).collect();
    let rhs = names.code(arena, &rhs_roots, &from_f);
    let rhs_statements = rhs.statements(quote! { &self.params });
    let rhs_rows: Vec<Literal> = moving.iter().map(|&a| index(a)).collect();
    let rhs_values = &rhs.roots;
    let constant_rows: Vec<Literal> = (0..system.rhs.len())
        .filter(|&a| system.constant[a])
        .map(index)
        .collect();
    let rhs_t = rhs.time_arg();
    let rhs_f = if rhs.uses_source {
        quote! { f }
    } else {
        quote! { _f }
    };

    let mut entries = Vec::new();
    for (a, row) in system.jacobian.iter().enumerate() {
        for (b, &e) in row.iter().enumerate() {
            if !arena.is_zero(e) {
                entries.push((a, b, e));
            }
        }
    }
    let roots: Vec<ExprId> = entries.iter().map(|&(_, _, e)| e).collect();
    let jac = names.code(arena, &roots, &from_f);
    let jac_statements = jac.statements(quote! { &self.params });
    let jac_assign: Vec<TokenStream> = entries
        .iter()
        .zip(&jac.roots)
        .map(|(&(a, b, _), v)| {
            let (a, b) = (index(a), index(b));
            quote! { jac[(#a, #b)] = #v; }
        })
        .collect();
    let jac_t = jac.time_arg();
    let jac_f = if jac.uses_source {
        quote! { f }
    } else {
        quote! { _f }
    };
    let jac_arg = if entries.is_empty() {
        quote! { _jac }
    } else {
        quote! { jac }
    };

    let partials: Vec<(usize, ExprId)> = system
        .time_partial
        .iter()
        .enumerate()
        .filter(|&(_, &e)| !arena.is_zero(e))
        .map(|(a, &e)| (a, e))
        .collect();
    let roots: Vec<ExprId> = partials.iter().map(|&(_, e)| e).collect();
    let tp = names.code(arena, &roots, &from_f);
    let tp_statements = tp.statements(quote! { &self.params });
    let tp_rows: Vec<Literal> = partials.iter().map(|&(a, _)| index(a)).collect();
    let tp_values = &tp.roots;
    let tp_t = tp.time_arg();
    let tp_f = if tp.uses_source {
        quote! { f }
    } else {
        quote! { _f }
    };
    let tp_arg = if partials.is_empty() {
        quote! { _dfdt }
    } else {
        quote! { dfdt }
    };
    let linear = system.linear;
    let kind = if linear {
        "linear: no `X_A` depends on `x_1`"
    } else {
        "of Riccati type: some `X_A` depends on `x_1`"
    };
    let doc = format!(" The coefficient system of the field ansatz (10), {kind}.");
    Some(quote! {
        #[doc = #doc]
        pub struct Coefficients {
            pub params: Params,
        }

        impl CoefficientSystem for Coefficients {
            fn dim(&self) -> usize { STATE_NAMES.len() }

            fn rhs(&self, #rhs_t: f64, #rhs_f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
                #rhs_statements
                #(df[#constant_rows] = 0.0;)*
                #(df[#rhs_rows] = #rhs_values;)*
                Ok(())
            }

            fn jacobian(&self, #jac_t: f64, #jac_f: &[f64], #jac_arg: &mut DMatrix<f64>) -> Result<(), Failure> {
                #jac_statements
                #(#jac_assign)*
                Ok(())
            }

            fn time_partial(&self, #tp_t: f64, #tp_f: &[f64], #tp_arg: &mut [f64]) -> Result<(), Failure> {
                #tp_statements
                #(dfdt[#tp_rows] = #tp_values;)*
                Ok(())
            }

            fn is_linear(&self) -> bool { #linear }
        }
    })
}
