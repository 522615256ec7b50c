//! Constraints: explicit `q^(k) = φ` (the left side names a dependent
//! coordinate; no right side holds a dependent derivative of order ≥ k),
//! implicit `lhs = rhs for q^(k) or …`, and holonomic `f(t, q) = g(t, q)`
//! (no derivatives; differentiated to the common order k). Implicit and
//! holonomic constraints that share candidates, or hold each other's, form
//! a group solved together (SPEC §2.3).

use super::expressions::Allowed;
use super::model::{Constraint, Group, Implicit, Name};
use super::{Checker, MAX_DERIVATIVE_ORDER};
use crate::diagnostic::{codes, Diagnostic};
use crate::span::Span;
use crate::syntax::ast::{Expr, ExprKind, ItemKind};

impl Checker<'_> {
    /// Returns the common order k, the constraints in source order and the
    /// groups of implicit constraints solved together (SPEC §2.3).
    pub(super) fn constraints(&mut self) -> (Option<u32>, Vec<Constraint>, Vec<Group>) {
        let mut constraints: Vec<Constraint> = Vec::new();
        // Per constraint: the coordinates whose derivative of the
        // constraint's order it holds (for an implicit constraint; the
        // coordinates themselves for a holonomic one).
        let mut held: Vec<Vec<usize>> = Vec::new();
        let mut right_sides = Vec::new();
        // The coordinates explicit constraints (`constraint y' = …;`) make
        // dependent: an implicit constraint written without `for` is not
        // solved for them.
        let explicit_dependents: Vec<&str> = self
            .items()
            .filter_map(|(item, _)| match item {
                ItemKind::Constraint {
                    lhs, candidates, ..
                } if candidates.is_empty() => match &lhs.kind {
                    ExprKind::Var { name, primes } if *primes > 0 => Some(name.name.as_str()),
                    _ => None,
                },
                _ => None,
            })
            .collect();
        for (item, span) in self.items() {
            let ItemKind::Constraint {
                lhs,
                rhs,
                candidates,
            } = item
            else {
                continue;
            };
            if self.is_holonomic(lhs, rhs) {
                let Some((constraint, coords)) = self.holonomic(lhs, rhs, candidates, span) else {
                    self.constraints_incomplete = true;
                    continue;
                };
                constraints.push(constraint);
                held.push(coords);
                continue;
            }
            // Named after `for`, or (written without `for`, an expression on
            // the left) the highest derivatives the constraint holds.
            let solved_for = if candidates.is_empty() {
                self.automatic_candidates(lhs, rhs, &explicit_dependents)
            } else {
                let Some(named) = self.candidates(candidates) else {
                    self.constraints_incomplete = true;
                    continue;
                };
                Some(named)
            };
            let (coord, order, implicit) = if let Some((order, owned)) = solved_for {
                let implicit = Implicit {
                    lhs: lhs.clone(),
                    candidates: owned,
                    holonomic: false,
                    raised: false,
                };
                (implicit.candidates[0], order, Some(implicit))
            } else {
                let Some((coord, order)) = self.constraint_lhs(lhs) else {
                    self.constraints_incomplete = true;
                    right_sides.push((rhs, span, None));
                    continue;
                };
                right_sides.push((rhs, span, Some(order)));
                (coord, order, None)
            };
            if !self.constrained_once(coord, implicit.as_ref(), lhs.span, &constraints) {
                continue;
            }
            if let Some(first) = constraints.iter().find(|c| !c.is_holonomic()) {
                if first.order != order {
                    let diagnostic = Diagnostic::error(
                        codes::MIXED_CONSTRAINT_ORDERS,
                        "constraints of different orders",
                    )
                    .with_primary(lhs.span, format!("this constraint has order {order}"))
                    .with_secondary(first.span, format!("the first constraint has order {}", first.order))
                    .with_help("all constraints of a model share one order k; differentiate the lower-order ones");
                    self.report(diagnostic);
                    self.constraints_incomplete = true;
                    continue;
                }
            }
            constraints.push(Constraint {
                coord,
                order,
                rhs: rhs.clone(),
                span,
                text: String::new(),
                implicit,
            });
            held.push(Vec::new());
        }
        // Holonomic constraints are differentiated to the others' order
        // (1 when there are none).
        let k = constraints
            .iter()
            .find(|c| !c.is_holonomic())
            .map_or(1, |c| c.order);
        let order = (!constraints.is_empty()).then_some(k);
        for c in &mut constraints {
            if c.is_holonomic() {
                c.order = k;
            }
        }
        self.holonomic_candidates(&mut constraints, &held);
        for index in 0..constraints.len() {
            if let Some(implicit) = constraints[index].implicit.clone() {
                if !implicit.holonomic {
                    held[index] =
                        self.implicit_residual(&constraints[index], &implicit, &constraints);
                }
            }
        }
        if let Some(k) = order {
            // A right side is checked against its own constraint's order, so
            // that a constraint of the wrong order gets one error, not two.
            for (rhs, span, own_order) in right_sides {
                self.constraint_rhs(rhs, span, own_order.unwrap_or(k), &constraints);
            }
        }
        let groups = self.groups(&mut constraints, &held);
        let order = order.map(|k| self.raise_nonlinear(&mut constraints, &groups, k));
        if !self.coords.is_empty() && constraints.len() >= self.coords.len() {
            if let Some(last) = constraints.last() {
                let diagnostic = Diagnostic::error(
                    codes::NO_INDEPENDENT_COORDINATE,
                    "every coordinate is constrained",
                )
                .with_primary(
                    last.span,
                    "this constraint leaves no independent coordinate",
                )
                .with_help("at least one coordinate must stay independent");
                self.report(diagnostic);
            }
        }
        (order, constraints, groups)
    }

    /// Reports a coordinate made dependent by two constraints, one of them
    /// explicit (implicit constraints that share candidates are solved
    /// together instead); true when there is none.
    fn constrained_once(
        &mut self,
        coord: usize,
        implicit: Option<&Implicit>,
        span: Span,
        constraints: &[Constraint],
    ) -> bool {
        let mine = owned_by(coord, implicit);
        let Some(first) = constraints.iter().find(|c| {
            (implicit.is_none() || c.implicit.is_none())
                && owned_by(c.coord, c.implicit.as_ref())
                    .iter()
                    .any(|j| mine.contains(j))
        }) else {
            return true;
        };
        let shared = owned_by(first.coord, first.implicit.as_ref())
            .into_iter()
            .find(|j| mine.contains(j))
            .unwrap_or(coord);
        let name = &self.coords[shared].name;
        let diagnostic = Diagnostic::error(
            codes::DOUBLE_CONSTRAINT,
            format!("coordinate `{name}` is constrained twice"),
        )
        .with_primary(span, "second constraint on it here")
        .with_secondary(first.span, "first constraint here")
        .with_help("each constraint makes one coordinate dependent; constrain another coordinate");
        self.report(diagnostic);
        self.constraints_incomplete = true;
        false
    }

    /// The coordinate and order of `q'`, `q''`, … on a constraint's left side.
    fn constraint_lhs(&mut self, lhs: &Expr) -> Option<(usize, u32)> {
        let ExprKind::Var { name, primes } = &lhs.kind else {
            self.report(bad_lhs(lhs.span, "not a derivative of a coordinate"));
            return None;
        };
        let Some(declared) = self.names.get(&name.name).copied() else {
            let diagnostic = self.unknown_name(&name.name, name.span);
            self.report(diagnostic);
            return None;
        };
        let Name::Coord(coord) = declared.name else {
            let what = super::declarations::kind_name(declared.name);
            let diagnostic = bad_lhs(lhs.span, &format!("`{}` is {what}", name.name))
                .with_secondary(declared.span, "declared here");
            self.report(diagnostic);
            return None;
        };
        if *primes == 0 {
            let diagnostic = bad_lhs(lhs.span, "a coordinate, not a derivative")
                .with_note("a constraint without derivatives, `q2 = f(t, q1)`, is holonomic; this one holds derivatives, so its left side must be the derivative it fixes")
                .with_help(format!("write `constraint {}' = …;`, or name the derivative it is solved for: `… for {}'`", name.name, name.name));
            self.report(diagnostic);
            return None;
        }
        if *primes > MAX_DERIVATIVE_ORDER {
            let diagnostic = Diagnostic::error(
                codes::DERIVATIVE_ORDER_NOT_ALLOWED,
                format!("constraint of order {primes} is too high"),
            )
            .with_primary(
                lhs.span,
                format!("lagc accepts orders up to {MAX_DERIVATIVE_ORDER}"),
            );
            self.report(diagnostic);
            return None;
        }
        Some((coord, *primes))
    }

    fn constraint_rhs(&mut self, rhs: &Expr, span: Span, k: u32, constraints: &[Constraint]) {
        let allowed = Allowed {
            time: true,
            masses: true,
            coord_order: Some(k),
            inputs: true,
            ..Allowed::constants("a constraint")
        };
        for used in self.check_expr(rhs, allowed) {
            let Some(dependent) = constraints
                .iter()
                .find(|c| owned_by(c.coord, c.implicit.as_ref()).contains(&used.coord))
            else {
                continue;
            };
            // A let's uses are its whole body's: `vel.x` of `let vel =
            // (x', y')` does not hold `y'` (components.rs).
            if used.order >= k && self.holds_jet_of(rhs, used.coord, k) {
                let name = &self.coords[used.coord].name;
                let diagnostic = Diagnostic::error(
                    codes::DEPENDENT_DERIVATIVE_IN_RHS,
                    format!("a constraint's right side holds a dependent derivative of order {}", used.order),
                )
                .with_primary(used.span, format!("`{name}` is dependent"))
                .with_secondary(dependent.span, format!("`{name}` is made dependent here"))
                .with_note(format!(
                    "right sides may hold dependent coordinates' derivatives of order below k = {k} only"
                ));
                // The constraint's own statement span helps place the error.
                let diagnostic = if dependent.span == span {
                    diagnostic.with_help("a constraint cannot refer to the derivative it defines")
                } else if dependent.implicit.is_some() {
                    diagnostic.with_help(
                        "write this constraint implicitly (`constraint … = … for …;`): \
                         implicit constraints that share derivatives are solved together",
                    )
                } else {
                    diagnostic.with_help("substitute that coordinate's constraint into this one")
                };
                self.report(diagnostic);
            }
        }
    }
}

