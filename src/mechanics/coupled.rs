//! Implicit constraints solved together (SPEC §2.3): the residuals `h_ν`
//! of a group (an implicit constraint's `lhs − rhs`, a holonomic one's
//! k-th total derivative `D^k f`) are linear in the chosen dependents'
//! order-k derivatives `z`, `h = A z + r`; the dependents are
//! `z = −A⁻¹ r`, by Cramer's rule.
//!
//! Why symbolic, when SPEC §1.4 asks for a numeric solve of mass matrices
//! beyond s = 2: the solution `φ` is not only evaluated but substituted
//! into `L^(k)`, differentiated (`Dφ` into `L^(k+1)`, `∂φ/∂q_i^(k)` for the
//! projection) and eliminated from equations (4) — the order-matched star
//! needs it as an expression. A group holds at most
//! [`crate::check::MAX_COUPLED`] constraints; the Laplace expansion's
//! minors are shared nodes of the arena (hash-consed), so `det A` and the
//! m numerators cost 2^m minors, not m!, and the emitted code computes
//! each once. A numeric solve would need the mechanics to carry `φ`
//! implicitly (and its derivatives through the implicit function
//! theorem), which the cross-check then could not compare term by term.

use crate::check::model::{Constraint, Model};
use crate::diagnostic::{codes, Diagnostic};
use crate::ir::{Arena, ExprId, Symbol};
use std::collections::HashMap;

/// The residual `h = 0` of order k of an implicit constraint: `lhs − rhs`,
/// or for a holonomic one `D^k (lhs − rhs)` (mass symbols replaced by
/// their laws first, `laws`: the true time derivative). `None` for an
/// explicit constraint.
pub fn residual(
    arena: &mut Arena,
    model: &Model,
    c: &Constraint,
    laws: &HashMap<Symbol, ExprId>,
) -> Result<Option<ExprId>, Diagnostic> {
    let Some(implicit) = &c.implicit else {
        return Ok(None);
    };
    let lhs = super::symbols::lower_checked(arena, &implicit.lhs, model)?;
    let rhs = super::symbols::lower_checked(arena, &c.rhs, model)?;
    let h = arena.sub(lhs, rhs);
    if implicit.raised {
        // Not linear in its candidates of order k − 1 (or beside one that
        // is not): its total derivative is linear in those of order k.
        // A candidate it switches on has no derivative there.
        for &j in &implicit.candidates {
            let written = Symbol::Jet {
                coord: j as u32,
                order: c.order - 1,
            };
            if arena.switches_on(h, written) {
                let name = arena.symbol_name(written);
                return Err(Diagnostic::error(
                    codes::BAD_CANDIDATE,
                    format!("the constraint switches on `{name}`"),
                )
                .with_primary(c.span, format!("`{name}` enters through a selection (`if`, `abs`, `sign`, `min`, `max`)"))
                .with_note("a constraint is solved through its derivative in its candidate, which a switch on the candidate does not have")
                .with_help(format!("solve the constraint for `{name}` and write it explicitly: `constraint {name} = …;`")));
            }
        }
        let h = arena.subst(h, laws);
        return Ok(Some(arena.total_derivative(h)));
    }
    if !implicit.holonomic {
        return Ok(Some(h));
    }
    let mut h = arena.subst(h, laws);
    for _ in 0..c.order {
        h = arena.total_derivative(h);
    }
    Ok(Some(h))
}

/// A raised constraint's `f = lhs − rhs` as written, of order k − 1 (mass
/// symbols replaced by their laws): the run keeps `f = 0`.
pub fn written_residual(
    arena: &mut Arena,
    model: &Model,
    c: &Constraint,
    laws: &HashMap<Symbol, ExprId>,
) -> Result<ExprId, Diagnostic> {
    let implicit = c.implicit.as_ref().filter(|i| i.raised);
    let Some(implicit) = implicit else {
        return Err(Diagnostic::error(
            codes::BAD_CANDIDATE,
            "internal error: the written residual of a constraint that is not raised",
        ));
    };
    let lhs = super::symbols::lower_checked(arena, &implicit.lhs, model)?;
    let rhs = super::symbols::lower_checked(arena, &c.rhs, model)?;
    let f = arena.sub(lhs, rhs);
    Ok(arena.subst(f, laws))
}

