//! The derivation as text a mechanician reads (`lagc derive`) and as a LaTeX
//! `align*` block: the model's sizes, the constraints, equations (4), the
//! masses divided out, the reduced system (7), the state and its initial
//! values.

use super::reduced::{Highest, InitialValue};
use super::tidy::{tidy_terms, tidy_terms_all};
use super::Derivation;
use crate::ir::{Arena, ExprId, FxMap, SharedNames, Symbol};
use std::fmt::Write;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Style {
    Text,
    Latex,
}

/// How [`sum`] writes: the first pass only collects the terms it would
/// print (the roots of the shared names), the second prints them, each
/// named shared part as its name.
struct Printer {
    collecting: bool,
    roots: Vec<ExprId>,
    names: SharedNames,
    /// `tidy_terms` of every expression written, kept from the first pass
    /// for the second (tidying a large model is most of its text's cost).
    tidied: FxMap<ExprId, Vec<ExprId>>,
}

impl Printer {
    fn collecting() -> Printer {
        Printer {
            collecting: true,
            roots: Vec::new(),
            names: SharedNames::none(),
            tidied: FxMap::default(),
        }
    }

    /// Every expression written out (the impacts' few short lines).
    fn plain() -> Printer {
        Printer {
            collecting: false,
            roots: Vec::new(),
            names: SharedNames::none(),
            tidied: FxMap::default(),
        }
    }

    /// The printer of the second pass: names for what the first collected.
    fn printing(self, arena: &Arena, prefix: &str) -> Printer {
        Printer {
            collecting: false,
            names: arena.shared_names(&self.roots, prefix),
            roots: Vec::new(),
            tidied: self.tidied,
        }
    }

    /// Tidies `es` together (one Jacobian for all, see [`tidy_terms_all`])
    /// ahead of their [`sum`]s.
    fn prepare(&mut self, arena: &mut Arena, es: &[ExprId]) {
        let mut todo: Vec<ExprId> = Vec::new();
        for &e in es {
            if !self.tidied.contains_key(&e) && !todo.contains(&e) {
                todo.push(e);
            }
        }
        let tidied = tidy_terms_all(arena, &todo);
        self.tidied.extend(todo.into_iter().zip(tidied));
    }

    /// The definitions of the shared names, as a text section or LaTeX lines.
    fn definitions(&self, arena: &Arena, style: Style) -> String {
        let mut out = String::new();
        if self.names.is_empty() {
            return out;
        }
        if style == Style::Text {
            out.push_str("\nshared subexpressions (named once, used below):\n");
        }
        for (name, e) in self.names.definitions() {
            match style {
                Style::Text => {
                    let _ = writeln!(
                        out,
                        "  {name} = {}",
                        arena.definition(e, &self.names, false)
                    );
                }
                Style::Latex => out.push_str(&crate::latex::equation(
                    &arena.latex_named(e, &self.names),
                    &arena.definition(e, &self.names, true),
                    "\\text{shared}",
                )),
            }
        }
        out
    }
}

/// The prefix of the shared names: `w` (`w1`, `w2`, …) unless a name of
/// the model's is `w` and digits.
fn name_prefix(arena: &Arena, lets: &[(String, Vec<ExprId>)]) -> String {
    let lets: Vec<&str> = lets.iter().map(|(name, _)| name.as_str()).collect();
    arena.fresh_prefix("w", &lets)
}

/// `e` written as its collected terms, highest derivatives first.
fn sum(arena: &mut Arena, e: ExprId, style: Style, p: &mut Printer) -> String {
    let terms = match p.tidied.get(&e) {
        Some(terms) => terms.clone(),
        None => {
            let terms = tidy_terms(arena, e);
            p.tidied.insert(e, terms.clone());
            terms
        }
    };
    if p.collecting {
        p.roots.extend_from_slice(&terms);
        return String::new();
    }
    let mut out = String::new();
    for (i, &t) in terms.iter().enumerate() {
        let s = match style {
            Style::Text => arena.display_named(t, &p.names),
            Style::Latex => arena.latex_named(t, &p.names),
        };
        match (i, s.strip_prefix('-')) {
            (0, _) => out.push_str(&s),
            (_, Some(rest)) => {
                out.push_str(" - ");
                out.push_str(rest);
            }
            (_, None) => {
                out.push_str(" + ");
                out.push_str(&s);
            }
        }
    }
    out
}

