//! The linearization as text (`Display`), JSON and LaTeX.

use super::Linearization;
use lagc_runtime::summary::json_string;
use std::fmt::{self, Write};

/// `A`'s entries as expressions (`--symbolic`).
#[derive(Debug, Clone)]
pub struct Symbolic {
    /// `∂row/∂column = text` for every non-zero entry of an explicit row.
    pub entries: Vec<Entry>,
    /// The rows an implicit system gives (`z = ` the highest derivatives
    /// solving `G = 0`): `∂z/∂x = −G_z⁻¹ G_x`, its parts below.
    pub implicit_rows: Vec<String>,
    /// `∂G_r/∂z_c` and `∂G_r/∂x_c`, non-zero.
    pub implicit_parts: Vec<Entry>,
}

#[derive(Debug, Clone)]
pub struct Entry {
    pub row: String,
    pub column: String,
    pub text: String,
    pub latex: String,
}

/// A number as JSON (non-finite numbers cannot occur: they are errors).
fn num(v: f64) -> String {
    if v == 0.0 {
        // `-0.0` is a zero.
        "0.0".to_string()
    } else if v.is_finite() {
        format!("{v:?}")
    } else {
        "null".to_string()
    }
}

fn list<T>(items: &[T], f: impl Fn(&T) -> String) -> String {
    let parts: Vec<String> = items.iter().map(f).collect();
    format!("[{}]", parts.join(", "))
}

