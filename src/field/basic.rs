//! The basic equation (9) with the ansatz (10) inserted, collected into the
//! coefficient system.
//!
//! With `x_1 = Φ = f_1 + Σ_A f_A x_A` the basic equation is
//! `∂Φ/∂t + Σ_A ∂Φ/∂x_A X_A(t, Φ, x) − X_1(t, Φ, x) = 0`, i.e.
//! `f_1' + Σ_A f_A' x_A + G = 0` with `G = Σ_A f_A X_A(Φ) − X_1(Φ)`. When `G`
//! is affine in `x_2..x_N` it holds for every `x` iff the free term and each
//! coefficient vanish: `f_1' = −G|_{x=0}`, `f_B' = −∂G/∂x_B`.

use crate::ir::{Arena, ExprId, Symbol};
use crate::mechanics::{Highest, ReducedSystem};
use std::collections::HashMap;

/// The field method's view of a reduced system.
#[derive(Debug, Clone)]
pub struct FieldSystem {
    /// `X_A(t, x)` for every state component (`None` for an implicit
    /// system, whose highest derivatives are not symbolic expressions).
    pub motion: Option<Vec<ExprId>>,
    /// The coefficients `f_1..f_N` (`Symbol::Aux` named `f1`..`fN`).
    pub coefficients: Vec<Symbol>,
    /// Their derivatives `f_1'..f_N'` (`Symbol::Aux` named `f1'`..), used
    /// only in the text of (9).
    pub coefficient_rates: Vec<Symbol>,
    /// The left side of (9) with the ansatz inserted (explicit systems).
    pub basic_equation: Option<ExprId>,
    /// The coefficient system when `X` is affine in `x_2..x_N` after the
    /// ansatz (the linear ansatz is then a complete solution).
    pub coefficient_system: Option<CoefficientSystem>,
}

/// `f' = F(t, f)` and what the emitter needs about it.
#[derive(Debug, Clone)]
pub struct CoefficientSystem {
    /// `F_A(t, f)`, one per coefficient.
    pub rhs: Vec<ExprId>,
    /// `∂F_A/∂f_B`, row-major.
    pub jacobian: Vec<Vec<ExprId>>,
    /// `∂F_A/∂t`.
    pub time_partial: Vec<ExprId>,
    /// No `X_A` (A ≥ 2) depends on `x_1` (`a_A1 = 0`): `F` is affine in `f`.
    /// Otherwise the system is of Riccati type.
    pub linear: bool,
    /// `F_A ≡ 0`: the coefficient stays at its anchor value `c_A`.
    pub constant: Vec<bool>,
}

impl FieldSystem {
    /// Whether the linear ansatz solves the system completely.
    pub fn is_affine(&self) -> bool {
        self.coefficient_system.is_some()
    }
}

/// `X(t, x)` of the reduced system, one expression per state component:
/// `(q^(r))' = q^(r+1)` below the highest order, the highest derivatives
/// from (7). `None` when the highest derivatives are implicit.
pub fn motion_expressions(arena: &mut Arena, reduced: &ReducedSystem) -> Option<Vec<ExprId>> {
    let Highest::Explicit(highest) = &reduced.highest else {
        return None;
    };
    let u = reduced.order;
    let mut out = Vec::with_capacity(reduced.state.len());
    for &s in &reduced.state {
        let Symbol::Jet { coord, order } = s else {
            return None;
        };
        if order + 1 < u {
            out.push(arena.jet(coord, order + 1));
        } else {
            out.push(*highest.get(coord as usize)?);
        }
    }
    Some(out)
}