impl Checker<'_> {
    /// The order and coordinates of `for y' or x'`: derivatives of one
    /// order, of distinct coordinates.
    fn candidates(&mut self, candidates: &[Expr]) -> Option<(u32, Vec<usize>)> {
        let mut order = None;
        let mut owned = Vec::new();
        for candidate in candidates {
            if let ExprKind::Var { name, primes: 0 } = &candidate.kind {
                let diagnostic = Diagnostic::error(
                    codes::BAD_CANDIDATE,
                    format!("`for` names `{}`, not a derivative", name.name),
                )
                .with_primary(candidate.span, "not a derivative")
                .with_help("name the derivative the constraint is solved for, e.g. `for y'`");
                self.report(diagnostic);
                return None;
            }
            let (coord, primes) = self.constraint_lhs(candidate)?;
            match order {
                None => order = Some(primes),
                Some(k) if k != primes => {
                    let diagnostic = Diagnostic::error(
                        codes::BAD_CANDIDATE,
                        "a constraint's candidates differ in order",
                    )
                    .with_primary(candidate.span, format!("of order {primes}"))
                    .with_secondary(candidates[0].span, format!("of order {k}"))
                    .with_help("a constraint of order k is solved for a derivative of order k");
                    self.report(diagnostic);
                    return None;
                }
                Some(_) => {}
            }
            if owned.contains(&coord) {
                let diagnostic =
                    Diagnostic::error(codes::BAD_CANDIDATE, "a candidate is named twice")
                        .with_primary(candidate.span, "named again here");
                self.report(diagnostic);
                return None;
            }
            owned.push(coord);
        }
        Some((order?, owned))
    }

    /// Checks `lhs = rhs` of an implicit constraint: its order is the
    /// candidates', every candidate occurs in it, and no explicit
    /// constraint's dependent derivative of order ≥ k does (another
    /// implicit constraint's candidate couples the two: they are solved
    /// together). Returns the coordinates whose derivative of order k it
    /// holds.
    fn implicit_residual(
        &mut self,
        own: &Constraint,
        implicit: &Implicit,
        all: &[Constraint],
    ) -> Vec<usize> {
        let k = own.order;
        let allowed = Allowed {
            time: true,
            masses: true,
            coord_order: Some(k),
            inputs: true,
            ..Allowed::constants("a constraint")
        };
        let errors = self.diagnostics.len();
        let mut uses = self.check_expr(&implicit.lhs, allowed);
        uses.extend(self.check_expr(&own.rhs, allowed));
        if self.diagnostics.len() > errors {
            return Vec::new();
        }
        let mut held: Vec<usize> = uses
            .iter()
            .filter(|u| u.order == k)
            .map(|u| u.coord)
            .collect();
        held.sort_unstable();
        held.dedup();
        for &candidate in &implicit.candidates {
            if !uses.iter().any(|u| u.coord == candidate && u.order == k) {
                let name = &self.coords[candidate].name;
                let diagnostic = Diagnostic::error(
                    codes::BAD_CANDIDATE,
                    format!(
                        "the constraint does not hold `{name}{}`",
                        "'".repeat(k as usize)
                    ),
                )
                .with_primary(own.span, "solved for a derivative it does not contain")
                .with_help("name after `for` derivatives that occur in the constraint");
                self.report(diagnostic);
            }
        }
        for used in uses {
            if used.order < k || implicit.candidates.contains(&used.coord) {
                continue;
            }
            if let Some(other) = all
                .iter()
                .find(|c| c.implicit.is_none() && c.coord == used.coord)
            {
                let name = &self.coords[used.coord].name;
                let diagnostic = Diagnostic::error(
                    codes::DEPENDENT_DERIVATIVE_IN_RHS,
                    format!(
                        "a constraint holds another constraint's dependent derivative of order {}",
                        used.order
                    ),
                )
                .with_primary(used.span, format!("`{name}` is dependent"))
                .with_secondary(other.span, format!("`{name}` is made dependent here"))
                .with_help("substitute that coordinate's constraint into this one");
                self.report(diagnostic);
            }
        }
        held
    }
}