/// The holonomic constraint's `f = lhs − rhs` (mass symbols replaced by
/// their laws).
pub fn position_residual(
    arena: &mut Arena,
    model: &Model,
    c: &Constraint,
    laws: &HashMap<Symbol, ExprId>,
) -> Result<ExprId, Diagnostic> {
    let implicit = c.implicit.as_ref().filter(|i| i.holonomic);
    let Some(implicit) = implicit else {
        return Err(Diagnostic::error(
            codes::CONSTRAINT_LHS,
            "internal error: a position residual of a constraint that is not holonomic",
        ));
    };
    let lhs = super::symbols::lower_checked(arena, &implicit.lhs, model)?;
    let rhs = super::symbols::lower_checked(arena, &c.rhs, model)?;
    let f = arena.sub(lhs, rhs);
    Ok(arena.subst(f, laws))
}

/// `∂h_ν/∂z_c`, row-major.
pub fn block(arena: &mut Arena, residuals: &[ExprId], unknowns: &[Symbol]) -> Vec<Vec<ExprId>> {
    residuals
        .iter()
        .map(|&h| unknowns.iter().map(|&z| arena.diff(h, z)).collect())
        .collect()
}

/// The determinant of a square matrix of expressions, by Laplace
/// expansion along the rows with the minors memoised by their columns.
pub fn determinant(arena: &mut Arena, a: &[Vec<ExprId>]) -> ExprId {
    let m = a.len();
    let mut memo: HashMap<u64, ExprId> = HashMap::new();
    minor(arena, a, (1u64 << m) - 1, &mut memo)
}

/// The determinant of the rows `m − |columns| .. m` and the `columns` (a
/// bit set).
fn minor(
    arena: &mut Arena,
    a: &[Vec<ExprId>],
    columns: u64,
    memo: &mut HashMap<u64, ExprId>,
) -> ExprId {
    if columns == 0 {
        return arena.one();
    }
    if let Some(&d) = memo.get(&columns) {
        return d;
    }
    let m = a.len();
    let row = m - columns.count_ones() as usize;
    let mut terms = Vec::new();
    let mut sign = 1.0;
    for c in 0..m {
        if columns & (1 << c) == 0 {
            continue;
        }
        if !arena.is_zero(a[row][c]) {
            let rest = minor(arena, a, columns & !(1 << c), memo);
            let term = arena.mul(&[a[row][c], rest]);
            terms.push(if sign < 0.0 { arena.neg(term) } else { term });
        }
        sign = -sign;
    }
    let d = arena.add(&terms);
    memo.insert(columns, d);
    d
}

/// Solves `h(z) = 0`, linear in `z`, for `z` by Cramer's rule: `(z_c)`
/// with `z_c = det(A with column c replaced by −r) / det A`. `span` and
/// `names` place and word the errors: a residual not linear in `z`, or a
/// determinant that is identically zero.
pub fn solve(
    arena: &mut Arena,
    residuals: &[ExprId],
    unknowns: &[Symbol],
    span: crate::span::Span,
) -> Result<Vec<ExprId>, Diagnostic> {
    let names: Vec<String> = unknowns
        .iter()
        .map(|&z| format!("`{}`", arena.symbol_name(z)))
        .collect();
    let a = block(arena, residuals, unknowns);
    for (&h, row) in residuals.iter().zip(&a) {
        for (&z, &entry) in unknowns.iter().zip(row) {
            if unknowns.iter().any(|&w| arena.depends_on(entry, w)) || arena.switches_on(h, z) {
                let name = arena.symbol_name(z);
                return Err(Diagnostic::error(
                    codes::BAD_CANDIDATE,
                    format!("the constraints solved together are not linear in `{name}`"),
                )
                .with_primary(span, format!("`{name}` enters non-linearly"))
                .with_note("lagc solves implicit constraints for their dependents symbolically, which needs them to enter linearly"));
            }
        }
    }
    let det = determinant(arena, &a);
    if arena.is_zero(det) {
        return Err(Diagnostic::error(
            codes::BAD_CANDIDATE,
            format!(
                "the constraints solved together do not determine {}",
                names.join(", ")
            ),
        )
        .with_primary(
            span,
            "their determinant in these derivatives is identically 0",
        )
        .with_help("the constraints are dependent: remove one, or name other candidates"));
    }
    let zero = arena.zero();
    let at_zero: HashMap<Symbol, ExprId> = unknowns.iter().map(|&z| (z, zero)).collect();
    let minus_r: Vec<ExprId> = residuals
        .iter()
        .map(|&h| {
            let r = arena.subst(h, &at_zero);
            arena.neg(r)
        })
        .collect();
    let mut solution = Vec::with_capacity(unknowns.len());
    for c in 0..unknowns.len() {
        let replaced: Vec<Vec<ExprId>> = a
            .iter()
            .zip(&minus_r)
            .map(|(row, &v)| {
                let mut row = row.clone();
                row[c] = v;
                row
            })
            .collect();
        let numerator = determinant(arena, &replaced);
        solution.push(arena.div(numerator, det));
    }
    Ok(solution)
}

