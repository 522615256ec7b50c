//! The text form of the field method for `lagc derive`: the basic
//! equation (9) with the ansatz inserted, and the coefficient system.

use super::basic::FieldSystem;
use crate::ir::{Arena, ExprId, SharedNames, Symbol};
use std::fmt::Write;

impl FieldSystem {
    /// A section to print after the mechanics' derivation text.
    pub fn text(&self, arena: &Arena, state: &[Symbol]) -> String {
        let mut out = String::from("\nfield method:\n");
        let Some(basic) = self.basic_equation else {
            out.push_str(
                "  the highest derivatives are implicit: the linear ansatz is not a complete \
                 solution; the local field method is used\n",
            );
            return out;
        };
        let Some(&x1) = state.first() else {
            return out;
        };
        let ansatz: Vec<String> = std::iter::once(arena.symbol_name(self.coefficients[0]))
            .chain(
                state
                    .iter()
                    .zip(&self.coefficients)
                    .skip(1)
                    .map(|(&x, &f)| format!("{}*{}", arena.symbol_name(f), arena.symbol_name(x))),
            )
            .collect();
        let _ = writeln!(
            out,
            "  ansatz (10): {} = {}",
            arena.symbol_name(x1),
            ansatz.join(" + ")
        );
        let names = self.shared_names(arena);
        if !names.is_empty() {
            out.push_str("  shared subexpressions (named once, used below):\n");
            for (name, e) in names.definitions() {
                let _ = writeln!(out, "    {name} = {}", arena.definition(e, &names, false));
            }
        }
        let _ = writeln!(
            out,
            "  basic equation (9):\n    {} = 0",
            arena.display_named(basic, &names)
        );
        match &self.coefficient_system {
            None => out.push_str(
                "  not affine in the state: the linear ansatz is not a complete solution; \
                 the local field method is used\n",
            ),
            Some(system) => {
                let kind = if system.linear { "linear" } else { "Riccati" };
                let _ = writeln!(out, "  coefficient system ({kind}):");
                for ((&rate, &rhs), &constant) in self
                    .coefficient_rates
                    .iter()
                    .zip(&system.rhs)
                    .zip(&system.constant)
                {
                    let note = if constant { "  (constant: f = c)" } else { "" };
                    let _ = writeln!(
                        out,
                        "    {} = {}{note}",
                        arena.symbol_name(rate),
                        arena.display_named(rhs, &names)
                    );
                }
            }
        }
        out
    }
}

impl FieldSystem {
    /// Names (`v1`, `v2`, …) for the long parts that (9) and the
    /// coefficient system share: the motion inserted into (9) repeats
    /// those of the reduced system.
    fn shared_names(&self, arena: &Arena) -> SharedNames {
        let mut roots: Vec<ExprId> = self.basic_equation.into_iter().collect();
        if let Some(system) = &self.coefficient_system {
            roots.extend(&system.rhs);
        }
        arena.shared_names(&roots, &arena.fresh_prefix("v", &[]))
    }

    /// The field method's lines for the `align*` block of `lagc derive
    /// --format latex`: the ansatz (10), the basic equation (9) and the
    /// coefficient system.
    pub fn latex_lines(&self, arena: &Arena, state: &[Symbol]) -> String {
        let mut out = String::new();
        let (Some(basic), Some(&x1)) = (self.basic_equation, state.first()) else {
            return out;
        };
        let symbol = |s: Symbol| {
            let mut a = arena.clone();
            let e = a.symbol(s);
            a.latex(e)
        };
        let mut ansatz = symbol(self.coefficients[0]);
        for (&x, &f) in state.iter().zip(&self.coefficients).skip(1) {
            ansatz.push_str(&format!(" + {} {}", symbol(f), symbol(x)));
        }
        out.push_str(&crate::latex::equation(
            &symbol(x1),
            &ansatz,
            "\\text{ansatz (10)}",
        ));
        let names = self.shared_names(arena);
        for (_, e) in names.definitions() {
            out.push_str(&crate::latex::equation(
                &arena.latex_named(e, &names),
                &arena.definition(e, &names, true),
                "\\text{shared}",
            ));
        }
        out.push_str(&crate::latex::equation(
            &arena.latex_named(basic, &names),
            "0",
            "\\text{(9)}",
        ));
        if let Some(system) = &self.coefficient_system {
            let kind = if system.linear { "linear" } else { "Riccati" };
            for (&rate, &rhs) in self.coefficient_rates.iter().zip(&system.rhs) {
                let tag = format!("\\text{{coefficient system ({kind})}}");
                out.push_str(&crate::latex::equation(
                    &symbol(rate),
                    &arena.latex_named(rhs, &names),
                    &tag,
                ));
            }
        }
        out
    }
}
