//! The text form of expressions (`M*t*q1' + M*(1 + t^2)*q1''`) and a simple
//! LaTeX form. Both are deterministic: they follow the canonical order.
//!
//! A product is written as numerator over denominator (factors with a
//! negative numeric exponent go below the bar); a sum writes a negative term
//! as `a - b`; `x^(1/2)` is written `sqrt(x)`.

use super::expr::{Arena, ExprId, Node, Symbol};
use super::shared::SharedNames;
use crate::syntax::ast::Func;
use std::fmt;

/// Binding strength of the context a sub-expression is written in.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Prec {
    Sum,
    Product,
    Power,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Style {
    Text,
    Latex,
}

/// An exponent as written: a number or an expression.
#[derive(Clone, Copy)]
enum Exponent {
    Number(f64),
    Expr(ExprId),
}

/// `Display` adapter returned by [`Arena::display`].
pub struct ExprDisplay<'a> {
    arena: &'a Arena,
    e: ExprId,
}

impl fmt::Display for ExprDisplay<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut out = String::new();
        Writer::new(self.arena, Style::Text).expr(self.e, Prec::Sum, &mut out);
        f.write_str(&out)
    }
}

impl Arena {
    pub fn display(&self, e: ExprId) -> ExprDisplay<'_> {
        ExprDisplay { arena: self, e }
    }

    pub fn latex(&self, e: ExprId) -> String {
        let mut out = String::new();
        Writer::new(self, Style::Latex).expr(e, Prec::Sum, &mut out);
        out
    }

    /// The text of `e` with every node that `names` names written as its
    /// name (`e` too, when it has one).
    pub fn display_named(&self, e: ExprId, names: &SharedNames) -> String {
        self.write_named(e, names, Style::Text, None)
    }

    /// [`Arena::display_named`] in LaTeX; a name `w3` is written `w_{3}`.
    pub fn latex_named(&self, e: ExprId, names: &SharedNames) -> String {
        self.write_named(e, names, Style::Latex, None)
    }

    /// The definition of a named node: `e` written out, its named parts as
    /// their names; LaTeX when `latex`.
    pub fn definition(&self, e: ExprId, names: &SharedNames, latex: bool) -> String {
        let style = if latex { Style::Latex } else { Style::Text };
        self.write_named(e, names, style, Some(e))
    }

    fn write_named(
        &self,
        e: ExprId,
        names: &SharedNames,
        style: Style,
        top: Option<ExprId>,
    ) -> String {
        let mut out = String::new();
        Writer::named(self, style, names, top).expr(e, Prec::Sum, &mut out);
        out
    }

    /// The text name of a symbol (`t`, `alpha`, `q1''`, `q1^(4)`, `f_2`).
    pub fn symbol_name(&self, s: Symbol) -> String {
        match s {
            Symbol::Time => "t".to_string(),
            Symbol::Param(i) => name_or(&self.names.params, i, "p"),
            Symbol::Mass(i) => name_or(&self.names.masses, i, "m"),
            Symbol::Input(i) => name_or(&self.names.inputs, i, "u"),
            Symbol::InputRate(i) => format!("{}'", name_or(&self.names.inputs, i, "u")),
            Symbol::Aux(i) => self
                .aux_name(i)
                .map_or_else(|| format!("aux{i}"), str::to_string),
            Symbol::Jet { coord, order } => {
                let q = name_or(&self.names.coords, coord, "q");
                match order {
                    0..=3 => format!("{q}{}", "'".repeat(order as usize)),
                    _ => format!("{q}^({order})"),
                }
            }
        }
    }

    fn symbol_latex(&self, s: Symbol) -> String {
        match s {
            Symbol::Time => "t".to_string(),
            Symbol::Param(i) => latex_name(&name_or(&self.names.params, i, "p")),
            Symbol::Mass(i) => latex_name(&name_or(&self.names.masses, i, "m")),
            Symbol::Input(i) => latex_name(&name_or(&self.names.inputs, i, "u")),
            Symbol::InputRate(i) => {
                format!(
                    "\\dot{{{}}}",
                    latex_name(&name_or(&self.names.inputs, i, "u"))
                )
            }
            Symbol::Aux(i) => latex_name(&self.symbol_name(Symbol::Aux(i))),
            Symbol::Jet { coord, order } => {
                let q = latex_name(&name_or(&self.names.coords, coord, "q"));
                match order {
                    0..=3 => format!("{q}{}", "'".repeat(order as usize)),
                    _ => format!("{q}^{{({order})}}"),
                }
            }
        }
    }
}