/// The coordinates a constraint may make dependent.
fn owned_by(coord: usize, implicit: Option<&Implicit>) -> Vec<usize> {
    match implicit {
        Some(i) => i.candidates.clone(),
        None => vec![coord],
    }
}

fn bad_lhs(span: Span, label: &str) -> Diagnostic {
    Diagnostic::error(
        codes::CONSTRAINT_LHS,
        "a constraint's left side must be a derivative of a coordinate",
    )
    .with_primary(span, label.to_string())
    .with_help(
        "write it as `constraint q2' = …;` (the coordinate it makes dependent, with primes), \
         or name the derivative it is solved for: `… for q2'`; written without either, a \
         constraint is solved for the highest derivatives it holds that no other constraint fixes",
    )
}

/// At most this many constraints are solved together: the dependents of
/// a coupled group are solved symbolically by Cramer's rule over shared
/// minors (2^m of them), and the mechanics differentiates the solution.
/// Eight: a chain of eight links in Cartesian coordinates (one candidate
/// each) builds in 15 s on a loaded machine, its crate 0.9 MB, and agrees
/// with the chain in angles to 2e-13 (`docs/BENCHMARKS.md` §14.7); four,
/// the bound before, refused a five-link chain written as a user first
/// writes it.
pub const MAX_COUPLED: usize = 8;
/// At most this many reduced systems (modes) are derived for the choices
/// of dependents; each is a derivation and a part of the generated crate.
pub const MAX_MODES: usize = 64;
/// The modes times the minors of the largest group (2^m) are at most this
/// many: what 64 modes of groups of four cost. A group of eight with its
/// 256 minors is derived for at most four choices of dependents.
pub const MAX_MODE_MINORS: usize = MAX_MODES << 4;

