//! The generated code's names for the model's symbols, and the `let`
//! bindings that bring the symbols a function uses into scope.

use super::expr::{lower_exprs_split, Lowered};
use super::namer::Namer;
use crate::ir::{Arena, ExprId, Symbol};
use proc_macro2::{Ident, TokenStream};
use quote::quote;
use std::collections::{BTreeSet, HashMap};

/// Where a function finds the state-like symbols it reads.
pub type Source<'a> = &'a dyn Fn(Symbol) -> Option<TokenStream>;

pub struct SymbolNames {
    /// The locals that hold the params in generated functions.
    pub params: Vec<Ident>,
    /// The params' field names in `Params`: the model's own names (a
    /// keyword gets a `_`), since fields cannot clash with locals.
    pub param_fields: Vec<Ident>,
    pub masses: Vec<Ident>,
    pub mass_fns: Vec<Ident>,
    symbols: HashMap<Symbol, Ident>,
    /// The switches' branch symbols: `branch_k` reads `self.branches[k]`.
    pub branches: HashMap<Symbol, usize>,
    pub namer: Namer,
}

impl SymbolNames {
    pub fn new(arena: &Arena, extra: &[Symbol]) -> SymbolNames {
        let mut namer = Namer::default();
        let names = arena.names().clone();
        let params = names.params.iter().map(|n| namer.fresh(n)).collect();
        let mut field_namer = Namer::empty();
        let param_fields = names.params.iter().map(|n| field_namer.fresh(n)).collect();
        let masses = names.masses.iter().map(|n| namer.fresh(n)).collect();
        let mass_fns = names
            .masses
            .iter()
            .map(|n| namer.fresh(&format!("mass_{n}")))
            .collect();
        let mut symbols = HashMap::new();
        for &s in extra {
            if let std::collections::hash_map::Entry::Vacant(v) = symbols.entry(s) {
                v.insert(namer.fresh(&arena.symbol_name(s)));
            }
        }
        SymbolNames {
            params,
            param_fields,
            masses,
            mass_fns,
            symbols,
            branches: HashMap::new(),
            namer,
        }
    }

    /// The local variable of a symbol.
    pub fn ident(&mut self, arena: &Arena, s: Symbol) -> TokenStream {
        match s {
            Symbol::Time => quote! { t },
            Symbol::Param(i) => ident_tokens(self.params.get(i as usize)),
            Symbol::Mass(i) => ident_tokens(self.masses.get(i as usize)),
            _ => {
                if !self.symbols.contains_key(&s) {
                    let name = self.namer.fresh(&arena.symbol_name(s));
                    self.symbols.insert(s, name);
                }
                ident_tokens(self.symbols.get(&s))
            }
        }
    }

    /// Straight-line code for `roots`: the bindings of the symbols they use
    /// (params from `p`, mass laws by their functions, state-like symbols
    /// from `source`), the shared sub-expressions, the root expressions.
    pub fn code(&mut self, arena: &Arena, roots: &[ExprId], source: Source) -> Code {
        self.code_split(arena, roots, roots.len(), source).0
    }