fn name_or(names: &[String], i: u32, prefix: &str) -> String {
    names
        .get(i as usize)
        .cloned()
        .unwrap_or_else(|| format!("{prefix}{i}"))
}

/// Greek letters LaTeX has commands for (the capitals that look like Latin
/// ones, `Alpha`, `Beta`, …, have none).
const GREEK: [&str; 38] = [
    "alpha",
    "beta",
    "gamma",
    "delta",
    "epsilon",
    "varepsilon",
    "zeta",
    "eta",
    "theta",
    "vartheta",
    "iota",
    "kappa",
    "lambda",
    "mu",
    "nu",
    "xi",
    "pi",
    "rho",
    "sigma",
    "tau",
    "upsilon",
    "phi",
    "varphi",
    "chi",
    "psi",
    "omega",
    "Gamma",
    "Delta",
    "Theta",
    "Lambda",
    "Xi",
    "Pi",
    "Sigma",
    "Upsilon",
    "Phi",
    "Psi",
    "Omega",
    "ell",
];

/// `alpha` → `\alpha`, `q1` → `q_{1}`, `M0` → `M_{0}`, `x_max` → `x_{max}`,
/// other multi-letter names upright.
fn latex_name(name: &str) -> String {
    // `f1'`: the name's primes follow its LaTeX form.
    let primes = name.len() - name.trim_end_matches('\'').len();
    if primes > 0 {
        return format!(
            "{}{}",
            latex_name(&name[..name.len() - primes]),
            "'".repeat(primes)
        );
    }
    let (stem, sub) = match name.split_once('_') {
        Some((stem, sub)) if !stem.is_empty() && !sub.is_empty() => (stem, sub),
        _ => {
            let split = name.trim_end_matches(|c: char| c.is_ascii_digit()).len();
            let split = if split == 0 { name.len() } else { split };
            (&name[..split], &name[split..])
        }
    };
    let stem = if GREEK.contains(&stem) {
        format!("\\{stem}")
    } else if stem.chars().count() > 1 {
        format!("\\mathrm{{{}}}", stem.replace('_', "\\_"))
    } else {
        stem.to_string()
    };
    if sub.is_empty() {
        stem
    } else {
        format!("{stem}_{{{}}}", sub.replace('_', "\\_"))
    }
}

/// `w3` as `w_{3}`: the prefix upright-italic, the number a subscript.
fn latex_shared_name(name: &str) -> String {
    let digits = name.trim_start_matches(|c: char| !c.is_ascii_digit());
    let prefix = &name[..name.len() - digits.len()];
    format!("{prefix}_{{{digits}}}")
}

fn number(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        format!("{v:?}")
    }
}

struct Writer<'a> {
    arena: &'a Arena,
    style: Style,
    /// Nodes written as their names (none by default).
    names: Option<&'a SharedNames>,
    /// The node being defined: written out even when it has a name.
    top: Option<ExprId>,
}

impl<'a> Writer<'a> {
    fn new(arena: &'a Arena, style: Style) -> Writer<'a> {
        Writer {
            arena,
            style,
            names: None,
            top: None,
        }
    }

    fn named(
        arena: &'a Arena,
        style: Style,
        names: &'a SharedNames,
        top: Option<ExprId>,
    ) -> Writer<'a> {
        Writer {
            arena,
            style,
            names: Some(names),
            top,
        }
    }

    /// The name `e` is written as, if any.
    fn name_of(&self, e: ExprId) -> Option<String> {
        if self.top == Some(e) {
            return None;
        }
        let name = self.names?.get(e)?;
        Some(match self.style {
            Style::Text => name.to_string(),
            Style::Latex => latex_shared_name(name),
        })
    }

    fn open(&self, out: &mut String) {
        out.push_str(match self.style {
            Style::Text => "(",
            Style::Latex => "\\left(",
        });
    }

    fn close(&self, out: &mut String) {
        out.push_str(match self.style {
            Style::Text => ")",
            Style::Latex => "\\right)",
        });
    }

