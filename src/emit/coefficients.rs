//! The coefficient system `f' = F(t, f)` of the field method (affine
//! reduced systems only) as trait items, printed from the kernel.
//! Coefficients with `F_A ≡ 0` keep their anchor values: only their zero
//! rate is written.

use super::bodies::{self, index};
use super::names::SymbolNames;
use crate::kernel::Kernel;
use proc_macro2::TokenStream;
use quote::quote;

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
    let rates: Vec<_> = system.rhs.iter().copied().enumerate().collect();
    let rhs = bodies::body(names, arena, &rates, &from_f, "f", "df");
    let jac = bodies::body(names, arena, &system.jacobian, &from_f, "f", "jac");
    let tp = bodies::body(names, arena, &system.time_partial, &from_f, "f", "dfdt");
    let (rhs_t, rhs_f, rhs_statements, rhs_rows) =
        (&rhs.t, &rhs.source, &rhs.statements, &rhs.assignments);
    let (jac_t, jac_f, jac_out, jac_statements, cells) = (
        &jac.t,
        &jac.source,
        &jac.out,
        &jac.statements,
        &jac.assignments,
    );
    let (tp_t, tp_f, tp_out, tp_statements, tp_rows) =
        (&tp.t, &tp.source, &tp.out, &tp.statements, &tp.assignments);
    quote! {
        fn coefficients(&self, #rhs_t: f64, #rhs_f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
            #rhs_statements
            #(#rhs_rows)*
            Ok(())
        }

        fn coefficient_jacobian(&self, #jac_t: f64, #jac_f: &[f64], #jac_out: &mut Matrix) -> Result<(), Failure> {
            #jac_statements
            #(#cells)*
            Ok(())
        }

        fn coefficient_time_partial(&self, #tp_t: f64, #tp_f: &[f64], #tp_out: &mut [f64]) -> Result<(), Failure> {
            #tp_statements
            #(#tp_rows)*
            Ok(())
        }
    }
}
