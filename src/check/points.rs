//! Points of variable mass, for the reactive forces (SPEC §1.3): each has a
//! mass, a position r(t, q) and the velocity of its separated particles.

use super::expressions::Allowed;
use super::model::{EjectaVelocity, Point};
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
