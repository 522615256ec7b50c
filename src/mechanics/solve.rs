//! Solving equations for their highest derivatives: symbolically when the
//! system is linear and small (one or two unknowns) or diagonal, otherwise
//! left to the generated code (a linear solve or Newton) with the symbolic
//! Jacobian.

use super::sample::{eval_scaled, Rng, SamplePoint};
use super::tidy::simplify;
use crate::ir::{Arena, ExprId, Symbol};

/// Points at which affinity in the unknowns is tested numerically, when the
/// canonical form does not show it.
const AFFINE_POINTS: usize = 10;
const AFFINE_TOLERANCE: f64 = 1e-10;

/// `rows(z) = 0` for the unknowns `z`.
#[derive(Debug, Clone)]
pub struct System {
    pub unknowns: Vec<Symbol>,
    pub rows: Vec<ExprId>,
    /// `∂row_r/∂z_c`, row-major.
    pub jacobian: Vec<Vec<ExprId>>,
    /// Affine in the unknowns.
    pub linear: bool,
    /// The symbolic solution, one expression per unknown, when found.
    pub explicit: Option<Vec<ExprId>>,
}

impl System {
    pub fn new(
        arena: &mut Arena,
        rows: Vec<ExprId>,
        unknowns: Vec<Symbol>,
        param_defaults: &[f64],
        masses: usize,
    ) -> System {
        // All partials in one pass over the DAG (`Arena::jacobian`). The
        // mass matrix: sin² + cos² = 1 where the derivative brought the
        // squares together.
        let cells: Vec<ExprId> = arena.jacobian(&rows, &unknowns).concat();
        let paired = arena.pythagoras_all(&cells);
        let jacobian: Vec<Vec<ExprId>> = (0..rows.len())
            .map(|r| paired[r * unknowns.len()..(r + 1) * unknowns.len()].to_vec())
            .collect();
        let linear = rows.iter().all(|&r| arena.is_affine_in(r, &unknowns))
            || affine_numerically(arena, &jacobian, &unknowns, param_defaults, masses);
        System {
            unknowns,
            rows,
            jacobian,
            linear,
            explicit: None,
        }
    }

    /// Whether every off-diagonal entry of the Jacobian is zero.
    pub fn is_diagonal(&self, arena: &Arena) -> bool {
        self.jacobian.iter().enumerate().all(|(r, row)| {
            row.iter()
                .enumerate()
                .all(|(c, &e)| r == c || arena.is_zero(e))
        })
    }

    /// Solves a linear system symbolically when it has at most two unknowns
    /// or is diagonal (`A z + b = 0`, `z = −A⁻¹ b` by Cramer's rule).
    pub fn solve_symbolically(&mut self, arena: &mut Arena) {
        let s = self.unknowns.len();
        if !self.linear || self.rows.len() != s || !(s <= 2 || self.is_diagonal(arena)) {
            return;
        }
        let zero = arena.zero();
        let at_zero: std::collections::HashMap<Symbol, ExprId> =
            self.unknowns.iter().map(|&z| (z, zero)).collect();
        // Simplified first, so that `4 + 4t² − 1.5(2 + 2t²)` is `1 + t²`
        // before it becomes a denominator.
        let b: Vec<ExprId> = self
            .rows
            .iter()
            .map(|&r| {
                let free = arena.subst(r, &at_zero);
                simplify(arena, free)
            })
            .collect();
        let matrix: Vec<Vec<ExprId>> = self
            .jacobian
            .iter()
            .map(|row| row.iter().map(|&e| simplify(arena, e)).collect())
            .collect();
        let a = |r: usize, c: usize| matrix[r][c];
        let minus = |arena: &mut Arena, num: ExprId, den: ExprId| {
            let q = arena.div(num, den);
            arena.neg(q)
        };
        let solution = if s == 2 && !self.is_diagonal(arena) {
            let d1 = arena.mul(&[a(0, 0), a(1, 1)]);
            let d2 = arena.mul(&[a(0, 1), a(1, 0)]);
            let det = arena.sub(d1, d2);
            let n1a = arena.mul(&[b[0], a(1, 1)]);
            let n1b = arena.mul(&[b[1], a(0, 1)]);
            let n1 = arena.sub(n1a, n1b);
            let n2a = arena.mul(&[a(0, 0), b[1]]);
            let n2b = arena.mul(&[a(1, 0), b[0]]);
            let n2 = arena.sub(n2a, n2b);
            vec![minus(arena, n1, det), minus(arena, n2, det)]
        } else {
            (0..s).map(|i| minus(arena, b[i], a(i, i))).collect()
        };
        self.explicit = Some(solution);
    }
}

/// The Jacobian does not change when the unknowns do, at random points.
fn affine_numerically(
    arena: &Arena,
    jacobian: &[Vec<ExprId>],
    unknowns: &[Symbol],
    param_defaults: &[f64],
    masses: usize,
) -> bool {
    let entries: Vec<ExprId> = jacobian.iter().flatten().copied().collect();
    let mut rng = Rng::new(0x6166_6669_6e65);
    let mut finite = 0;
    for _ in 0..4 * AFFINE_POINTS {
        let mut first = SamplePoint::random(&mut rng, param_defaults, masses);
        let mut second = first.clone();
        for &z in unknowns {
            if let Symbol::Jet { coord, order } = z {
                first.set_jet(coord, order, rng.range(-1.0, 1.0));
                second.set_jet(coord, order, rng.range(-1.0, 1.0));
            }
        }
        let a = eval_scaled(arena, &entries, &|s| first.value(s));
        let b = eval_scaled(arena, &entries, &|s| second.value(s));
        if !a.iter().chain(&b).all(|x| x.is_finite()) {
            continue;
        }
        if a.iter()
            .zip(&b)
            .any(|(x, y)| !x.agrees(*y, AFFINE_TOLERANCE))
        {
            return false;
        }
        finite += 1;
        if finite == AFFINE_POINTS {
            return true;
        }
    }
    false
}
