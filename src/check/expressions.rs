//! Resolving the names of one expression against what its statement allows.

use super::declarations::kind_name;
use super::model::Name;
use super::types::{type_mismatch, Ty, Uses};
use super::{Checker, MAX_DERIVATIVE_ORDER};
use crate::diagnostic::{codes, Diagnostic};
use crate::span::Span;
use crate::syntax::ast::{Builtin, Expr};

/// What an expression of one kind of statement may refer to.
#[derive(Debug, Clone, Copy)]
pub struct Allowed {
    /// The statement, for messages: "a mass law", "the Lagrangian", …
    pub what: &'static str,
    pub time: bool,
    /// Params with an index below this may be used (a param may use only
    /// earlier ones); `usize::MAX` for all.
    pub params_before: usize,
    pub masses: bool,
    /// The highest derivative order of a coordinate allowed; `None` when no
    /// coordinate may appear.
    pub coord_order: Option<u32>,
    /// The code for a coordinate where none may appear.
    pub coord_code: &'static str,
    /// The code for a derivative above `coord_order` (a mass law's
    /// velocity is E0005, not the general E0021).
    pub order_code: &'static str,
    /// Lets with an index below this may be used (a let may use only
    /// earlier ones); `usize::MAX` for all.
    pub lets_before: usize,
    /// Inputs may be used (SPEC §2.3: where forces, the right sides of
    /// velocity constraints and outputs may use `t`).
    pub inputs: bool,
}

impl Allowed {
    /// Numbers and params only: param values, initial values, time bounds.
    pub const fn constants(what: &'static str) -> Allowed {
        Allowed {
            what,
            time: false,
            params_before: usize::MAX,
            masses: false,
            coord_order: None,
            coord_code: codes::NAME_NOT_ALLOWED,
            order_code: codes::DERIVATIVE_ORDER_NOT_ALLOWED,
            lets_before: usize::MAX,
            inputs: false,
        }
    }

    /// Anything: the body of a let, whose uses are checked where it is used.
    pub const fn anything(what: &'static str, lets_before: usize) -> Allowed {
        Allowed {
            what,
            time: true,
            params_before: usize::MAX,
            masses: true,
            coord_order: Some(MAX_DERIVATIVE_ORDER),
            coord_code: codes::NAME_NOT_ALLOWED,
            order_code: codes::DERIVATIVE_ORDER_NOT_ALLOWED,
            lets_before,
            inputs: true,
        }
    }
}

/// A coordinate's derivative found in an expression.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CoordUse {
    pub coord: usize,
    pub order: u32,
    pub span: Span,
}