fn name(arena: &Arena, s: Symbol, style: Style) -> String {
    match style {
        Style::Text => arena.symbol_name(s),
        Style::Latex => {
            let e = arena_symbol_latex(arena, s);
            e.unwrap_or_else(|| arena.symbol_name(s))
        }
    }
}

/// The LaTeX name of a symbol, through a throwaway copy of the arena.
fn arena_symbol_latex(arena: &Arena, s: Symbol) -> Option<String> {
    let mut copy = Arena::new(arena.names().clone());
    let e = copy.symbol(s);
    Some(copy.latex(e))
}

fn jet(coord: u32, order: u32) -> Symbol {
    Symbol::Jet { coord, order }
}

impl Derivation {
    /// The derivation as plain text.
    pub fn text(&self) -> String {
        let mut arena = self.arena.clone();
        self.text_in(&mut arena)
    }

    /// [`Derivation::text`] built in `arena`: the derivation's own arena
    /// taken out of it, or one grown from it (a caller done with the
    /// derivation spares the copy, which on a large model is millions of
    /// nodes to copy and to free).
    pub fn text_in(&self, arena: &mut Arena) -> String {
        let mut first = Printer::collecting();
        first.prepare(arena, &self.bulk());
        self.text_with(arena, &mut first);
        let prefix = name_prefix(arena, &self.lets);
        let mut second = first.printing(arena, &prefix);
        self.text_with(arena, &mut second)
    }

    /// The expressions that make most of the text: both sides of (4) and
    /// the reduced system's.
    fn bulk(&self) -> Vec<ExprId> {
        let mut es: Vec<ExprId> = self
            .equations
            .iter()
            .flat_map(|eq| [eq.lhs, eq.rhs])
            .collect();
        match &self.reduced.highest {
            Highest::Explicit(exprs) => es.extend_from_slice(exprs),
            Highest::Implicit {
                residual,
                dependent,
                ..
            } => {
                es.extend_from_slice(residual);
                es.extend(dependent.iter().map(|&(_, e)| e));
            }
        }
        es
    }

