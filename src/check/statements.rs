//! Params, mass laws, the Lagrangian, forces, exact solutions and the time
//! span: the statements checked one by one.

use super::expressions::Allowed;
use super::model::{
    DeclaredIntegrator, Exact, Force, Input, IntegratorChoice, MassLaw, Name, Output, Param,
    TimeSpan,
};
use super::types::{type_mismatch, Ty, Uses};
use super::Checker;
use crate::diagnostic::{codes, Diagnostic};
use crate::span::Span;
use crate::syntax::ast::{Expr, ExprKind, Ident, ItemKind};

impl<'a> Checker<'a> {
    /// Checks each param against the params before it and computes its default.
    pub(super) fn params(&mut self) -> Vec<Param> {
        let mut params = Vec::new();
        for (item, _) in self.items() {
            let ItemKind::Param { name, value } = item else {
                continue;
            };
            let allowed = Allowed {
                params_before: params.len(),
                ..Allowed::constants("a param")
            };
            let errors_before = self.diagnostics.len();
            self.check_expr(value, allowed);
            let default = if self.diagnostics.len() == errors_before {
                self.evaluate_finite(value, &format!("the default of param `{}`", name.name))
            } else {
                None
            };
            self.param_defaults.push(default);
            params.push(Param {
                name: name.name.clone(),
                span: name.span,
                value: value.clone(),
                default: default.unwrap_or(f64::NAN),
                // Decided once every statement is checked (`tunable_params`).
                tunable: false,
            });
        }
        params
    }

    /// Checks each input's default: a number (no param: an input's value
    /// is the importer's, and a default that followed a param overridden
    /// at run time would be a second way to set it).
    pub(super) fn inputs(&mut self) -> Vec<Input> {
        let mut inputs = Vec::new();
        for (item, _) in self.items() {
            let ItemKind::Input { name, default } = item else {
                continue;
            };
            let errors_before = self.diagnostics.len();
            self.check_expr(default, Allowed::constants("an input's default"));
            let mut value = None;
            if self.diagnostics.len() == errors_before {
                let declared_pi = self.names.contains_key("pi");
                let constant = |n: &str| n == "pi" && !declared_pi;
                if let Some(used) = first_name(default, &constant) {
                    let diagnostic = Diagnostic::error(
                        codes::INPUT_NOT_ALLOWED,
                        format!("the default of input `{}` must be a number", name.name),
                    )
                    .with_primary(used.span, format!("`{}` used here", used.name))
                    .with_help("write the number; the input's value is set from outside");
                    self.report(diagnostic);
                } else {
                    value = self
                        .evaluate_finite(default, &format!("the default of input `{}`", name.name));
                }
            }
            inputs.push(Input {
                name: name.name.clone(),
                span: name.span,
                default: value.unwrap_or(f64::NAN),
            });
        }
        inputs
    }

    pub(super) fn masses(&mut self) -> Vec<MassLaw> {
        // A mass law may follow the configuration (SPEC §2.3: `rho * x`),
        // not the velocities (E0005, `mass_of_velocity`).
        let allowed = Allowed {
            time: true,
            coord_order: Some(0),
            order_code: codes::MASS_DEPENDS_ON_STATE,
            ..Allowed::constants("a mass law")
        };
        let mut masses = Vec::new();
        for (item, _) in self.items() {
            if let ItemKind::Mass { name, law } = item {
                self.check_expr(law, allowed);
                masses.push(MassLaw {
                    name: name.name.clone(),
                    span: name.span,
                    law: law.clone(),
                });
            }
        }
        masses
    }

    pub(super) fn lagrangian(&mut self) -> Option<Expr> {
        let allowed = Allowed {
            time: true,
            masses: true,
            coord_order: Some(1),
            ..Allowed::constants("the Lagrangian")
        };
        let lagrangian = self.single("lagrangian", |item| match item {
            ItemKind::Lagrangian(expr) => Some(expr),
            _ => None,
        });
        let Some((expr, _)) = lagrangian else {
            let diagnostic = Diagnostic::error(codes::MISSING_LAGRANGIAN, "missing lagrangian")
                .with_primary(
                    self.end_of_file,
                    "the model ends here without a `lagrangian`",
                )
                .with_help("add `lagrangian = …;`, e.g. `lagrangian = m / 2 * q1'^2;`");
            self.report(diagnostic);
            return None;
        };
        self.check_expr(expr, allowed);
        Some(expr.clone())
    }