impl Checker<'_> {
    /// Reports every name in `expr` that `allowed` forbids or that is not
    /// declared, and every type error; requires a number. Returns the
    /// coordinate derivatives it holds (those of the lets it uses included).
    pub(super) fn check_expr(&mut self, expr: &Expr, allowed: Allowed) -> Vec<CoordUse> {
        self.check_typed(expr, allowed, Ty::Scalar)
    }

    /// [`Checker::check_expr`] for an expression of type `wanted`.
    pub(super) fn check_typed(
        &mut self,
        expr: &Expr,
        allowed: Allowed,
        wanted: Ty,
    ) -> Vec<CoordUse> {
        let mut uses = Uses::default();
        if let Some(found) = self.type_of(expr, allowed, &mut uses) {
            self.expect_type(expr, found, wanted, allowed.what);
        }
        self.note_params(allowed, &uses);
        uses.coords
    }

    /// Records the params an expression uses where they could not change
    /// between steps (see `Param::tunable`), and each param's own params.
    pub(super) fn note_params(&mut self, allowed: Allowed, uses: &Uses) {
        match allowed.what {
            "a param" => self.param_uses.push(uses.params.clone()),
            "an initial value" | "an input's default" | "a let" | "an exact solution" => {}
            _ if allowed.inputs => {}
            _ => self.fixed_params.extend_from_slice(&uses.params),
        }
    }

    /// Which params may change between steps: none of those fixed, nor of
    /// the params computed from them (a tuned param recomputes those).
    pub(super) fn tunable_params(&self, count: usize) -> Vec<bool> {
        // Without every param's own params (a param's check not recorded
        // as "a param") a fixed param's sources are unknown: none is
        // tunable rather than one wrongly.
        if self.param_uses.len() != count {
            return vec![false; count];
        }
        let mut fixed = vec![false; count];
        for &i in &self.fixed_params {
            if let Some(f) = fixed.get_mut(i) {
                *f = true;
            }
        }
        // A param uses only earlier ones: latest first, each fixed param
        // fixes those it is computed from.
        for j in (0..count).rev() {
            if fixed[j] {
                for &i in &self.param_uses[j] {
                    if let Some(f) = fixed.get_mut(i) {
                        *f = true;
                    }
                }
            }
        }
        fixed.into_iter().map(|f| !f).collect()
    }

    /// Reports `found` where `wanted` is needed.
    pub(super) fn expect_type(&mut self, expr: &Expr, found: Ty, wanted: Ty, what: &str) {
        if found != wanted {
            self.report(type_mismatch(expr.span, found, wanted, what));
        }
    }

    pub(super) fn check_var(
        &mut self,
        name: &str,
        primes: u32,
        span: Span,
        allowed: Allowed,
    ) -> Option<CoordUse> {
        if name == "t" {
            if primes > 0 {
                self.report(primes_on_time(span));
            } else if !allowed.time {
                self.report(
                    Diagnostic::error(
                        codes::NAME_NOT_ALLOWED,
                        format!("{} cannot depend on time", allowed.what),
                    )
                    .with_primary(span, "time `t` used here"),
                );
            }
            return None;
        }
        let Some(declared) = self.names.get(name).copied() else {
            // One report per unknown name, at its first use: a misspelt
            // name used often would otherwise bury every other error.
            if self.unknown_reported.insert(name.to_string()) {
                self.report(self.unknown_name(name, span));
            }
            return None;
        };
        let not_allowed = |kind: &str| {
            Diagnostic::error(
                codes::NAME_NOT_ALLOWED,
                format!("{} cannot use {kind} `{name}`", allowed.what),
            )
            .with_primary(span, format!("{kind} used here"))
            .with_secondary(declared.span, format!("`{name}` declared here"))
        };
        match declared.name {
            Name::Coord(coord) => {
                let Some(max_order) = allowed.coord_order else {
                    let diagnostic = Diagnostic::error(
                        allowed.coord_code,
                        format!("{} cannot depend on the coordinate `{name}`", allowed.what),
                    )
                    .with_primary(span, "coordinate used here")
                    .with_secondary(declared.span, "declared as a coordinate here");
                    self.report(diagnostic);
                    return None;
                };
                let max_order = max_order.min(MAX_DERIVATIVE_ORDER);
                if primes > max_order {
                    let diagnostic = if allowed.order_code == codes::MASS_DEPENDS_ON_STATE {
                        mass_of_velocity(
                            allowed.what,
                            name,
                            primes,
                            span,
                            "a derivative of a coordinate used here",
                        )
                    } else {
                        order_not_allowed(allowed.what, name, primes, max_order, span)
                    };
                    self.report(diagnostic);
                    return None;
                }
                Some(CoordUse {
                    coord,
                    order: primes,
                    span,
                })
            }
            _ if primes > 0 => {
                self.report(primes_on_non_coordinate(
                    name,
                    declared.name,
                    span,
                    declared.span,
                ));
                None
            }
            Name::Param(index) if index >= allowed.params_before => {
                let diagnostic = Diagnostic::error(
                    codes::PARAM_USED_BEFORE_DECLARATION,
                    format!("param `{name}` is used before its declaration"),
                )
                .with_primary(span, "used here")
                .with_secondary(declared.span, "declared later here")
                .with_help("a param may use only params declared before it; move this one down");
                self.report(diagnostic);
                None
            }
            Name::Param(_) => None,
            Name::Input(_) if allowed.inputs => None,
            Name::Input(_) => {
                self.report(input_not_allowed(allowed, name, span, declared.span));
                None
            }
            Name::Mass(_) if allowed.masses => None,
            Name::Mass(_) => {
                self.report(not_allowed("the mass law"));
                None
            }
            Name::Let(_) | Name::Output(_) => None,
            Name::Point(_) => {
                let diagnostic = not_allowed("the point")
                    .with_note("a point names a body for the reactive forces; it has no value");
                self.report(diagnostic);
                None
            }
        }
    }

    pub(super) fn unknown_name(&self, name: &str, span: Span) -> Diagnostic {
        let diagnostic = Diagnostic::error(codes::UNKNOWN_NAME, format!("unknown name `{name}`"))
            .with_primary(span, "not declared");
        if Builtin::from_name(name).is_some() {
            return diagnostic.with_help(format!("`{name}` is a function: write `{name}(…)`"));
        }
        match crate::suggest::closest(name, self.known_names()) {
            Some(close) => diagnostic.with_help(format!("did you mean `{close}`?")),
            None => {
                diagnostic.with_help("declare it with `param`, `input`, `coord`, `mass` or `point`")
            }
        }
    }
}

