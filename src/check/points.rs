//! Points of variable mass, for the reactive forces (SPEC §1.3): each has a
//! mass, a position r(t, q) and the velocity of its separated particles.

use super::expressions::Allowed;
use super::model::{EjectaVelocity, Initial, Name, Point, TimeSpan};
use super::types::{type_mismatch, Ty, Uses};
use super::Checker;
use crate::diagnostic::{codes, Diagnostic};
use crate::span::Span;
use crate::syntax::ast::{Expr, ExprKind, Ident, ItemKind, PointField, PointFieldKind};

const POINT_MASS: Allowed = Allowed {
    time: true,
    masses: true,
    coord_order: Some(0),
    order_code: codes::MASS_DEPENDS_ON_STATE,
    ..Allowed::constants("a point's mass")
};
const POSITION: Allowed = Allowed {
    time: true,
    coord_order: Some(0),
    ..Allowed::constants("a position")
};
const VELOCITY: Allowed = Allowed {
    time: true,
    coord_order: Some(1),
    inputs: true,
    ..Allowed::constants("a velocity")
};

impl Checker<'_> {
    pub(super) fn points(&mut self) -> Vec<Point> {
        let mut points = Vec::new();
        for (item, span) in self.items() {
            if let ItemKind::Point { name, fields } = item {
                if let Some(point) = self.point(name, fields, span) {
                    points.push(point);
                }
            }
        }
        points
    }

    fn point(&mut self, name: &Ident, fields: &[PointField], span: Span) -> Option<Point> {
        let mut mass: Option<(&Expr, Span)> = None;
        let mut position: Option<(Vec<Expr>, Span)> = None;
        let mut velocity: Option<(EjectaVelocity, Vec<Expr>, Span)> = None;
        for field in fields {
            let first = match &field.kind {
                PointFieldKind::Mass(expr) => {
                    self.check_expr(expr, POINT_MASS);
                    first_or(&mut mass, (expr, field.span)).map(|m| m.1)
                }
                PointFieldKind::Position(expr) => {
                    let vector = self.check_vector(expr, POSITION);
                    first_or(&mut position, (vector, field.span)).map(|p| p.1)
                }
                PointFieldKind::AbsoluteVelocity(expr) => {
                    let vector = self.check_vector(expr, VELOCITY);
                    let given = (EjectaVelocity::Absolute(vector.clone()), vector, field.span);
                    first_or(&mut velocity, given).map(|v| v.2)
                }
                PointFieldKind::RelativeVelocity(expr) => {
                    let vector = self.check_vector(expr, VELOCITY);
                    let given = (EjectaVelocity::Relative(vector.clone()), vector, field.span);
                    first_or(&mut velocity, given).map(|v| v.2)
                }
            };
            if let Some(first) = first {
                let diagnostic = Diagnostic::error(
                    codes::DUPLICATE_POINT_FIELD,
                    format!("point `{}` gives a field twice", name.name),
                )
                .with_primary(field.span, "given again here")
                .with_secondary(first, "first given here")
                .with_note(
                    "a point has one mass, one position and one velocity (absolute or relative)",
                );
                self.report(diagnostic);
            }
        }
        let missing: Vec<&str> = [
            ("`mass`", mass.is_none()),
            ("`position`", position.is_none()),
            (
                "`absolute velocity` or `relative velocity`",
                velocity.is_none(),
            ),
        ]
        .into_iter()
        .filter_map(|(field, missing)| missing.then_some(field))
        .collect();
        if !missing.is_empty() {
            let diagnostic = Diagnostic::error(
                codes::MISSING_POINT_FIELD,
                format!("point `{}` lacks {}", name.name, missing.join(" and ")),
            )
            .with_primary(name.span, "this point is incomplete")
            .with_help("a point needs `mass = …;`, `position = (…);` and `absolute velocity = (…);` or `relative velocity = (…);`");
            self.report(diagnostic);
        }
        let ((mass, _), (position, position_span), (velocity, velocity_vector, velocity_span)) =
            (mass?, position?, velocity?);
        if position.len() != velocity_vector.len() {
            let diagnostic = Diagnostic::error(
                codes::DIMENSION_MISMATCH,
                format!(
                    "point `{}`: position and velocity have different dimensions",
                    name.name
                ),
            )
            .with_primary(
                velocity_span,
                format!("{} components", velocity_vector.len()),
            )
            .with_secondary(position_span, format!("{} components", position.len()));
            self.report(diagnostic);
        }
        Some(Point {
            name: name.name.clone(),
            span,
            mass: mass.clone(),
            position,
            velocity,
        })
    }

    /// Reports every point whose velocity has no value at the start the
    /// file states, where every value it reads is a constant there: a
    /// thrust along the velocity, `-w * (x', y') / speed`, of a rocket
    /// launched from rest is 0/0, and the run stopped at t = 0 blaming "a
    /// force, the Lagrangian or a mass law" (issue 29). A start set at run
    /// time (`--init`) meets the run's own check.
    pub(super) fn points_at_start(
        &mut self,
        points: &[Point],
        initial: &[Initial],
        time: &TimeSpan,
    ) {
        if points.is_empty() {
            return;
        }
        let Some(t0) = self.state_the_start(initial, time) else {
            return;
        };
        let undefined: Vec<(&Point, &str, Span, Vec<f64>)> = points
            .iter()
            .filter_map(|point| {
                // A constant mass gives no reactive force: its velocity is
                // never used (a run of it at 0/0 goes on).
                if self.constant(&point.mass) {
                    return None;
                }
                let (kind, parts) = match &point.velocity {
                    EjectaVelocity::Absolute(parts) => ("absolute", parts),
                    EjectaVelocity::Relative(parts) => ("relative", parts),
                };
                let values: Vec<f64> = parts
                    .iter()
                    .map(|p| self.evaluate(p))
                    .collect::<Option<_>>()?;
                let span = parts.first()?.span.to(parts.last()?.span);
                (!values.iter().all(|v| v.is_finite())).then_some((point, kind, span, values))
            })
            .collect();
        self.start = None;
        for (point, kind, span, values) in undefined {
            let shown: Vec<String> = values.iter().map(|v| format!("{v}")).collect();
            let diagnostic = Diagnostic::error(
                codes::NON_FINITE_VALUE,
                format!(
                    "the {kind} velocity of point `{}` has no value at the start",
                    point.name
                ),
            )
            .with_primary(span, format!("this is ({}) at t = {t0}", shown.join(", ")))
            .with_note("evaluated at the initial values and params the file states")
            .with_help(
                "a direction taken from the velocity (`(x', y') / speed`) has none at \
                 rest: start with a speed along it, or give the direction until the \
                 body moves (`if t < t1 then (0, 1) else (x', y') / speed`)",
            );
            self.report(diagnostic);
        }
    }

    /// Whether `expr` reads only numbers and params, through lets and mass
    /// laws: neither `t`, a coordinate nor an input.
    fn constant(&self, expr: &Expr) -> bool {
        let body = |index: usize, mass: bool| {
            self.ast
                .items
                .iter()
                .filter_map(|item| match &item.kind {
                    ItemKind::Let { value, .. } if !mass => Some(value),
                    ItemKind::Mass { law, .. } if mass => Some(law),
                    _ => None,
                })
                .nth(index)
        };
        match &expr.kind {
            ExprKind::Number(_) => true,
            ExprKind::Var { name, primes: 0 } => match self.names.get(&name.name).map(|d| d.name) {
                Some(Name::Param(_)) => true,
                Some(Name::Let(index)) => body(index, false).is_some_and(|e| self.constant(e)),
                Some(Name::Mass(index)) => body(index, true).is_some_and(|e| self.constant(e)),
                None => name.name == "pi",
                _ => false,
            },
            ExprKind::Var { .. } => false,
            ExprKind::Neg(e) | ExprKind::Not(e) | ExprKind::Component { base: e, .. } => {
                self.constant(e)
            }
            ExprKind::Binary { lhs, rhs, .. }
            | ExprKind::Compare { lhs, rhs, .. }
            | ExprKind::Logic { lhs, rhs, .. } => self.constant(lhs) && self.constant(rhs),
            ExprKind::Call { args, .. } | ExprKind::Vector(args) => {
                args.iter().all(|a| self.constant(a))
            }
            ExprKind::If {
                cond,
                then,
                otherwise,
            } => self.constant(cond) && self.constant(then) && self.constant(otherwise),
        }
    }

    /// A point's vector, as its components: a vector literal's elements,
    /// the components of any other vector expression (`p1 + (0, l)`), or
    /// one number (v1 accepted `(z)`, a 1-vector).
    fn check_vector(&mut self, expr: &Expr, allowed: Allowed) -> Vec<Expr> {
        let mut uses = Uses::default();
        let found = self.type_of(expr, allowed, &mut uses);
        self.note_params(allowed, &uses);
        match found {
            Some(Ty::Scalar) | None => vec![expr.clone()],
            Some(Ty::Bool) => {
                self.report(type_mismatch(
                    expr.span,
                    Ty::Bool,
                    Ty::Vector(2),
                    allowed.what,
                ));
                vec![expr.clone()]
            }
            Some(Ty::Vector(n)) => match &expr.kind {
                ExprKind::Vector(elements) => elements.clone(),
                _ => ["x", "y", "z"][..n]
                    .iter()
                    .map(|axis| Expr {
                        kind: ExprKind::Component {
                            base: Box::new(expr.clone()),
                            axis: Ident {
                                name: (*axis).to_string(),
                                span: expr.span,
                            },
                        },
                        span: expr.span,
                    })
                    .collect(),
            },
        }
    }
}

/// Stores `given` in an empty slot; otherwise returns the slot's value (the
/// first one given), leaving it in place.
fn first_or<T: Clone>(slot: &mut Option<T>, given: T) -> Option<T> {
    match slot {
        Some(first) => Some(first.clone()),
        None => {
            *slot = Some(given);
            None
        }
    }
}