/// The holonomic constraints of a model (in its mode): `f_ν = 0` with
/// each one's dependent coordinate as the Newton unknowns. `None` when it
/// has none.
pub fn closure(
    arena: &mut Arena,
    model: &Model,
    laws: &HashMap<Symbol, ExprId>,
) -> Result<Option<super::reduced::Closure>, Diagnostic> {
    let mut unknowns = Vec::new();
    let mut residual = Vec::new();
    let mut texts = Vec::new();
    for c in model.constraints.iter().filter(|c| c.is_holonomic()) {
        let f = position_residual(arena, model, c, &HashMap::new())?;
        texts.push(if c.text.is_empty() {
            format!("{} = 0", arena.display(f))
        } else {
            c.text.clone()
        });
        residual.push(arena.subst(f, laws));
        unknowns.push(Symbol::Jet {
            coord: c.coord as u32,
            order: 0,
        });
    }
    if residual.is_empty() {
        return Ok(None);
    }
    let jacobian = block(arena, &residual, &unknowns);
    let coordinates: Vec<Symbol> = (0..model.coords.len() as u32)
        .map(|coord| Symbol::Jet { coord, order: 0 })
        .collect();
    let normals = block(arena, &residual, &coordinates);
    let u = model.constraint_order.unwrap_or(1).max(2);
    let mut levels: Vec<Vec<ExprId>> = Vec::new();
    let mut level = residual.clone();
    for _ in 1..u {
        level = level.iter().map(|&f| arena.total_derivative(f)).collect();
        levels.push(level.clone());
    }
    Ok(Some(super::reduced::Closure {
        unknowns,
        residual,
        jacobian,
        text: texts.join("; "),
        normals,
        levels,
    }))
}

/// For k ≥ 2: the dependent coordinates' derivatives of order `1..k` that
/// the holonomic constraints fix, `D^r f = 0` solved for `q_d^(r)` with
/// the lower orders substituted (each an expression of `t`, params, the
/// positions and the other coordinates' derivatives). `explicit` replaces
/// the explicit constraints' dependents' derivatives of order k (none of
/// order below k is fixed by them). Empty for k = 1.
pub fn holonomic_levels(
    arena: &mut Arena,
    model: &Model,
    closure: &super::reduced::Closure,
    k: u32,
    span: crate::span::Span,
) -> Result<HashMap<Symbol, ExprId>, Diagnostic> {
    let mut fixed: HashMap<Symbol, ExprId> = HashMap::new();
    let mut level: Vec<ExprId> = closure.residual.clone();
    let _ = model;
    for r in 1..k {
        let unknowns: Vec<Symbol> = closure
            .unknowns
            .iter()
            .map(|&s| match s {
                Symbol::Jet { coord, .. } => Symbol::Jet { coord, order: r },
                other => other,
            })
            .collect();
        level = level
            .iter()
            .map(|&f| {
                let d = arena.total_derivative(f);
                arena.subst(d, &fixed)
            })
            .collect();
        let solution = solve(arena, &level, &unknowns, span)?;
        for (z, e) in unknowns.into_iter().zip(solution) {
            fixed.insert(z, e);
        }
    }
    Ok(fixed)
}
