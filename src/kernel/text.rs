//! The kernel's text form: every expression the generated crate
//! evaluates, for snapshots and for reading.

use super::{Kernel, Motion};
use std::fmt;

impl fmt::Display for Kernel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = &self.arena;
        let name = |i: usize| a.symbol_name(self.state[i]);
        writeln!(
            f,
            "state: {}",
            (0..self.state.len())
                .map(name)
                .collect::<Vec<_>>()
                .join(", ")
        )?;
        for p in &self.params {
            writeln!(f, "param {} = {}", p.name, a.display(p.value))?;
        }
        for (name, default) in &self.inputs {
            writeln!(f, "input {name} = {default:?}")?;
        }
        for (i, (m, law)) in self.masses.iter().enumerate() {
            let args = if self.state_laws.contains(&(i as u32)) {
                "t, q"
            } else {
                "t"
            };
            writeln!(f, "mass {m}({args}) = {}", a.display(*law))?;
        }
        writeln!(
            f,
            "time {} .. {}",
            a.display(self.time_span.0),
            a.display(self.time_span.1)
        )?;
        match &self.motion {
            Motion::Explicit(e) => {
                for (j, &h) in e.rhs.iter().enumerate() {
                    writeln!(
                        f,
                        "X[{}] = {}",
                        name(self.highest_row(j as u32)),
                        a.display(h)
                    )?;
                }
                for &(r, c, d) in &e.jacobian {
                    writeln!(f, "∂X[{}]/∂{} = {}", name(r), name(c), a.display(d))?;
                }
                for &(r, d) in &e.time_partial {
                    writeln!(f, "∂X[{}]/∂t = {}", name(r), a.display(d))?;
                }
            }
            Motion::Implicit(i) => {
                let z: Vec<String> = i.unknowns.iter().map(|&s| a.symbol_name(s)).collect();
                writeln!(
                    f,
                    "solve G = 0 for {} ({})",
                    z.join(", "),
                    if i.linear { "linear" } else { "Newton" }
                )?;
                for (r, &g) in i.residual.iter().enumerate() {
                    writeln!(f, "G{r} = {}", a.display(g))?;
                }
                for &(r, c, d) in &i.g_z {
                    writeln!(f, "∂G{r}/∂{} = {}", z[c], a.display(d))?;
                }
                for &(r, c, d) in &i.g_x {
                    writeln!(f, "∂G{r}/∂{} = {}", name(c), a.display(d))?;
                }
                for &(r, d) in &i.g_t {
                    writeln!(f, "∂G{r}/∂t = {}", a.display(d))?;
                }
                for d in &i.dependent {
                    let row = name(self.highest_row(d.coord));
                    writeln!(f, "X[{row}] = {}", a.display(d.value))?;
                }
            }
        }
        for &(i, e) in &self.kept {
            writeln!(f, "kept {} = {}", name(i), a.display(e))?;
        }
        for &(i, j, d) in &self.kept_gradient {
            writeln!(f, "∂kept {}/∂{} = {}", name(i), name(j), a.display(d))?;
        }
        if let Some(c) = &self.coefficients {
            let kind = if c.linear { "linear" } else { "Riccati" };
            writeln!(f, "coefficient system ({kind}):")?;
            for (k, &r) in c.rhs.iter().enumerate() {
                writeln!(f, "  f{}' = {}", k + 1, a.display(r))?;
            }
        }
        for &(k, e) in &self.exact {
            writeln!(f, "exact {} = {}", name(k), a.display(e))?;
        }
        for impact in &self.impacts {
            writeln!(f, "when {} ({:?}):", impact.text, impact.condition)?;
            for &(k, e) in &impact.resets {
                writeln!(f, "  {} := {}", name(k), a.display(e))?;
            }
        }
        for &(k, e) in &self.constrained {
            writeln!(f, "after an impact {} := {}", name(k), a.display(e))?;
        }
        Ok(())
    }
}