impl Checker<'_> {
    /// The candidates of a constraint that holds derivatives, written
    /// without `for` and whose left side is an expression, not the
    /// derivative it fixes (`constraint x'^2 + y'^2 = v^2;`): as for a
    /// holonomic constraint, every coordinate whose derivative of the
    /// constraint's highest order it holds, the last declared first, but
    /// an explicit constraint's dependent. `None` where the left side is a
    /// single name (an explicit constraint, checked as such) or nothing is
    /// left to solve for (the left side's error then says what to write).
    fn automatic_candidates(
        &self,
        lhs: &Expr,
        rhs: &Expr,
        explicit_dependents: &[&str],
    ) -> Option<(u32, Vec<usize>)> {
        if matches!(lhs.kind, ExprKind::Var { .. }) {
            return None;
        }
        let mut held = Vec::new();
        self.derivatives_held(lhs, &mut held);
        self.derivatives_held(rhs, &mut held);
        let order = held.iter().map(|&(_, order)| order).max()?;
        if order == 0 || order > MAX_DERIVATIVE_ORDER {
            return None;
        }
        let mut owned: Vec<usize> = held
            .iter()
            .filter(|&&(coord, o)| {
                o == order && !explicit_dependents.contains(&self.coords[coord].name.as_str())
            })
            .map(|&(coord, _)| coord)
            .collect();
        owned.sort_unstable_by(|a, b| b.cmp(a));
        owned.dedup();
        (!owned.is_empty()).then_some((order, owned))
    }

    /// Every coordinate's derivative `expr` holds, through lets, as
    /// `(coordinate, order)` (positions included, with order 0).
    fn derivatives_held(&self, expr: &Expr, out: &mut Vec<(usize, u32)>) {
        match &expr.kind {
            ExprKind::Number(_) => {}
            ExprKind::Var { name, primes } => match self.names.get(&name.name).map(|d| d.name) {
                Some(Name::Coord(coord)) => out.push((coord, *primes)),
                Some(Name::Let(i)) => {
                    if let Some(l) = self.lets.get(i) {
                        out.extend(l.uses.coords.iter().map(|u| (u.coord, u.order + primes)));
                    }
                }
                _ => {}
            },
            ExprKind::Neg(e) | ExprKind::Not(e) => self.derivatives_held(e, out),
            ExprKind::Component { base, .. } => self.derivatives_held(base, out),
            ExprKind::Binary { lhs, rhs, .. }
            | ExprKind::Compare { lhs, rhs, .. }
            | ExprKind::Logic { lhs, rhs, .. } => {
                self.derivatives_held(lhs, out);
                self.derivatives_held(rhs, out);
            }
            ExprKind::Call { args, .. } | ExprKind::Vector(args) => {
                for a in args {
                    self.derivatives_held(a, out);
                }
            }
            ExprKind::If {
                cond,
                then,
                otherwise,
            } => {
                self.derivatives_held(cond, out);
                self.derivatives_held(then, out);
                self.derivatives_held(otherwise, out);
            }
        }
    }

    /// A constraint without any derivative on either side, whose left side
    /// is not one (`constraint x^2 + y^2 = l^2;`, `constraint y = x^2;`).
    fn is_holonomic(&self, lhs: &Expr, rhs: &Expr) -> bool {
        !self.holds_derivative(lhs) && !self.holds_derivative(rhs)
    }

    /// Whether `expr` holds a derivative, through a let included.
    fn holds_derivative(&self, expr: &Expr) -> bool {
        match &expr.kind {
            ExprKind::Number(_) => false,
            ExprKind::Var { name, primes } => {
                *primes > 0
                    || match self.names.get(&name.name).map(|d| d.name) {
                        Some(Name::Let(i)) => self
                            .lets
                            .get(i)
                            .is_some_and(|l| l.uses.coords.iter().any(|u| u.order > 0)),
                        _ => false,
                    }
            }
            ExprKind::Neg(e) | ExprKind::Not(e) => self.holds_derivative(e),
            ExprKind::Component { base, .. } => self.holds_derivative(base),
            ExprKind::Binary { lhs, rhs, .. }
            | ExprKind::Compare { lhs, rhs, .. }
            | ExprKind::Logic { lhs, rhs, .. } => {
                self.holds_derivative(lhs) || self.holds_derivative(rhs)
            }
            ExprKind::Call { args, .. } | ExprKind::Vector(args) => {
                args.iter().any(|a| self.holds_derivative(a))
            }
            ExprKind::If {
                cond,
                then,
                otherwise,
            } => {
                self.holds_derivative(cond)
                    || self.holds_derivative(then)
                    || self.holds_derivative(otherwise)
            }
        }
    }

    /// A holonomic constraint `lhs = rhs` (SPEC §2.3): both sides checked
    /// as expressions of `t`, params, masses and coordinates; its
    /// candidates are the coordinates named after `for`, or (computed once
    /// every constraint is known, [`Checker::holonomic_candidates`]) the
    /// coordinate on its left side, else every coordinate it holds. Returns
    /// the constraint (of order 0 until the model's order is known) and the
    /// coordinates it holds.
    fn holonomic(
        &mut self,
        lhs: &Expr,
        rhs: &Expr,
        candidates: &[Expr],
        span: Span,
    ) -> Option<(Constraint, Vec<usize>)> {
        let allowed = Allowed {
            time: true,
            masses: true,
            coord_order: Some(0),
            ..Allowed::constants("a constraint")
        };
        let errors = self.diagnostics.len();
        let mut uses = self.check_expr(lhs, allowed);
        uses.extend(self.check_expr(rhs, allowed));
        if self.diagnostics.len() > errors {
            return None;
        }
        let mut held: Vec<usize> = uses.iter().map(|u| u.coord).collect();
        held.sort_unstable();
        held.dedup();
        if held.is_empty() {
            let diagnostic = Diagnostic::error(
                codes::CONSTRAINT_LHS,
                "a constraint without derivatives must hold a coordinate",
            )
            .with_primary(span, "no coordinate here")
            .with_help(
                "a holonomic constraint `f(t, q) = 0` relates coordinates, e.g. \
                 `constraint x^2 + y^2 = l^2;`",
            );
            self.report(diagnostic);
            return None;
        }
        let mut named = Vec::new();
        for candidate in candidates {
            let ExprKind::Var { name, primes } = &candidate.kind else {
                self.report(bad_lhs(candidate.span, "not a coordinate"));
                return None;
            };
            let coord = match self.names.get(&name.name).map(|d| d.name) {
                Some(Name::Coord(coord)) if *primes == 0 => coord,
                Some(Name::Coord(_)) => {
                    let diagnostic = Diagnostic::error(
                        codes::BAD_CANDIDATE,
                        format!(
                            "`for` names `{}{}`, but the constraint holds no derivative",
                            name.name,
                            "'".repeat(*primes as usize)
                        ),
                    )
                    .with_primary(candidate.span, "a derivative")
                    .with_help(format!(
                        "a constraint without derivatives is solved for coordinates: `for {}`",
                        name.name
                    ));
                    self.report(diagnostic);
                    return None;
                }
                _ => {
                    self.constraint_lhs(candidate);
                    return None;
                }
            };
            if named.contains(&coord) {
                let diagnostic =
                    Diagnostic::error(codes::BAD_CANDIDATE, "a candidate is named twice")
                        .with_primary(candidate.span, "named again here");
                self.report(diagnostic);
                return None;
            }
            if !held.contains(&coord) {
                let diagnostic = Diagnostic::error(
                    codes::BAD_CANDIDATE,
                    format!("the constraint does not hold `{}`", name.name),
                )
                .with_primary(
                    candidate.span,
                    "solved for a coordinate it does not contain",
                )
                .with_help("name after `for` coordinates that occur in the constraint");
                self.report(diagnostic);
                return None;
            }
            named.push(coord);
        }
        // `constraint y = f(x);`: solved for `y`, as `y' = …` is for `y'`.
        if named.is_empty() {
            if let ExprKind::Var { name, primes: 0 } = &lhs.kind {
                if let Some(Name::Coord(coord)) = self.names.get(&name.name).map(|d| d.name) {
                    named.push(coord);
                }
            }
        }
        let constraint = Constraint {
            coord: named.first().copied().unwrap_or(held[0]),
            order: 0,
            rhs: rhs.clone(),
            span,
            text: String::new(),
            implicit: Some(Implicit {
                lhs: lhs.clone(),
                candidates: named,
                holonomic: true,
                raised: false,
            }),
        };
        Some((constraint, held))
    }

    /// Completes the candidates of the holonomic constraints: those named
    /// (or the left side's coordinate) must not be an explicit
    /// constraint's dependent; without them, every coordinate the
    /// constraint holds that no explicit constraint makes dependent, the
    /// last declared first.
    fn holonomic_candidates(&mut self, constraints: &mut [Constraint], held: &[Vec<usize>]) {
        let explicit: Vec<(usize, Span)> = constraints
            .iter()
            .filter(|c| c.implicit.is_none())
            .map(|c| (c.coord, c.span))
            .collect();
        for (c, held) in constraints.iter_mut().zip(held) {
            let Some(implicit) = c.implicit.as_mut().filter(|i| i.holonomic) else {
                continue;
            };
            if implicit.candidates.is_empty() {
                implicit.candidates = held
                    .iter()
                    .rev()
                    .copied()
                    .filter(|j| !explicit.iter().any(|&(e, _)| e == *j))
                    .collect();
            } else if let Some(&(j, first)) = explicit
                .iter()
                .find(|(e, _)| implicit.candidates.contains(e))
            {
                let name = &self.coords[j].name;
                let diagnostic = Diagnostic::error(
                    codes::DOUBLE_CONSTRAINT,
                    format!("coordinate `{name}` is constrained twice"),
                )
                .with_primary(c.span, "second constraint on it here")
                .with_secondary(first, "first constraint here")
                .with_help("solve this constraint for another coordinate: `for …`");
                self.report(diagnostic);
                self.constraints_incomplete = true;
                implicit.candidates.clear();
            }
            if implicit.candidates.is_empty() {
                if !self.constraints_incomplete {
                    let diagnostic = Diagnostic::error(
                        codes::DOUBLE_CONSTRAINT,
                        "every coordinate of this constraint is already dependent",
                    )
                    .with_primary(c.span, "no coordinate left to solve it for")
                    .with_help("each constraint makes one coordinate dependent");
                    self.report(diagnostic);
                }
                self.constraints_incomplete = true;
                continue;
            }
            c.coord = implicit.candidates[0];
        }
    }

    /// The groups of implicit constraints solved together: connected by a
    /// shared candidate, or by one holding another's candidate at the
    /// constraint order. Each group of m constraints is solved for m of
    /// the union of its candidates (in order: each constraint's candidates
    /// as written, then the next constraint's new ones); a choice is kept
    /// when every constraint can be matched to a chosen coordinate it holds
    /// (otherwise the block of the chosen derivatives is singular whatever
    /// the state). The constraints' `coord` is set from the first choice.
    fn groups(&mut self, constraints: &mut [Constraint], held: &[Vec<usize>]) -> Vec<Group> {
        let implicit: Vec<usize> = (0..constraints.len())
            .filter(|&i| {
                constraints[i]
                    .implicit
                    .as_ref()
                    .is_some_and(|im| !im.candidates.is_empty())
            })
            .collect();
        let candidate_lists: Vec<Vec<usize>> = constraints
            .iter()
            .map(|c| {
                c.implicit
                    .as_ref()
                    .map_or(Vec::new(), |im| im.candidates.clone())
            })
            .collect();
        let candidates_of = |i: usize| -> &[usize] { &candidate_lists[i] };
        // Union–find by the smallest index.
        let mut root: Vec<usize> = (0..constraints.len()).collect();
        fn find(root: &mut [usize], i: usize) -> usize {
            let mut r = i;
            while root[r] != r {
                r = root[r];
            }
            root[i] = r;
            r
        }
        for (x, &a) in implicit.iter().enumerate() {
            for &b in &implicit[x + 1..] {
                let touches = |p: usize, q: usize| {
                    candidates_of(q)
                        .iter()
                        .any(|j| candidates_of(p).contains(j) || held[p].contains(j))
                };
                if touches(a, b) || touches(b, a) {
                    let (ra, rb) = (find(&mut root, a), find(&mut root, b));
                    root[ra.max(rb)] = ra.min(rb);
                }
            }
        }
        let mut groups = Vec::new();
        let mut modes: usize = 1;
        let mut largest: usize = 0;
        for &first in &implicit {
            if find(&mut root, first) != first {
                continue;
            }
            let members: Vec<usize> = implicit
                .iter()
                .copied()
                .filter(|&i| find(&mut root, i) == first)
                .collect();
            let mut union: Vec<usize> = Vec::new();
            for &i in &members {
                for &j in candidates_of(i) {
                    if !union.contains(&j) {
                        union.push(j);
                    }
                }
            }
            let last = constraints[*members.last().unwrap_or(&first)].span;
            if members.len() > MAX_COUPLED {
                let diagnostic = Diagnostic::error(
                    codes::BAD_CANDIDATE,
                    format!(
                        "{} constraints are coupled; lagc solves at most {MAX_COUPLED} together",
                        members.len()
                    ),
                )
                .with_primary(last, "coupled with the constraints before it")
                .with_note(
                    "constraints that share candidates (or hold each other's) are solved \
                     together, symbolically",
                )
                .with_help(
                    "choose coordinates that decouple the constraints (a chain or a linkage: \
                     each link's angle as a coordinate, its points written from the angles, \
                     needs no constraint for the links' lengths), or name fewer candidates \
                     after `for`",
                );
                self.report(diagnostic);
                continue;
            }
            let mut choices: Vec<Vec<usize>> = subsets(union.len(), members.len())
                .into_iter()
                .filter_map(|subset| {
                    let chosen: Vec<usize> = subset.iter().map(|&u| union[u]).collect();
                    matching(&members, &chosen, held, constraints)
                })
                .collect();
            // The first choice: each constraint its first candidate that an
            // earlier one has not taken (what `for y' or x'` on each says),
            // when that works.
            let mut greedy: Vec<usize> = Vec::new();
            for &i in &members {
                if let Some(&j) = candidates_of(i).iter().find(|j| !greedy.contains(j)) {
                    greedy.push(j);
                }
            }
            let same_set = |a: &[usize], b: &[usize]| a.iter().all(|j| b.contains(j));
            if greedy.len() == members.len() {
                if let Some(at) = choices.iter().position(|c| same_set(c, &greedy)) {
                    choices.remove(at);
                    choices.insert(0, greedy);
                }
            }
            if choices.is_empty() {
                let names: Vec<String> = union
                    .iter()
                    .map(|&j| format!("`{}`", self.coords[j].name))
                    .collect();
                let mut diagnostic = Diagnostic::error(
                    codes::DOUBLE_CONSTRAINT,
                    format!(
                        "{} constraints solved together have too few candidates ({})",
                        members.len(),
                        names.join(", ")
                    ),
                )
                .with_primary(last, "no candidate left for this constraint");
                for &i in &members[..members.len() - 1] {
                    diagnostic =
                        diagnostic.with_secondary(constraints[i].span, "solved together with it");
                }
                let diagnostic = diagnostic.with_help(
                    "each constraint makes one coordinate dependent: name another candidate \
                     after `for` (`for y' or x'`)",
                );
                self.report(diagnostic);
                self.constraints_incomplete = true;
                continue;
            }
            modes = modes.saturating_mul(choices.len());
            largest = largest.max(members.len());
            if modes <= MAX_MODES && modes.saturating_mul(1 << largest) > MAX_MODE_MINORS {
                let diagnostic = Diagnostic::error(
                    codes::BAD_CANDIDATE,
                    format!(
                        "{modes} reduced systems of {largest} constraints solved together are \
                         more than lagc derives"
                    ),
                )
                .with_primary(
                    last,
                    format!("{} choices of dependents here", choices.len()),
                )
                .with_note(format!(
                    "lagc derives one reduced system for each choice of dependent coordinates, \
                     each solving its group by 2^m minors: at most {MAX_MODE_MINORS} minors in all"
                ))
                .with_help(
                    "name fewer candidates after `for` (one each: `for y2`), or choose \
                     coordinates that decouple the constraints (a chain's links by their angles)",
                );
                self.report(diagnostic);
                continue;
            }
            if modes > MAX_MODES {
                let diagnostic = Diagnostic::error(
                    codes::BAD_CANDIDATE,
                    format!(
                        "the constraints' candidates make more than {MAX_MODES} reduced systems"
                    ),
                )
                .with_primary(
                    last,
                    format!("{} choices of dependents here", choices.len()),
                )
                .with_note(
                    "lagc derives one reduced system for each choice of dependent coordinates \
                     and switches between them at run time",
                )
                .with_help("name the candidates after `for` (`for y or x`) to choose among fewer");
                self.report(diagnostic);
                continue;
            }
            for (&i, &j) in members.iter().zip(&choices[0]) {
                constraints[i].coord = j;
            }
            groups.push(Group {
                constraints: members,
                choices,
            });
        }
        groups
    }
}