/// A number for the text tables: 6 significant digits, `0` for zero.
fn short(v: f64) -> String {
    if v == 0.0 {
        "0".to_string()
    } else if (1e-4..1e6).contains(&v.abs()) {
        let s = format!("{v:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
        if s == "-0" {
            "0".to_string()
        } else {
            s
        }
    } else {
        format!("{v:.5e}")
    }
}

impl Linearization {
    /// `{"state": […], "ignorable": […], "A": [[…]], "eigenvalues": [[re,
    /// im], …], "residual": […], …}` on one line; with `--symbolic`, `A`'s
    /// entries are strings (`"0"` where zero) and the implicit rows are
    /// named.
    pub fn json(&self) -> String {
        let mut out = String::from("{");
        let _ = write!(out, "\"state\": {}", list(&self.state, |s| json_string(s)));
        let _ = write!(
            out,
            ", \"ignorable\": {}",
            list(&self.ignorable, |(s, _)| json_string(s))
        );
        match &self.symbolic {
            None => {
                let _ = write!(
                    out,
                    ", \"A\": {}",
                    list(&self.a, |row| list(row, |&v| num(v)))
                );
            }
            Some(sym) => {
                let rows: Vec<String> = self
                    .state
                    .iter()
                    .map(|r| {
                        let rate = rate_of(r);
                        list(&self.state, |c| {
                            if sym.implicit_rows.contains(&rate) {
                                return json_string("implicit");
                            }
                            sym.entries
                                .iter()
                                .find(|e| e.row == rate && &e.column == c)
                                .map_or_else(|| json_string("0"), |e| json_string(&e.text))
                        })
                    })
                    .collect();
                let _ = write!(out, ", \"A\": [{}]", rows.join(", "));
                let _ = write!(
                    out,
                    ", \"implicit\": {}",
                    list(&sym.implicit_parts, |e| format!(
                        "[{}, {}, {}]",
                        json_string(&e.row),
                        json_string(&e.column),
                        json_string(&e.text)
                    ))
                );
            }
        }
        let _ = write!(
            out,
            ", \"eigenvalues\": {}",
            list(&self.eigenvalues, |e| format!(
                "[{}, {}]",
                num(e.re),
                num(e.im)
            ))
        );
        let _ = write!(out, ", \"residual\": {}", list(&self.residual, |&v| num(v)));
        let _ = write!(out, ", \"equilibrium\": {}", self.equilibrium);
        let _ = write!(out, ", \"t\": {}", num(self.t));
        let _ = write!(out, ", \"point\": {}", list(&self.point, |&v| num(v)));
        let _ = write!(
            out,
            ", \"ignorable_values\": {}",
            list(&self.ignorable, |(_, v)| num(*v))
        );
        let _ = write!(
            out,
            ", \"fixed\": {{{}}}",
            self.fixed
                .iter()
                .map(|(n, v)| format!("{}: {}", json_string(n), num(*v)))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let _ = write!(
            out,
            ", \"params\": {}",
            list(&self.params, |s| json_string(s))
        );
        let _ = write!(
            out,
            ", \"B_params\": {}",
            list(&self.b_params, |row| list(row, |&v| num(v)))
        );
        if !self.inputs.is_empty() {
            let _ = write!(
                out,
                ", \"inputs\": {}, \"B_inputs\": {}",
                list(&self.inputs, |s| json_string(s)),
                list(&self.b_inputs, |row| list(row, |&v| num(v)))
            );
        }
        out.push_str("}\n");
        out
    }

    /// An `align*` block: `A` as a `pmatrix` over the state (or its
    /// symbolic entries), the eigenvalues and the residual.
    pub fn latex(&self) -> String {
        let mut out = String::from("\\begin{align*}\n");
        let names: Vec<String> = self.state.iter().map(|s| latex_name(s)).collect();
        let _ = writeln!(
            out,
            "  x &= \\left({}\\right) && \\text{{the state}} \\\\",
            names.join(",\\ ")
        );
        match &self.symbolic {
            None => {
                let rows: Vec<String> = self
                    .a
                    .iter()
                    .map(|row| {
                        row.iter()
                            .map(|&v| latex_number(v))
                            .collect::<Vec<_>>()
                            .join(" & ")
                    })
                    .collect();
                let _ = writeln!(
                    out,
                    "  A &= \\begin{{pmatrix}} {} \\end{{pmatrix}} && \\text{{$\\partial f/\\partial x$}} \\\\",
                    rows.join(" \\\\ ")
                );
            }
            Some(sym) => {
                for e in &sym.entries {
                    let lhs = format!(
                        "\\frac{{\\partial {}}}{{\\partial {}}}",
                        latex_name(&e.row),
                        latex_name(&e.column)
                    );
                    out.push_str(&crate::latex::equation(&lhs, &e.latex, "\\text{of } A"));
                }
                for e in &sym.implicit_parts {
                    let lhs = format!(
                        "\\frac{{\\partial {}}}{{\\partial {}}}",
                        latex_name(&e.row),
                        latex_name(&e.column)
                    );
                    out.push_str(&crate::latex::equation(
                        &lhs,
                        &e.latex,
                        "\\text{implicit rows}",
                    ));
                }
            }
        }
        let eig: Vec<String> = self
            .eigenvalues
            .iter()
            .map(|e| {
                if e.im == 0.0 {
                    latex_number(e.re)
                } else {
                    let sign = if e.im < 0.0 { "-" } else { "+" };
                    format!(
                        "{} {sign} {} i",
                        latex_number(e.re),
                        latex_number(e.im.abs())
                    )
                }
            })
            .collect();
        if self.symbolic.is_none() {
            let _ = writeln!(
                out,
                "  \\lambda &\\in \\left\\{{{}\\right\\}} && \\text{{eigenvalues}} \\\\",
                eig.join(",\\ ")
            );
        }
        let res: Vec<String> = self.residual.iter().map(|&v| latex_number(v)).collect();
        let _ = writeln!(
            out,
            "  f &= \\left({}\\right) && \\text{{the residual}}",
            res.join(",\\ ")
        );
        out.push_str("\\end{align*}\n");
        out
    }
}

/// The rate of a state component's name: `th` → `th'`, `th'` → `th''`.
fn rate_of(name: &str) -> String {
    format!("{name}'")
}

fn latex_name(name: &str) -> String {
    let base = name.trim_end_matches('\'');
    let primes = name.len() - base.len();
    let letter = match base {
        "alpha" | "beta" | "gamma" | "delta" | "epsilon" | "zeta" | "eta" | "theta" | "iota"
        | "kappa" | "lambda" | "mu" | "nu" | "xi" | "pi" | "rho" | "sigma" | "tau" | "upsilon"
        | "phi" | "chi" | "psi" | "omega" => format!("\\{base}"),
        b if b.chars().count() == 1 => b.to_string(),
        b => format!("\\mathit{{{}}}", b.replace('_', "\\_")),
    };
    format!("{letter}{}", "'".repeat(primes))
}

fn latex_number(v: f64) -> String {
    let s = short(v);
    match s.split_once('e') {
        Some((m, e)) => format!("{m} \\cdot 10^{{{}}}", e.trim_start_matches('+')),
        None => s,
    }
}

impl fmt::Display for Linearization {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "linearization at t = {}", short(self.t))?;
        if let Some(mode) = &self.mode {
            writeln!(f, "reduced system: {mode}")?;
        }
        let point: Vec<String> = self
            .state
            .iter()
            .zip(&self.point)
            .map(|(n, v)| format!("{n} = {}", short(*v)))
            .collect();
        writeln!(f, "state x = ({})", self.state.join(", "))?;
        writeln!(f, "  at {}", point.join(", "))?;
        if !self.ignorable.is_empty() {
            let ig: Vec<String> = self
                .ignorable
                .iter()
                .map(|(n, v)| format!("{n} = {}", short(*v)))
                .collect();
            writeln!(
                f,
                "ignorable (no right side contains them; left out): {}",
                ig.join(", ")
            )?;
        }
        if !self.fixed.is_empty() {
            let fx: Vec<String> = self
                .fixed
                .iter()
                .map(|(n, v)| format!("{n} = {}", short(*v)))
                .collect();
            writeln!(
                f,
                "fixed by the constraints (eliminated: they move with the state along the constraints): {}",
                fx.join(", ")
            )?;
        }
        match &self.symbolic {
            None => {
                writeln!(f, "\nA = ∂f/∂x (rows: the rates of x; columns: x):")?;
                let cells: Vec<Vec<String>> = self
                    .a
                    .iter()
                    .map(|row| row.iter().map(|&v| short(v)).collect())
                    .collect();
                let width = cells
                    .iter()
                    .flatten()
                    .map(|s| s.chars().count())
                    .chain(self.state.iter().map(|s| s.chars().count()))
                    .max()
                    .unwrap_or(1);
                let label = self
                    .state
                    .iter()
                    .map(|s| rate_of(s).chars().count())
                    .max()
                    .unwrap_or(1);
                write!(f, "  {:label$} ", "")?;
                for s in &self.state {
                    write!(f, " {s:>width$}")?;
                }
                writeln!(f)?;
                for (s, row) in self.state.iter().zip(&cells) {
                    write!(f, "  {:label$} ", rate_of(s))?;
                    for c in row {
                        write!(f, " {c:>width$}")?;
                    }
                    writeln!(f)?;
                }
                writeln!(f, "\neigenvalues (frequency |Im λ|, natural frequency |λ|, damping ratio −Re λ/|λ|):")?;
                // Parts below A's rounding (a few ε·‖A‖) are shown as 0:
                // a zero eigenvalue comes out of the Schur form as ±1e-16.
                let norm = self.a.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
                let floor = 64.0 * f64::EPSILON * norm * self.a.len().max(1) as f64;
                let clean = |v: f64| if v.abs() <= floor { 0.0 } else { v };
                for e in &self.eigenvalues {
                    let e = super::Eigenvalue {
                        re: clean(e.re),
                        im: clean(e.im),
                    };
                    let damping = e.damping_ratio().map_or_else(|| "-".to_string(), short);
                    writeln!(
                        f,
                        "  {:>13} {:>+14}i   frequency {:<12} natural {:<12} damping {}",
                        short(e.re),
                        short(e.im),
                        short(e.frequency()),
                        short(e.natural_frequency()),
                        damping
                    )?;
                }
                let unstable = self.eigenvalues.iter().any(|e| clean(e.re) > 0.0);
                if unstable {
                    writeln!(f, "  an eigenvalue has a positive real part: unstable")?;
                }
            }
            Some(sym) => {
                writeln!(
                    f,
                    "\nA = ∂f/∂x, its non-zero entries (values given on the command line substituted):"
                )?;
                for e in &sym.entries {
                    writeln!(f, "  ∂{}/∂{} = {}", e.row, e.column, e.text)?;
                }
                if !sym.implicit_rows.is_empty() {
                    writeln!(
                        f,
                        "  rows {}: implicit, ∂z/∂x = −G_z⁻¹ G_x with the highest derivatives z solving G = 0:",
                        sym.implicit_rows.join(", ")
                    )?;
                    for e in &sym.implicit_parts {
                        writeln!(f, "    ∂{}/∂{} = {}", e.row, e.column, e.text)?;
                    }
                }
            }
        }
        if !self.params.is_empty() && self.symbolic.is_none() {
            writeln!(f, "\n∂f/∂p (columns: {}):", self.params.join(", "))?;
            for (s, row) in self.state.iter().zip(&self.b_params) {
                let cells: Vec<String> = row.iter().map(|&v| short(v)).collect();
                writeln!(f, "  {}: {}", rate_of(s), cells.join(", "))?;
            }
        }
        if !self.inputs.is_empty() && self.symbolic.is_none() {
            writeln!(
                f,
                "\n∂f/∂u (columns: {}; the inputs held at their values):",
                self.inputs.join(", ")
            )?;
            for (s, row) in self.state.iter().zip(&self.b_inputs) {
                let cells: Vec<String> = row.iter().map(|&v| short(v)).collect();
                writeln!(f, "  {}: {}", rate_of(s), cells.join(", "))?;
            }
        }
        let res: Vec<String> = self.residual.iter().map(|&v| short(v)).collect();
        writeln!(f, "\nresidual f = ({})", res.join(", "))?;
        let moving = self.ignorable.iter().any(|(n, _)| {
            // An ignorable coordinate moves when its velocity is non-zero.
            let v = format!("{n}'");
            self.state
                .iter()
                .zip(&self.point)
                .any(|(s, &x)| *s == v && x != 0.0)
        });
        if self.equilibrium && moving {
            writeln!(
                f,
                "a steady motion: f = 0 to rounding (the ignorable coordinates move at constant rates)"
            )
        } else if self.equilibrium {
            writeln!(f, "an equilibrium: f = 0 to rounding")
        } else {
            let (i, v) = self
                .residual
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
                .map_or((0, 0.0), |(i, v)| (i, *v));
            let name = self.state.get(i).map(|s| rate_of(s)).unwrap_or_default();
            writeln!(
                f,
                "not an equilibrium: the largest |f| is {} ({name})",
                short(v.abs())
            )
        }
    }
}