    fn text_with(&self, a: &mut Arena, p: &mut Printer) -> String {
        let mut out = String::new();
        let coords: Vec<String> = (0..self.coordinates as u32)
            .map(|j| a.symbol_name(jet(j, 0)))
            .collect();
        let independent: Vec<String> = self
            .independent
            .iter()
            .map(|&i| coords[i as usize].clone())
            .collect();
        let order = match self.constraint_order {
            Some(k) => format!("constraint order k = {k}"),
            None => "no constraints (holonomic, (4) with k = 1)".to_string(),
        };
        let _ = writeln!(
            out,
            "n = {} ({}), s = {} independent ({}), {order}, u = {}",
            self.coordinates,
            coords.join(", "),
            self.independent.len(),
            independent.join(", "),
            self.reduced.order
        );
        out.push_str(&p.definitions(a, Style::Text));
        let inputs = &a.names().inputs;
        if !inputs.is_empty() {
            // Set from outside between steps; `u'` is an input's rate on a
            // segment (0 when held).
            let _ = writeln!(out, "inputs: {}", inputs.join(", "));
        }
        if !self.lets.is_empty() {
            out.push_str("\nlets:\n");
            for (name, value) in &self.lets {
                let parts: Vec<String> = value.iter().map(|&e| sum(a, e, Style::Text, p)).collect();
                let shown = if parts.len() == 1 {
                    parts[0].clone()
                } else {
                    format!("({})", parts.join(", "))
                };
                let _ = writeln!(out, "  {name} = {shown}");
            }
        }
        if !self.holonomic.is_empty() {
            let times = if self.k == 1 { "once" } else { "k times" };
            let _ = writeln!(
                out,
                "\nholonomic constraints (kept at position level), differentiated {times}:"
            );
            for &(f, h) in &self.holonomic {
                let f = sum(a, f, Style::Text, p);
                let h = sum(a, h, Style::Text, p);
                let _ = writeln!(out, "  {f} = 0");
                let _ = writeln!(out, "    D^{}: {h} = 0", self.k);
            }
        }
        if !self.raised.is_empty() {
            let _ = writeln!(
                out,
                "\nconstraints not linear in their candidates (kept as written), differentiated once:"
            );
            for &(f, h) in &self.raised {
                let f = sum(a, f, Style::Text, p);
                let h = sum(a, h, Style::Text, p);
                let _ = writeln!(out, "  {f} = 0");
                let _ = writeln!(out, "    D: {h} = 0");
            }
        }
        if !self.constraints.is_empty() {
            out.push_str("\nconstraints:\n");
            for &(d, phi) in &self.constraints {
                let lhs = a.symbol_name(jet(d, self.k));
                let rhs = sum(a, phi, Style::Text, p);
                let _ = writeln!(out, "  {lhs} = {rhs}");
            }
        }
        if !self.state_laws.is_empty() {
            out.push_str(
                "\nmass laws of the state (frozen in L and (4); their rates M' along the \
                 motion in the reactive forces; their laws in (7)):\n",
            );
            for (m, law, rate) in self.state_law_rates(a, Style::Text, p) {
                let _ = writeln!(out, "  {m} = {law}");
                let _ = writeln!(out, "  {m}' = {rate}");
            }
        }
        out.push_str("\nequations (4):\n");
        for eq in &self.equations {
            let lhs = sum(a, eq.lhs, Style::Text, p);
            let rhs = sum(a, eq.rhs, Style::Text, p);
            let _ = writeln!(out, "  {}: {lhs} = {rhs}", coords[eq.coord as usize]);
        }
        let divided: Vec<String> = self
            .equations
            .iter()
            .zip(&self.divided_out)
            .filter_map(|(eq, m)| {
                m.map(|m| {
                    format!(
                        "{} from the equation of {}",
                        a.symbol_name(Symbol::Mass(m)),
                        coords[eq.coord as usize]
                    )
                })
            })
            .collect();
        if !divided.is_empty() {
            let _ = writeln!(out, "\nmasses divided out: {}", divided.join("; "));
        }
        self.write_reduced(a, &mut out, Style::Text, p);
        let state: Vec<String> = self
            .reduced
            .state
            .iter()
            .map(|&s| a.symbol_name(s))
            .collect();
        let _ = writeln!(out, "\nstate x = ({})", state.join(", "));
        if !self.reduced.mass_laws.is_empty() {
            out.push_str("mass laws still in the system:\n");
            for &(i, law) in &self.reduced.mass_laws {
                let _ = writeln!(
                    out,
                    "  {} = {}",
                    a.symbol_name(Symbol::Mass(i)),
                    a.display(law)
                );
            }
        }
        // Another mode of an implicit constraint (`lagc derive` shows every
        // mode's system) starts from the first mode's initial values.
        if !self.reduced.initial.is_empty() {
            out.push_str("initial values at t0:\n");
        }
        for (&s, value) in self.reduced.state.iter().zip(&self.reduced.initial) {
            let what = match value {
                InitialValue::Given(e) => format!("{}", a.display(*e)),
                InitialValue::Constraint(e) => {
                    format!("{}  (fixed by the constraints)", sum(a, *e, Style::Text, p))
                }
                InitialValue::Solved => "solved from (4) at t0".to_string(),
            };
            let _ = writeln!(out, "  {} = {what}", a.symbol_name(s));
        }
        for stage in &self.reduced.consistency {
            let names: Vec<String> = stage.unknowns.iter().map(|&z| a.symbol_name(z)).collect();
            let _ = writeln!(out, "consistency at t0 for {}:", names.join(", "));
            match &stage.explicit {
                Some(solution) => {
                    for (&z, &e) in stage.unknowns.iter().zip(solution) {
                        let rhs = sum(a, e, Style::Text, p);
                        let _ = writeln!(out, "  {} = {rhs}", a.symbol_name(z));
                    }
                }
                None => {
                    for &r in &stage.residual {
                        let rhs = sum(a, r, Style::Text, p);
                        let _ = writeln!(out, "  0 = {rhs}");
                    }
                }
            }
        }
        out
    }

    /// The equations as a LaTeX `align*` block.
    pub fn latex(&self) -> String {
        format!("\\begin{{align*}}\n{}\\end{{align*}}\n", self.latex_lines())
    }

    /// The lines of [`Derivation::latex`] without the environment, for
    /// more lines (the field method's) to follow in one block.
    pub fn latex_lines(&self) -> String {
        let mut arena = self.arena.clone();
        let mut first = Printer::collecting();
        first.prepare(&mut arena, &self.bulk());
        self.latex_lines_with(&mut arena, &mut first);
        let prefix = name_prefix(&arena, &self.lets);
        let mut second = first.printing(&arena, &prefix);
        let lines = self.latex_lines_with(&mut arena, &mut second);
        second.definitions(&arena, Style::Latex) + &lines
    }