/// Every `m`-subset of `0..n`, in lexicographic order.
fn subsets(n: usize, m: usize) -> Vec<Vec<usize>> {
    let mut all = Vec::new();
    if m > n {
        return all;
    }
    let mut current: Vec<usize> = (0..m).collect();
    loop {
        all.push(current.clone());
        let Some(i) = (0..m).rev().find(|&i| current[i] < n - m + i) else {
            return all;
        };
        current[i] += 1;
        for j in i + 1..m {
            current[j] = current[j - 1] + 1;
        }
    }
}

/// A coordinate of `chosen` for each of `members`, one it holds, all
/// distinct (a perfect matching by augmenting paths; the first found,
/// preferring each constraint's candidates in its own order), or `None`.
fn matching(
    members: &[usize],
    chosen: &[usize],
    held: &[Vec<usize>],
    constraints: &[Constraint],
) -> Option<Vec<usize>> {
    let holds = |i: usize, j: usize| {
        let own = constraints[i]
            .implicit
            .as_ref()
            .is_some_and(|im| im.candidates.contains(&j));
        own || held[i].contains(&j)
    };
    // Each constraint's options: its own candidates first, in its order.
    let options: Vec<Vec<usize>> = members
        .iter()
        .map(|&i| {
            let own: Vec<usize> = constraints[i]
                .implicit
                .as_ref()
                .map_or(Vec::new(), |im| im.candidates.clone());
            let mut o: Vec<usize> = own.into_iter().filter(|j| chosen.contains(j)).collect();
            let more: Vec<usize> = chosen
                .iter()
                .copied()
                .filter(|&j| holds(i, j) && !o.contains(&j))
                .collect();
            o.extend(more);
            o
        })
        .collect();
    let mut owner: Vec<Option<usize>> = vec![None; chosen.len()];
    fn augment(
        m: usize,
        options: &[Vec<usize>],
        chosen: &[usize],
        owner: &mut [Option<usize>],
        seen: &mut [bool],
    ) -> bool {
        for &j in &options[m] {
            let slot = chosen.iter().position(|&c| c == j).unwrap_or(0);
            if seen[slot] {
                continue;
            }
            seen[slot] = true;
            if owner[slot].is_none_or(|other| augment(other, options, chosen, owner, seen)) {
                owner[slot] = Some(m);
                return true;
            }
        }
        false
    }
    for m in 0..members.len() {
        let mut seen = vec![false; chosen.len()];
        if !augment(m, &options, chosen, &mut owner, &mut seen) {
            return None;
        }
    }
    let mut assigned = vec![0; members.len()];
    for (slot, o) in owner.iter().enumerate() {
        if let Some(m) = o {
            assigned[*m] = chosen[slot];
        }
    }
    Some(assigned)
}