/// Builds (9) and the coefficient system of `reduced`.
pub fn field_system(arena: &mut Arena, reduced: &ReducedSystem) -> FieldSystem {
    let n = reduced.state.len();
    let coefficients: Vec<Symbol> = (1..=n).map(|a| arena.aux(&format!("f{a}"))).collect();
    let coefficient_rates: Vec<Symbol> = (1..=n).map(|a| arena.aux(&format!("f{a}'"))).collect();
    let motion = motion_expressions(arena, reduced);
    let mut field = FieldSystem {
        motion: motion.clone(),
        coefficients,
        coefficient_rates,
        basic_equation: None,
        coefficient_system: None,
    };
    let Some(x_rates) = motion else {
        return field;
    };
    if n == 0 {
        return field;
    }
    let state = &reduced.state;
    let f: Vec<ExprId> = field
        .coefficients
        .iter()
        .map(|&s| arena.symbol(s))
        .collect();
    // Φ = f_1 + Σ_A f_A x_A
    let mut phi_terms = vec![f[0]];
    for a in 1..n {
        let x_a = arena.symbol(state[a]);
        phi_terms.push(arena.mul(&[f[a], x_a]));
    }
    let phi = arena.add(&phi_terms);
    let on_field: HashMap<Symbol, ExprId> = HashMap::from([(state[0], phi)]);
    // G = Σ_A f_A X_A(Φ) − X_1(Φ)
    let mut g_terms = Vec::with_capacity(n);
    let x1 = arena.subst(x_rates[0], &on_field);
    g_terms.push(arena.neg(x1));
    for a in 1..n {
        let x_a = arena.subst(x_rates[a], &on_field);
        g_terms.push(arena.mul(&[f[a], x_a]));
    }
    let g = arena.add(&g_terms);
    // (9): ∂Φ/∂t + G with ∂Φ/∂t = f_1' + Σ_A f_A' x_A.
    let mut lhs_terms = vec![arena.symbol(field.coefficient_rates[0])];
    for (&rate, &x_a) in field.coefficient_rates.iter().zip(state).skip(1) {
        let rate = arena.symbol(rate);
        let x_a = arena.symbol(x_a);
        lhs_terms.push(arena.mul(&[rate, x_a]));
    }
    lhs_terms.push(g);
    field.basic_equation = Some(arena.add(&lhs_terms));

    let free_state = &state[1..];
    if !arena.is_affine_in(g, free_state) {
        return field;
    }
    let (slopes, free) = arena.affine_parts(g, free_state);
    let mut rhs = Vec::with_capacity(n);
    rhs.push(negate(arena, free));
    for slope in slopes {
        rhs.push(negate(arena, slope));
    }
    let jacobian = rhs
        .iter()
        .map(|&r| {
            field
                .coefficients
                .iter()
                .map(|&fb| arena.diff(r, fb))
                .collect()
        })
        .collect();
    let time_partial = rhs.iter().map(|&r| arena.diff(r, Symbol::Time)).collect();
    let linear = x_rates[1..]
        .iter()
        .all(|&x_a| !arena.depends_on(x_a, state[0]));
    let constant = rhs.iter().map(|&r| arena.is_zero(r)).collect();
    field.coefficient_system = Some(CoefficientSystem {
        rhs,
        jacobian,
        time_partial,
        linear,
        constant,
    });
    field
}

/// `−e`, distributed over a sum so that the text reads `1 - f3*…`
/// rather than `-(-1 + f3*…)` (the canonical `neg` keeps sums whole).
fn negate(arena: &mut Arena, e: ExprId) -> ExprId {
    match arena.node(e) {
        crate::ir::Node::Add(terms) => {
            let terms = terms.to_vec();
            let negated: Vec<ExprId> = terms.into_iter().map(|t| arena.neg(t)).collect();
            arena.add(&negated)
        }
        _ => arena.neg(e),
    }
}

/// The note SPEC §1.5 asks for when the linear ansatz is not a complete
/// solution; `None` when it is.
pub fn local_field_note(
    field: &FieldSystem,
    lagrangian: crate::span::Span,
) -> Option<crate::diagnostic::Diagnostic> {
    if field.is_affine() {
        return None;
    }
    let why = if field.motion.is_none() {
        "the highest derivatives are implicit (solved numerically)"
    } else {
        "the reduced system (7) is not affine in the state"
    };
    Some(
        crate::diagnostic::Diagnostic::note_diagnostic(
            crate::diagnostic::codes::LOCAL_FIELD_METHOD,
            "the linear field ansatz is not a complete solution of this system",
        )
        .with_primary(lagrangian, "the equations of motion come from here")
        .with_note(format!(
            "{why}, so `x1 = f1 + Σ fA·xA` cannot satisfy the basic equation (9) for \
             every state"
        ))
        .with_note(
            "the generated crate uses the quasilinear field method: on each window, the \
             field of the system linearised along a predicted motion (Newton–Kantorovich), \
             re-anchored where the window ends",
        ),
    )
}