    /// [`SymbolNames::code`] for code that computes the first `split`
    /// roots before it can bind some symbols the others read (an implicit
    /// model's highest derivatives, solved from the first): the bindings
    /// of the first roots' symbols come first in `prelude`, and with the
    /// count of `lets` they need, the [`Split`] of the statements.
    pub fn code_split(
        &mut self,
        arena: &Arena,
        roots: &[ExprId],
        split: usize,
        source: Source,
    ) -> (Code, Split) {
        let split = split.min(roots.len());
        let mut early_free: BTreeSet<Symbol> = BTreeSet::new();
        for &r in &roots[..split] {
            early_free.extend(arena.free_symbols(r));
        }
        let mut late_free: BTreeSet<Symbol> = BTreeSet::new();
        for &r in &roots[split..] {
            late_free.extend(arena.free_symbols(r));
        }
        let early_prelude_symbols = early_free.len();
        let free: Vec<Symbol> = early_free
            .iter()
            .copied()
            .chain(late_free.difference(&early_free).copied())
            .collect();
        let mut prelude = Vec::new();
        let mut early_prelude = 0;
        let mut uses_params = false;
        let mut uses_time = false;
        let mut uses_source = false;
        let mut idents: HashMap<Symbol, TokenStream> = HashMap::new();
        for (at, &s) in free.iter().enumerate() {
            if at == early_prelude_symbols {
                early_prelude = prelude.len();
            }
            let name = self.ident(arena, s);
            idents.insert(s, name.clone());
            match s {
                Symbol::Time => uses_time = true,
                Symbol::Param(i) => {
                    uses_params = true;
                    let field = ident_tokens(self.param_fields.get(i as usize));
                    prelude.push(quote! { let #name = p.#field; });
                }
                Symbol::Mass(i) => {
                    uses_params = true;
                    uses_time = true;
                    let f = ident_tokens(self.mass_fns.get(i as usize));
                    prelude.push(quote! { let #name = #f(p, t); });
                }
                // The model holds its inputs; on a segment each is a line
                // in `t` (`Inputs::at`), its rate a constant.
                Symbol::Input(i) => {
                    uses_time = true;
                    let i = proc_macro2::Literal::u32_unsuffixed(i);
                    prelude.push(quote! { let #name = self.inputs.at(#i, t); });
                }
                Symbol::InputRate(i) => {
                    let i = proc_macro2::Literal::u32_unsuffixed(i);
                    prelude.push(quote! { let #name = self.inputs.rate(#i); });
                }
                _ if self.branches.contains_key(&s) => {
                    let k = proc_macro2::Literal::usize_unsuffixed(self.branches[&s]);
                    prelude.push(quote! { let #name = self.branches[#k]; });
                }
                _ => {
                    uses_source = true;
                    let value = source(s).unwrap_or_else(|| quote! { f64::NAN });
                    // A source that is already this local needs no binding.
                    if value.to_string() != name.to_string() {
                        prelude.push(quote! { let #name = #value; });
                    }
                }
            }
        }
        let lookup = |s: Symbol| {
            idents
                .get(&s)
                .cloned()
                .unwrap_or_else(|| quote! { f64::NAN })
        };
        // The shared sub-expressions are named in a scope of this item's
        // own (`e`, `e_2`, … in every function), so that a change in one
        // item renames nothing in another.
        let mut item_scope = self.namer.clone();
        let (Lowered { lets, roots }, early_lets) =
            lower_exprs_split(arena, roots, split, &lookup, &mut item_scope);
        if early_prelude_symbols >= free.len() {
            early_prelude = prelude.len();
        }
        let code = Code {
            prelude,
            lets,
            roots,
            uses_params,
            uses_time,
            uses_source,
        };
        (
            code,
            Split {
                prelude: early_prelude,
                lets: early_lets,
            },
        )
    }
}

fn ident_tokens(ident: Option<&Ident>) -> TokenStream {
    match ident {
        Some(i) => quote! { #i },
        None => quote! { f64::NAN },
    }
}

/// Where [`SymbolNames::code_split`]'s statements divide: the first
/// `prelude` bindings and `lets` are all the first roots need.
#[derive(Clone, Copy)]
pub struct Split {
    pub prelude: usize,
    pub lets: usize,
}

pub struct Code {
    pub prelude: Vec<TokenStream>,
    pub lets: Vec<TokenStream>,
    pub roots: Vec<TokenStream>,
    pub uses_params: bool,
    pub uses_time: bool,
    /// Reads a symbol from the function's `source` (the state, `f`, …).
    pub uses_source: bool,
}

impl Code {
    /// The statements before the roots are used: `let p = &self.params;`
    /// when needed (`params` is the place that holds the params, e.g.
    /// `self.params`), the bindings and the shared sub-expressions.
    pub fn statements(&self, params: TokenStream) -> TokenStream {
        let prelude = &self.prelude;
        let lets = &self.lets;
        let p = if self.uses_params {
            quote! { let p = &#params; }
        } else {
            TokenStream::new()
        };
        quote! { #p #(#prelude)* #(#lets)* }
    }

    /// [`Code::statements`] in two: those the first roots of a
    /// [`SymbolNames::code_split`] need (with `let p = …;` when any
    /// statement uses the params), and the rest.
    pub fn split_statements(&self, params: TokenStream, at: Split) -> (TokenStream, TokenStream) {
        let (early_prelude, late_prelude) = self.prelude.split_at(at.prelude);
        let (early_lets, late_lets) = self.lets.split_at(at.lets);
        let p = if self.uses_params {
            quote! { let p = &#params; }
        } else {
            TokenStream::new()
        };
        (
            quote! { #p #(#early_prelude)* #(#early_lets)* },
            quote! { #(#late_prelude)* #(#late_lets)* },
        )
    }

    /// The statements for a function whose params are already `p`.
    pub fn statements_in_p(&self) -> TokenStream {
        let prelude = &self.prelude;
        let lets = &self.lets;
        quote! { #(#prelude)* #(#lets)* }
    }

    /// The statements and the first root as one expression: a block only
    /// when there are statements (rustc warns on needless braces).
    pub fn single(&self, params: TokenStream) -> TokenStream {
        let root = &self.roots[0];
        if self.prelude.is_empty() && self.lets.is_empty() && !self.uses_params {
            return root.clone();
        }
        // A lone param: `params.x0`, not a block binding and returning it
        // (clippy's `let_and_return`).
        if self.lets.is_empty() && self.prelude.len() == 1 && !self.uses_time {
            let binding = self.prelude[0].to_string();
            let field = binding
                .strip_prefix(&format!("let {root} = p . "))
                .and_then(|rest| rest.strip_suffix(" ;"));
            if let Some(field) = field {
                let field = proc_macro2::Ident::new(field, proc_macro2::Span::call_site());
                return quote! { #params.#field };
            }
        }
        let statements = self.statements(params);
        quote! { { #statements #root } }
    }

    /// The time argument's name: `_t` when unused (no warning).
    pub fn time_arg(&self) -> TokenStream {
        if self.uses_time {
            quote! { t }
        } else {
            quote! { _t }
        }
    }
}