    fn expr(&self, e: ExprId, ctx: Prec, out: &mut String) {
        self.term(e, ctx, false, out);
    }

    /// Writes `e` (or `−e` when `flip`) in context `ctx`.
    fn term(&self, e: ExprId, ctx: Prec, flip: bool, out: &mut String) {
        if let Some(name) = self.name_of(e) {
            if flip {
                out.push('-');
            }
            out.push_str(&name);
            return;
        }
        match self.arena.node(e) {
            Node::Const(v) => {
                let v = if flip { -v } else { *v };
                let parens = v < 0.0 && ctx > Prec::Sum;
                if parens {
                    self.open(out);
                }
                out.push_str(&number(v));
                if parens {
                    self.close(out);
                }
            }
            Node::Sym(s) => out.push_str(&match self.style {
                Style::Text => self.arena.symbol_name(*s),
                Style::Latex => self.arena.symbol_latex(*s),
            }),
            Node::Add(ts) => {
                let parens = ctx > Prec::Sum;
                if parens {
                    self.open(out);
                }
                for (i, &t) in ts.iter().enumerate() {
                    let negative = self.is_negative(t);
                    if i > 0 {
                        out.push_str(if negative { " - " } else { " + " });
                        self.term(t, Prec::Sum, negative, out);
                    } else {
                        self.term(t, Prec::Sum, false, out);
                    }
                }
                if parens {
                    self.close(out);
                }
            }
            Node::Mul(fs) => self.product(fs, ctx, flip, out),
            // A lone power is a one-factor product: `1/x^2`, `sqrt(x)`.
            Node::Pow(..) => self.product(&[e], ctx, flip, out),
            Node::Func(f, a) => {
                if flip {
                    out.push('-');
                }
                self.func(*f, *a, out);
            }
            Node::Select(g, a, b) => {
                if flip {
                    out.push('-');
                }
                self.select(*g, *a, *b, out);
            }
        }
    }

    /// `(if g < 0 then a else b)`; in LaTeX a `cases` block.
    fn select(&self, g: ExprId, a: ExprId, b: ExprId, out: &mut String) {
        match self.style {
            Style::Text => {
                out.push_str("(if ");
                self.expr(g, Prec::Sum, out);
                out.push_str(" < 0 then ");
                self.expr(a, Prec::Sum, out);
                out.push_str(" else ");
                self.expr(b, Prec::Sum, out);
                out.push(')');
            }
            Style::Latex => {
                out.push_str("\\begin{cases}");
                self.expr(a, Prec::Sum, out);
                out.push_str(" & ");
                self.expr(g, Prec::Sum, out);
                out.push_str(" < 0 \\\\ ");
                self.expr(b, Prec::Sum, out);
                out.push_str(" & \\text{otherwise}\\end{cases}");
            }
        }
    }

    fn is_negative(&self, e: ExprId) -> bool {
        if self.name_of(e).is_some() {
            return false;
        }
        match self.arena.node(e) {
            Node::Const(v) => *v < 0.0,
            Node::Mul(fs) => self.arena.as_const(fs[0]).is_some_and(|c| c < 0.0),
            _ => false,
        }
    }