/// An input where it may not stand, with the reason for the kind of
/// statement.
pub(super) fn input_not_allowed(
    allowed: Allowed,
    name: &str,
    span: Span,
    declared: Span,
) -> Diagnostic {
    Diagnostic::error(
        codes::INPUT_NOT_ALLOWED,
        format!("{} cannot use the input `{name}`", allowed.what),
    )
    .with_primary(span, "input used here")
    .with_secondary(declared, format!("`{name}` declared as an input here"))
    .with_note(input_note(allowed))
}

/// Why inputs may not stand where `allowed` describes.
pub(super) fn input_note(allowed: Allowed) -> &'static str {
    match allowed.what {
        "a constraint" if allowed.coord_order == Some(0) => {
            "a holonomic constraint fixes positions: a jump of an input would move the \
             body instantly; use the input in a velocity constraint or a force"
        }
        "the Lagrangian" | "a mass law" | "a point's mass" | "a position" => {
            "an input changes between steps, and each change restarts the integration; \
             the Lagrangian, the masses and the positions are differentiated in time \
             (equations (4), the reactive forces), so a jump there would be an impulse \
             or an ejection of matter that lagc does not model"
        }
        _ => {
            "inputs may be used in forces, velocity constraints, points' velocities, \
             outputs and `stop when`"
        }
    }
}

fn primes_on_time(span: Span) -> Diagnostic {
    Diagnostic::error(
        codes::PRIMES_ON_NON_COORDINATE,
        "time `t` cannot be differentiated",
    )
    .with_primary(span, "primes on `t`")
    .with_help("primes mark derivatives of coordinates; the derivative of `t` is 1")
}

fn primes_on_non_coordinate(name: &str, kind: Name, span: Span, declared: Span) -> Diagnostic {
    let diagnostic = Diagnostic::error(
        codes::PRIMES_ON_NON_COORDINATE,
        format!("`{name}` is {} and cannot carry primes", kind_name(kind)),
    )
    .with_primary(span, "primes mark derivatives of coordinates only")
    .with_secondary(declared, format!("`{name}` declared here"));
    match kind {
        Name::Mass(_) => diagnostic.with_note(
            "a mass law's rate of change enters only through the reactive forces of its points",
        ),
        _ => diagnostic,
    }
}

/// A mass law (or a point's mass) that holds a derivative of a coordinate:
/// a mass may follow the configuration (`rho * x`, SPEC §2.3), not the
/// motion's velocities.
pub(super) fn mass_of_velocity(
    what: &str,
    name: &str,
    order: u32,
    span: Span,
    label: &str,
) -> Diagnostic {
    let primes = "'".repeat(order as usize);
    Diagnostic::error(
        codes::MASS_DEPENDS_ON_STATE,
        format!("{what} cannot depend on the derivative `{name}{primes}`"),
    )
    .with_primary(span, label)
    .with_note(
        "a mass may depend on `t` and the coordinates; its rate along the motion, \
         Ṁ = ∂M/∂t + Σ ∂M/∂q_j q_j', enters the reactive forces. A law of velocities \
         would carry the accelerations into Ṁ (and the mass matrix), and a mass that \
         follows the speed, gained and given back as the body speeds up and slows down, \
         is no accretion or ejection of matter",
    )
    .with_help(format!(
        "write the mass as a function of time or of the coordinates (for an accretion \
         that grows with the distance travelled, a law of `{name}`)"
    ))
}

fn order_not_allowed(what: &str, name: &str, order: u32, max: u32, span: Span) -> Diagnostic {
    let allowed = match max {
        0 => "no derivatives are allowed here".to_string(),
        1 => "only first derivatives are allowed here".to_string(),
        _ => format!("derivatives up to order {max} are allowed here"),
    };
    Diagnostic::error(
        codes::DERIVATIVE_ORDER_NOT_ALLOWED,
        format!("{what} cannot hold a derivative of `{name}` of order {order}"),
    )
    .with_primary(span, allowed)
}