    fn latex_lines_with(&self, a: &mut Arena, p: &mut Printer) -> String {
        let mut out = String::new();
        for (name, value) in &self.lets {
            let parts: Vec<String> = value.iter().map(|&e| sum(a, e, Style::Latex, p)).collect();
            let shown = if parts.len() == 1 {
                parts[0].clone()
            } else {
                format!("\\left({}\\right)", parts.join(",\\ "))
            };
            let lhs = format!("\\mathit{{{name}}}");
            out.push_str(&crate::latex::equation(&lhs, &shown, "\\text{let}"));
        }
        for &(f, h) in &self.raised {
            let f = sum(a, f, Style::Latex, p);
            let h = sum(a, h, Style::Latex, p);
            out.push_str(&crate::latex::equation(&f, "0", "\\text{kept as written}"));
            out.push_str(&crate::latex::equation(&h, "0", "\\text{its derivative}"));
        }
        for &(f, h) in &self.holonomic {
            let f = sum(a, f, Style::Latex, p);
            let h = sum(a, h, Style::Latex, p);
            out.push_str(&crate::latex::equation(&f, "0", "\\text{holonomic}"));
            out.push_str(&crate::latex::equation(
                &h,
                "0",
                &format!("\\text{{its derivative of order {}}}", self.k),
            ));
        }
        for &(d, phi) in &self.constraints {
            let lhs = name(a, jet(d, self.k), Style::Latex);
            let rhs = sum(a, phi, Style::Latex, p);
            out.push_str(&crate::latex::equation(&lhs, &rhs, "\\text{constraint}"));
        }
        for (m, law, rate) in self.state_law_rates(a, Style::Latex, p) {
            out.push_str(&crate::latex::equation(&m, &law, "\\text{mass law}"));
            out.push_str(&crate::latex::equation(
                &format!("{m}'"),
                &rate,
                "\\text{along the motion}",
            ));
        }
        for eq in &self.equations {
            let lhs = sum(a, eq.lhs, Style::Latex, p);
            let rhs = sum(a, eq.rhs, Style::Latex, p);
            let q = name(a, jet(eq.coord, 0), Style::Latex);
            out.push_str(&crate::latex::equation(
                &lhs,
                &rhs,
                &format!("\\text{{(4) for }} {q}"),
            ));
        }
        self.write_reduced(a, &mut out, Style::Latex, p);
        out
    }

    /// `(M, law, Ṁ)` for every mass law of the state: `Ṁ = ∂M/∂t +
    /// Σ ∂M/∂q_j q_j'`, the rate the reactive forces use.
    fn state_law_rates(
        &self,
        a: &mut Arena,
        style: Style,
        p: &mut Printer,
    ) -> Vec<(String, String, String)> {
        self.state_laws
            .iter()
            .map(|&(i, law)| {
                let rate = super::reactive_forces::rate_along_motion(a, law);
                (
                    name(a, Symbol::Mass(i), style),
                    sum(a, law, style, p),
                    sum(a, rate, style, p),
                )
            })
            .collect()
    }

    fn write_reduced(&self, a: &mut Arena, out: &mut String, style: Style, p: &mut Printer) {
        let u = self.reduced.order;
        match (&self.reduced.highest, style) {
            (Highest::Explicit(exprs), Style::Text) => {
                out.push_str("\nreduced system (7), explicit:\n");
                for (j, &e) in exprs.iter().enumerate() {
                    let rhs = sum(a, e, style, p);
                    let _ = writeln!(out, "  {} = {rhs}", a.symbol_name(jet(j as u32, u)));
                }
            }
            (Highest::Explicit(exprs), Style::Latex) => {
                for (j, &e) in exprs.iter().enumerate() {
                    let rhs = sum(a, e, style, p);
                    let lhs = name(a, jet(j as u32, u), style);
                    out.push_str(&crate::latex::equation(&lhs, &rhs, "\\text{(7)}"));
                }
            }
            (
                Highest::Implicit {
                    unknowns,
                    residual,
                    linear,
                    dependent,
                    ..
                },
                _,
            ) => {
                let names: Vec<String> = unknowns.iter().map(|&z| name(a, z, style)).collect();
                let how = if *linear {
                    "one linear solve"
                } else {
                    "Newton with the symbolic Jacobian"
                };
                if style == Style::Text {
                    let _ = writeln!(
                        out,
                        "\nreduced system (7), implicit in {} ({how}):",
                        names.join(", ")
                    );
                }
                for &r in residual {
                    let rhs = sum(a, r, style, p);
                    match style {
                        Style::Text => {
                            let _ = writeln!(out, "  0 = {rhs}");
                        }
                        Style::Latex => {
                            let tag = format!("\\text{{(7), {how}}}");
                            out.push_str(&crate::latex::equation("0", &rhs, &tag));
                        }
                    }
                }
                for &(d, e) in dependent {
                    let rhs = sum(a, e, style, p);
                    let lhs = name(a, jet(d, u), style);
                    match style {
                        Style::Text => {
                            let _ = writeln!(out, "  {lhs} = {rhs}");
                        }
                        Style::Latex => {
                            out.push_str(&crate::latex::equation(&lhs, &rhs, "\\text{(7)}"));
                        }
                    }
                }
            }
        }
    }
}