    /// A product `c · Π num / Π den`, negated when `flip`.
    fn product(&self, fs: &[ExprId], ctx: Prec, flip: bool, out: &mut String) {
        let mut c = 1.0;
        let mut num: Vec<(ExprId, Exponent)> = Vec::new();
        let mut den: Vec<(ExprId, Exponent)> = Vec::new();
        for &f in fs {
            match self.arena.node(f) {
                Node::Const(v) => c *= v,
                Node::Pow(b, x) => match self.arena.as_const(*x) {
                    Some(k) if k < 0.0 => den.push((*b, Exponent::Number(-k))),
                    Some(k) => num.push((*b, Exponent::Number(k))),
                    None => num.push((*b, Exponent::Expr(*x))),
                },
                _ => num.push((f, Exponent::Number(1.0))),
            }
        }
        if flip {
            c = -c;
        }
        let negative = c < 0.0;
        let c = c.abs();
        let parens = ctx >= Prec::Power || (negative && ctx > Prec::Sum);
        if parens {
            self.open(out);
        }
        if negative {
            out.push('-');
        }
        let mut top = String::new();
        if c != 1.0 || num.is_empty() {
            top.push_str(&number(c));
        }
        for &(b, x) in &num {
            let mut factor = String::new();
            self.power(b, x, Prec::Product, &mut factor);
            if !top.is_empty() {
                top.push_str(match self.style {
                    Style::Text => "*",
                    Style::Latex if factor.starts_with(|ch: char| ch.is_ascii_digit()) => {
                        " \\cdot "
                    }
                    Style::Latex => " ",
                });
            }
            top.push_str(&factor);
        }
        if den.is_empty() {
            out.push_str(&top);
        } else {
            let mut bottom = String::new();
            for (i, &(b, x)) in den.iter().enumerate() {
                if i > 0 {
                    bottom.push_str(if self.style == Style::Text { "*" } else { " " });
                }
                self.power(b, x, Prec::Product, &mut bottom);
            }
            match self.style {
                Style::Text => {
                    out.push_str(&top);
                    out.push('/');
                    if den.len() > 1 {
                        out.push('(');
                        out.push_str(&bottom);
                        out.push(')');
                    } else {
                        out.push_str(&bottom);
                    }
                }
                Style::Latex => {
                    out.push_str(&format!("\\frac{{{top}}}{{{bottom}}}"));
                }
            }
        }
        if parens {
            self.close(out);
        }
    }

    /// `base^exp` with a non-negative or symbolic exponent.
    fn power(&self, base: ExprId, exp: Exponent, ctx: Prec, out: &mut String) {
        match exp {
            Exponent::Number(1.0) => self.expr(base, ctx, out),
            Exponent::Number(0.5) => {
                match self.style {
                    Style::Text => out.push_str("sqrt("),
                    Style::Latex => out.push_str("\\sqrt{"),
                }
                self.expr(base, Prec::Sum, out);
                out.push(if self.style == Style::Text { ')' } else { '}' });
            }
            _ => {
                let mut b = String::new();
                self.expr(base, Prec::Power, &mut b);
                // A derivative as a base: `{q'}^{2}`, and `{q^{(4)}}^{2}`
                // (TeX refuses a double superscript); `(q^(4))^2` in text,
                // where `q^(4)^2` would read as a power of a power.
                let higher = matches!(
                    self.arena.node(base),
                    Node::Sym(Symbol::Jet { order, .. }) if *order > 3
                );
                match self.style {
                    Style::Latex if higher || b.ends_with('\'') => b = format!("{{{b}}}"),
                    Style::Text if higher => b = format!("({b})"),
                    _ => {}
                }
                out.push_str(&b);
                out.push('^');
                match (exp, self.style) {
                    (Exponent::Number(k), Style::Text) => out.push_str(&number(k)),
                    (Exponent::Number(k), Style::Latex) => {
                        out.push_str(&format!("{{{}}}", number(k)))
                    }
                    (Exponent::Expr(x), Style::Text) => self.expr(x, Prec::Power, out),
                    (Exponent::Expr(x), Style::Latex) => {
                        out.push('{');
                        self.expr(x, Prec::Sum, out);
                        out.push('}');
                    }
                }
            }
        }
    }

    fn func(&self, f: Func, a: ExprId, out: &mut String) {
        match self.style {
            Style::Text => {
                out.push_str(f.name());
                out.push('(');
                self.expr(a, Prec::Sum, out);
                out.push(')');
            }
            Style::Latex if f == Func::Exp => {
                out.push_str("e^{");
                self.expr(a, Prec::Sum, out);
                out.push('}');
            }
            Style::Latex => {
                out.push_str(match f {
                    Func::Asin => "\\arcsin",
                    Func::Acos => "\\arccos",
                    Func::Atan => "\\arctan",
                    Func::Sin => "\\sin",
                    Func::Cos => "\\cos",
                    Func::Tan => "\\tan",
                    Func::Sinh => "\\sinh",
                    Func::Cosh => "\\cosh",
                    Func::Tanh => "\\tanh",
                    Func::Exp => "\\exp",
                    Func::Ln => "\\ln",
                    Func::Sqrt => "\\sqrt",
                });
                self.open(out);
                self.expr(a, Prec::Sum, out);
                self.close(out);
            }
        }
    }
}
