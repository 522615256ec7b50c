//! The coefficient system `f' = F(t, f)` of the field method (affine
//! reduced systems only) as trait items, printed from the kernel.
//! Coefficients with `F_A ≡ 0` keep their anchor values: only their zero
//! rate is written.

use super::names::SymbolNames;
use crate::ir::ExprId;
use crate::kernel::Kernel;
use proc_macro2::{Literal, TokenStream};
use quote::quote;

fn index(i: usize) -> Literal {
    Literal::usize_unsuffixed(i)
}

fn arg(used: bool, name: &str) -> TokenStream {
    let ident = proc_macro2::Ident::new(
        &if used {
            name.to_string()
        } else {
            format!("_{name}")
        },
        proc_macro2::Span::call_site(),
    );
    quote! { #ident }
}

pub fn coefficient_code(kernel: &Kernel, names: &mut SymbolNames) -> TokenStream {
    let Some(system) = &kernel.coefficients else {
        return TokenStream::new();
    };
    let arena = &kernel.arena;
    let position = |s| system.symbols.iter().position(|&c| c == s);
    let from_f = |s| {
        position(s).map(|k| {
            let k = index(k);
            quote! { f[#k] }
        })
    };
    let rhs = names.code(arena, &system.rhs, &from_f);
    let rhs_statements = rhs.statements(quote! { self.params });
    let rows: Vec<Literal> = (0..system.rhs.len()).map(index).collect();
    let values = &rhs.roots;
    let rhs_t = rhs.time_arg();
    let rhs_f = arg(rhs.uses_source, "f");

    let roots: Vec<ExprId> = system.jacobian.iter().map(|&(_, _, e)| e).collect();
    let jac = names.code(arena, &roots, &from_f);
    let jac_statements = jac.statements(quote! { self.params });
    let cells: Vec<TokenStream> = system
        .jacobian
        .iter()
        .zip(&jac.roots)
        .map(|(&(a, b, _), v)| {
            let (a, b) = (index(a), index(b));
            quote! { jac[(#a, #b)] = #v; }
        })
        .collect();
    let jac_t = jac.time_arg();
    let jac_f = arg(jac.uses_source, "f");
    let jac_out = arg(!cells.is_empty(), "jac");

    let roots: Vec<ExprId> = system.time_partial.iter().map(|&(_, e)| e).collect();
    let tp = names.code(arena, &roots, &from_f);
    let tp_statements = tp.statements(quote! { self.params });
    let tp_rows: Vec<Literal> = system.time_partial.iter().map(|&(a, _)| index(a)).collect();
    let tp_values = &tp.roots;
    let tp_t = tp.time_arg();
    let tp_f = arg(tp.uses_source, "f");
    let tp_out = arg(!tp_rows.is_empty(), "dfdt");
    quote! {
        fn coefficients(&self, #rhs_t: f64, #rhs_f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
            #rhs_statements
            #(df[#rows] = #values;)*
            Ok(())
        }

        fn coefficient_jacobian(&self, #jac_t: f64, #jac_f: &[f64], #jac_out: &mut Matrix) -> Result<(), Failure> {
            #jac_statements
            #(#cells)*
            Ok(())
        }

        fn coefficient_time_partial(&self, #tp_t: f64, #tp_f: &[f64], #tp_out: &mut [f64]) -> Result<(), Failure> {
            #tp_statements
            #(dfdt[#tp_rows] = #tp_values;)*
            Ok(())
        }
    }
}