impl Derivation {
    /// The resets of `model`'s `when` statements (SPEC §2.3) as text
    /// lines: each condition, the new values (read from the state before
    /// the impact), and the derivatives the constraints fix, recomputed
    /// from the new state. Empty without `when`.
    pub fn impacts_text(&self, model: &crate::check::model::Model) -> String {
        self.impact_lines(model, Style::Text)
    }

    /// [`Derivation::impacts_text`] as LaTeX lines (`y'^{+}` the value
    /// after the impact).
    pub fn impacts_latex_lines(&self, model: &crate::check::model::Model) -> String {
        self.impact_lines(model, Style::Latex)
    }

    fn impact_lines(&self, model: &crate::check::model::Model, style: Style) -> String {
        let mut out = String::new();
        if model.impacts.is_empty() {
            return out;
        }
        let mut arena = self.arena.clone();
        let a = &mut arena;
        let p = &mut Printer::plain();
        if style == Style::Text {
            out.push_str(
                "\nimpacts (at the event where the condition becomes true; every new value \
                 is read from the state before the impact):\n",
            );
        }
        for impact in &model.impacts {
            if style == Style::Text {
                let _ = writeln!(out, "  when {}:", impact.text);
            }
            for reset in &impact.resets {
                let value = crate::ir::lower(a, &reset.value, model);
                let rhs = sum(a, value, style, p);
                let lhs = name(a, jet(reset.coord as u32, reset.order), style);
                match style {
                    Style::Text => {
                        let _ = writeln!(out, "    {lhs} := {rhs}");
                    }
                    Style::Latex => {
                        let tag = format!("\\text{{when {}}}", latex_text(&impact.text));
                        out.push_str(&crate::latex::equation(
                            &format!("{{{lhs}}}^{{+}}"),
                            &rhs,
                            &tag,
                        ));
                    }
                }
            }
        }
        let fixed: Vec<(Symbol, ExprId)> = self
            .reduced
            .state
            .iter()
            .zip(&self.reduced.initial)
            .filter_map(|(&s, v)| match v {
                InitialValue::Constraint(e) => Some((s, *e)),
                _ => None,
            })
            .collect();
        if !fixed.is_empty() && style == Style::Text {
            out.push_str("  then, from the new state, what the constraints fix:\n");
        }
        for (s, e) in fixed {
            let rhs = sum(a, e, style, p);
            let lhs = name(a, s, style);
            match style {
                Style::Text => {
                    let _ = writeln!(out, "    {lhs} := {rhs}");
                }
                Style::Latex => {
                    out.push_str(&crate::latex::equation(
                        &format!("{{{lhs}}}^{{+}}"),
                        &rhs,
                        "\\text{after an impact}",
                    ));
                }
            }
        }
        out
    }
}

/// Plain text inside `\text{…}`: LaTeX's special characters escaped.
fn latex_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\\' => out.push_str("\\textbackslash{}"),
            '{' | '}' | '$' | '&' | '#' | '_' | '%' => {
                out.push('\\');
                out.push(c);
            }
            '^' => out.push_str("\\^{}"),
            '~' => out.push_str("\\~{}"),
            '<' => out.push_str("$<$"),
            '>' => out.push_str("$>$"),
            _ => out.push(c),
        }
    }
    out
}