    pub(super) fn time(&mut self) -> Option<TimeSpan> {
        let time = self.single("time", |item| match item {
            ItemKind::Time { start, end } => Some((start, end)),
            _ => None,
        });
        let Some(((start, end), span)) = time else {
            let diagnostic = Diagnostic::error(codes::MISSING_TIME, "missing time span")
                .with_primary(
                    self.end_of_file,
                    "the model ends here without a `time` statement",
                )
                .with_help("add the span to integrate over, e.g. `time 0 .. 10;`");
            self.report(diagnostic);
            return None;
        };
        let errors_before = self.diagnostics.len();
        self.check_expr(start, Allowed::constants("a time bound"));
        self.check_expr(end, Allowed::constants("a time bound"));
        if self.diagnostics.len() == errors_before {
            let t0 = self.evaluate_finite(start, "the start time");
            let t1 = self.evaluate_finite(end, "the end time");
            if let (Some(t0), Some(t1)) = (t0, t1) {
                if t1 <= t0 {
                    let what = if t1 == t0 { "empty" } else { "reversed" };
                    let diagnostic =
                        Diagnostic::error(codes::BAD_TIME_SPAN, format!("the time span is {what}"))
                            .with_primary(span, format!("from {t0} to {t1}"))
                            .with_help("the end time must be greater than the start time");
                    self.report(diagnostic);
                }
            }
        }
        Some(TimeSpan {
            start: start.clone(),
            end: end.clone(),
            span,
        })
    }

    pub(super) fn forces(&mut self) -> Vec<Force> {
        let allowed = Allowed {
            time: true,
            masses: true,
            coord_order: Some(1),
            inputs: true,
            ..Allowed::constants("a generalized force")
        };
        let mut forces: Vec<Force> = Vec::new();
        for (item, span) in self.items() {
            let ItemKind::Force { coord, value } = item else {
                continue;
            };
            self.check_expr(value, allowed);
            let Some(coord) = self.coordinate(coord, "a force") else {
                continue;
            };
            if let Some(first) = forces.iter().find(|f| f.coord == coord) {
                let name = &self.coords[coord].name;
                let diagnostic = Diagnostic::error(
                    codes::DUPLICATE_STATEMENT,
                    format!("two forces on coordinate `{name}`"),
                )
                .with_primary(span, "second force here")
                .with_secondary(first.span, "first force here")
                .with_help("add them in one `force` statement");
                self.report(diagnostic);
                continue;
            }
            forces.push(Force {
                coord,
                value: value.clone(),
                span,
            });
        }
        forces
    }

    pub(super) fn exact(&mut self) -> Vec<Exact> {
        let allowed = Allowed {
            time: true,
            ..Allowed::constants("an exact solution")
        };
        let mut exact: Vec<Exact> = Vec::new();
        for (item, span) in self.items() {
            let ItemKind::Exact { target, value } = item else {
                continue;
            };
            self.check_expr(value, allowed);
            let Some((coord, order)) = self.derivative_target(target, "an exact solution") else {
                continue;
            };
            if let Some(first) = exact.iter().find(|e| (e.coord, e.order) == (coord, order)) {
                let diagnostic = Diagnostic::error(
                    codes::DUPLICATE_STATEMENT,
                    "two exact solutions for one quantity",
                )
                .with_primary(target.span, "second exact solution here")
                .with_secondary(first.span, "first one here");
                self.report(diagnostic);
                continue;
            }
            exact.push(Exact {
                coord,
                order,
                value: value.clone(),
                span,
            });
        }
        exact
    }

