//! A mass matrix `∂(4)/∂q_i^(u)` that is singular at every point: the
//! equations do not determine the motion (e.g. a coordinate without kinetic
//! energy), so there is no reduced system to integrate (diagnostic E0015).

use super::sample::{Rng, SamplePoint};
use crate::diagnostic::{codes, Diagnostic};
use crate::ir::{Arena, ExprId, Symbol};
use crate::span::Span;
use nalgebra::DMatrix;

/// Random points at which the rank is tested.
const POINTS: usize = 20;
/// A singular value this small relative to the largest counts as zero.
const RANK_TOLERANCE: f64 = 1e-10;

/// E0015 when the mass matrix is rank-deficient at every finite sample point.
pub fn check_mass_matrix(
    arena: &Arena,
    jacobian: &[Vec<ExprId>],
    unknowns: &[Symbol],
    param_defaults: &[f64],
    masses: usize,
    lagrangian: Span,
) -> Result<(), Diagnostic> {
    let size = unknowns.len();
    if size == 0 || jacobian.len() != size {
        return Ok(());
    }
    let entries: Vec<ExprId> = jacobian.iter().flatten().copied().collect();
    let mut rng = Rng::new(0x7369_6e67);
    let mut singular_points = 0;
    let mut involved = vec![false; size];
    for _ in 0..POINTS {
        let point = SamplePoint::random(&mut rng, param_defaults, masses);
        let values = arena.eval_many(&entries, &|s| point.value(s));
        if !values.iter().all(|v| v.is_finite()) {
            continue;
        }
        let matrix = DMatrix::from_row_slice(size, size, &values);
        let svd = matrix.svd(false, true);
        let largest = svd.singular_values.max();
        let (smallest_at, smallest) = svd.singular_values.argmin();
        if smallest > RANK_TOLERANCE * largest {
            return Ok(());
        }
        singular_points += 1;
        // The null direction names the coordinates the equations miss.
        if let Some(v_t) = &svd.v_t {
            let null = v_t.row(smallest_at);
            let norm = null.norm();
            for (c, x) in null.iter().enumerate() {
                if norm > 0.0 && x.abs() > 1e-6 * norm {
                    involved[c] = true;
                }
            }
        }
    }
    if singular_points == 0 {
        return Ok(());
    }
    let names: Vec<String> = unknowns
        .iter()
        .zip(&involved)
        .filter(|&(_, &inv)| inv)
        .map(|(&z, _)| format!("`{}`", arena.symbol_name(z)))
        .collect();
    let names = if names.is_empty() {
        "all of them".to_string()
    } else {
        names.join(", ")
    };
    Err(Diagnostic::error(
        codes::SINGULAR_MASS_MATRIX,
        "the mass matrix of this Lagrangian is singular everywhere",
    )
    .with_primary(
        lagrangian,
        "equations (4) do not determine every acceleration",
    )
    .with_note(format!(
        "the equations of motion cannot be solved for {names}: the mass matrix \
         (the derivatives of (4) with respect to the highest derivatives) is \
         singular at every one of {singular_points} sample points"
    ))
    .with_help("give every independent coordinate a kinetic energy term (e.g. `m/2*q'^2`)"))
}
