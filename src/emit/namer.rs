//! The one place generated identifiers come from: every model name and
//! every internal name goes through [`Namer`], so the generated code never
//! holds an invalid, clashing or non-snake-case identifier.

use proc_macro2::{Ident, Span};
use std::collections::HashSet;

/// Rust's keywords (strict, reserved and weak ones that matter in
/// expression position), which a model may use as names.
const KEYWORDS: &[&str] = &[
    "abstract", "as", "async", "await", "become", "box", "break", "const", "continue", "crate",
    "do", "dyn", "else", "enum", "extern", "false", "final", "fn", "for", "gen", "if", "impl",
    "in", "let", "loop", "macro", "match", "mod", "move", "mut", "override", "priv", "pub", "ref",
    "return", "self", "static", "struct", "super", "trait", "true", "try", "type", "typeof",
    "union", "unsafe", "unsized", "use", "virtual", "where", "while", "yield",
];

/// Names the generated code uses itself (arguments, locals, items).
const INTERNAL: &[&str] = &[
    "t",
    "x",
    "dx",
    "jac",
    "dxdt",
    "f",
    "df",
    "dfdt",
    "p",
    "z",
    "a",
    "b",
    "lu",
    "params",
    "overrides",
    "residual",
    "step",
    "iteration",
    "main",
    "model",
    "runtime",
    "nalgebra",
    "std",
    "core",
    "failure",
    "sample",
    "samples",
    "times",
    "options",
    "on_sample",
    "value",
    "values",
    "g",
    "g_z",
    "g_x",
    "g_t",
    "c",
    "k",
    "m",
    "d_x",
    "d_z",
    "out",
    "given",
    "default",
    "mass_matrix",
    "highest",
    "highest_factored",
    "mass_system",
];

#[derive(Debug, Clone)]
pub struct Namer {
    used: HashSet<String>,
}

impl Default for Namer {
    fn default() -> Self {
        Namer {
            used: INTERNAL.iter().map(|s| s.to_string()).collect(),
        }
    }
}

impl Namer {
    /// A namer with nothing taken (for names in their own namespace, such
    /// as a struct's fields).
    pub fn empty() -> Namer {
        Namer {
            used: HashSet::new(),
        }
    }

    /// A fresh snake-case identifier close to `wanted`: lower case, primes
    /// as `_d<count>` (`q1''` → `q1_d2`), other characters as `_`, a `_`
    /// suffix for keywords, a number suffix when taken.
    pub fn fresh(&mut self, wanted: &str) -> Ident {
        let base = sanitize(wanted);
        let mut name = base.clone();
        // `self_` (a keyword's) taken: `self_2`, not `self__2`, which rustc
        // warns is not snake case.
        let stem = base.trim_end_matches('_');
        let mut k = 2;
        while self.used.contains(&name) {
            name = format!("{stem}_{k}");
            k += 1;
        }
        self.used.insert(name.clone());
        Ident::new(&name, Span::call_site())
    }
}

/// `wanted` as a valid, snake-case, non-keyword identifier (may be taken).
pub fn sanitize(wanted: &str) -> String {
    let primes = wanted.chars().rev().take_while(|&c| c == '\'').count();
    let stem = &wanted[..wanted.len() - primes];
    let mut name: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect();
    // Underscores only at the ends are fine for rustc; a run of them or
    // an empty name is not a useful identifier.
    while name.contains("__") {
        name = name.replace("__", "_");
    }
    let name = name.trim_matches('_').to_string();
    let mut name = if name.is_empty() {
        "v".to_string()
    } else {
        name
    };
    if name.starts_with(|c: char| c.is_ascii_digit()) {
        name.insert(0, 'v');
    }
    if primes > 0 {
        name = format!("{name}_d{primes}");
    }
    if KEYWORDS.contains(&name.as_str()) {
        name.push('_');
    }
    name
}