    /// The `integrator` statement: one at most, naming a known choice.
    pub(super) fn integrator(&mut self) -> Option<DeclaredIntegrator> {
        let (name, span) = self.single("integrator", |item| match item {
            ItemKind::Integrator(name) => Some(name),
            _ => None,
        })?;
        match IntegratorChoice::parse(&name.name) {
            Some(choice) => Some(DeclaredIntegrator { choice, span }),
            None => {
                let names: Vec<&str> = IntegratorChoice::ALL.iter().map(|c| c.name()).collect();
                let mut diagnostic = Diagnostic::error(
                    codes::UNKNOWN_INTEGRATOR,
                    format!("unknown integrator `{}`", name.name),
                )
                .with_primary(name.span, "not an integrator")
                .with_help("the integrators are `auto`, `explicit`, `stiff` and `magnus`");
                if let Some(close) = crate::suggest::closest(&name.name, names.iter().copied()) {
                    diagnostic = diagnostic.with_help(format!("did you mean `{close}`?"));
                }
                self.report(diagnostic);
                None
            }
        }
    }

    /// `output NAME = expr;`: a number or a vector of `t`, params, mass
    /// laws and the state (derivatives up to the state's order are checked
    /// by the mechanics, which knows it).
    pub(super) fn outputs(&mut self) -> Vec<Output> {
        let allowed = Allowed {
            time: true,
            masses: true,
            coord_order: Some(super::MAX_DERIVATIVE_ORDER),
            inputs: true,
            ..Allowed::constants("an output")
        };
        let mut outputs = Vec::new();
        for (item, span) in self.items() {
            let ItemKind::Output { name, value } = item else {
                continue;
            };
            let mut uses = Uses::default();
            let size = match self.type_of(value, allowed, &mut uses) {
                Some(Ty::Vector(n)) => n,
                Some(Ty::Bool) => {
                    self.report(
                        type_mismatch(value.span, Ty::Bool, Ty::Scalar, "an output")
                            .with_help("output a number: `if … then 1 else 0`"),
                    );
                    1
                }
                _ => 1,
            };
            outputs.push(Output {
                name: name.name.clone(),
                span,
                value: value.clone(),
                size,
            });
        }
        outputs
    }

    /// `stop when cond;` (at most one).
    pub(super) fn stop(&mut self) -> Option<Expr> {
        let (cond, _) = self.single("stop when", |item| match item {
            ItemKind::Stop(cond) => Some(cond),
            _ => None,
        })?;
        let allowed = Allowed {
            time: true,
            masses: true,
            coord_order: Some(super::MAX_DERIVATIVE_ORDER),
            inputs: true,
            ..Allowed::constants("a stop condition")
        };
        let errors = self.diagnostics.len();
        self.check_typed(cond, allowed, Ty::Bool);
        (self.diagnostics.len() == errors).then(|| cond.clone())
    }

    /// The only statement that `pick` selects, reporting any repeat.
    fn single<T>(
        &mut self,
        keyword: &str,
        pick: impl Fn(&'a ItemKind) -> Option<T>,
    ) -> Option<(T, Span)> {
        let mut found: Option<(T, Span)> = None;
        let mut repeats = Vec::new();
        for (item, span) in self.items() {
            if let Some(value) = pick(item) {
                match &found {
                    None => found = Some((value, span)),
                    Some((_, first)) => repeats.push((span, *first)),
                }
            }
        }
        for (span, first) in repeats {
            let diagnostic = Diagnostic::error(
                codes::DUPLICATE_STATEMENT,
                format!("more than one `{keyword}` statement"),
            )
            .with_primary(span, "repeated here")
            .with_secondary(first, "first given here")
            .with_help(format!(
                "a model has no more than one `{keyword}` statement"
            ));
            self.report(diagnostic);
        }
        found
    }

    /// The coordinate `ident` names, or a diagnostic naming `what` uses it.
    pub(super) fn coordinate(&mut self, ident: &Ident, what: &str) -> Option<usize> {
        match self.names.get(&ident.name).copied() {
            Some(declared) => match declared.name {
                Name::Coord(index) => Some(index),
                other => {
                    let mut diagnostic = not_a_coordinate(what, &ident.name, ident.span)
                        .with_secondary(
                            declared.span,
                            format!("declared here as {}", super::declarations::kind_name(other)),
                        );
                    if matches!(other, Name::Mass(_)) && what == "a reset" {
                        // A stage dropped by an event, as a new user first
                        // writes it (issue 29): say where a jump of mass goes.
                        diagnostic = diagnostic.with_help(
                            "a mass that jumps (a stage dropped) is written in its law: \
                             `mass M = if t < tb then M0 - mu * t else M2;`, or on the \
                             state, `if z < H then … else …`; the part dropped leaves \
                             with the body's velocity and gives no thrust",
                        );
                    }
                    self.report(diagnostic);
                    None
                }
            },
            None => {
                let diagnostic = self.unknown_name(&ident.name, ident.span);
                self.report(diagnostic);
                None
            }
        }
    }

    /// The coordinate and derivative order of a target such as `q1'`.
    pub(super) fn derivative_target(&mut self, target: &Expr, what: &str) -> Option<(usize, u32)> {
        let ExprKind::Var { name, primes } = &target.kind else {
            let diagnostic = Diagnostic::error(
                codes::NOT_A_COORDINATE,
                format!("the target of {what} must be a coordinate or its derivative"),
            )
            .with_primary(target.span, "not a coordinate")
            .with_help(target_help(target, what));
            self.report(diagnostic);
            return None;
        };
        let coord = self.coordinate(name, what)?;
        if *primes > super::MAX_DERIVATIVE_ORDER {
            let diagnostic = Diagnostic::error(
                codes::DERIVATIVE_ORDER_NOT_ALLOWED,
                format!("derivative of order {primes} is too high"),
            )
            .with_primary(
                target.span,
                format!("lagc accepts orders up to {}", super::MAX_DERIVATIVE_ORDER),
            );
            self.report(diagnostic);
            return None;
        }
        Some((coord, *primes))
    }
}

/// The help for a target that is no coordinate: a vector of them (a
/// velocity reflected at a curved wall, `(x', y') = …`, as a new user
/// first writes an impact) is given component by component.
fn target_help(target: &Expr, what: &str) -> String {
    let ExprKind::Vector(parts) = &target.kind else {
        return "write a coordinate with primes for a derivative, like `q1` or `q1'`".to_string();
    };
    let names: Vec<String> = parts
        .iter()
        .filter_map(|p| match &p.kind {
            ExprKind::Var { name, primes } => {
                Some(format!("{}{}", name.name, "'".repeat(*primes as usize)))
            }
            _ => None,
        })
        .collect();
    if names.len() != parts.len() {
        return "write a coordinate with primes for a derivative, like `q1` or `q1'`".to_string();
    }
    let axes = ["x", "y", "z"];
    let each: Vec<String> = names
        .iter()
        .zip(axes)
        .map(|(n, axis)| format!("{n} = v.{axis}"))
        .collect();
    if what == "a reset" {
        format!(
            "a vector is reset component by component, each read from the state before \
             the impact: with `let v = …;` the new velocity, write `then {}`",
            each.join(", ")
        )
    } else {
        format!(
            "give each component on its own: {}",
            names
                .iter()
                .map(|n| format!("`{n} = …`"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    }
}

fn not_a_coordinate(what: &str, name: &str, span: Span) -> Diagnostic {
    Diagnostic::error(
        codes::NOT_A_COORDINATE,
        format!("`{name}` is not a coordinate, but {what} needs one"),
    )
    .with_primary(span, "not a coordinate")
}

/// The first name an expression uses that is not a `constant` (`pi`).
fn first_name<'e>(expr: &'e Expr, constant: &dyn Fn(&str) -> bool) -> Option<&'e Ident> {
    let first = |e: &'e Expr| first_name(e, constant);
    match &expr.kind {
        ExprKind::Number(_) => None,
        ExprKind::Var { name, primes: 0 } if constant(&name.name) => None,
        ExprKind::Var { name, .. } => Some(name),
        ExprKind::Neg(e) | ExprKind::Not(e) | ExprKind::Component { base: e, .. } => first(e),
        ExprKind::Binary { lhs, rhs, .. }
        | ExprKind::Compare { lhs, rhs, .. }
        | ExprKind::Logic { lhs, rhs, .. } => first(lhs).or_else(|| first(rhs)),
        ExprKind::Call { args, .. } | ExprKind::Vector(args) => args.iter().find_map(first),
        ExprKind::If {
            cond,
            then,
            otherwise,
        } => first(cond)
            .or_else(|| first(then))
            .or_else(|| first(otherwise)),
    }
}
