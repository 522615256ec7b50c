//! Stage 6: the kernel — every expression the generated crate evaluates,
//! built from the derivation and the field system (SPEC §1.4–§1.5), so
//! that emission only prints. Emission never differentiates, substitutes
//! or lowers: all of that happens here.
//!
//! | file | what |
//! |---|---|
//! | `time.rs` | the true time partial (mass laws move with `t`) |
//! | `motion.rs` | `X`, the exact `∂X/∂x` and `∂X/∂t`; implicit systems' residual and its partials |
//! | `items.rs` | params, time span, initial values, exact solution, mass laws, coefficient system |
//! | `text.rs` | the kernel's text form (snapshots) |

mod candidates;
pub mod domains;
mod impacts;
mod items;
mod motion;
mod outputs;
mod sensitivity;
pub mod switches;
mod text;
pub mod time;

pub use candidates::KernelCandidates;
pub use impacts::KernelImpact;
pub use items::{
    Coefficients, InitialKind, InitialSource, KernelClosure, KernelInitial, KernelParam,
};
pub use motion::{Explicit, Implicit, Motion};
pub use sensitivity::ParamPartials;
pub use switches::{BranchCond, Switches};

use crate::check::model::{IntegratorChoice, Model};
use crate::diagnostic::Diagnostic;
use crate::field::FieldSystem;
use crate::ir::{Arena, ExprId, Symbol};
use crate::mechanics::Derivation;
use time::TimeDependence;

/// What the generated crate computes, as expressions in one arena.
#[derive(Debug, Clone)]
pub struct Kernel {
    pub arena: Arena,
    /// The state (6).
    pub state: Vec<Symbol>,
    /// `n`, the number of coordinates.
    pub coordinates: usize,
    /// `u`: the state holds derivatives of order `0..u`.
    pub order: u32,
    pub params: Vec<KernelParam>,
    /// `(name, default)` of every input (SPEC §2.3), `Symbol::Input(i)`:
    /// the generated model holds their values and the runtime sets them.
    pub inputs: Vec<(String, f64)>,
    /// Every mass law `(name, law)` (for naming a mass that reaches zero),
    /// and the indices of those the reduced system still holds.
    pub masses: Vec<(String, ExprId)>,
    pub remaining_masses: Vec<u32>,
    /// The indices of the mass laws of the state (SPEC §2.3): their
    /// functions take the state, and no expression here holds their
    /// symbols (each is its law of `q`).
    pub state_laws: Vec<u32>,
    pub time_span: (ExprId, ExprId),
    pub initial: KernelInitial,
    pub motion: Motion,
    /// The mass matrix of the highest derivatives (for diagnosis).
    pub mass_matrix: Vec<Vec<ExprId>>,
    /// The coefficient system, for affine reduced systems.
    pub coefficients: Option<Coefficients>,
    /// `(state index, exact value)`.
    pub exact: Vec<(usize, ExprId)>,
    pub integrator: Option<IntegratorChoice>,
    /// `(column, value)` of every `output` (a vector output flattened to
    /// `p.x`, `p.y`), latched.
    pub outputs: Vec<(String, ExprId)>,
    /// `stop when`, on the switches' branches.
    pub stop: Option<BranchCond>,
    /// Every `when` (SPEC §2.3): its condition on the branches and its
    /// resets.
    pub impacts: Vec<KernelImpact>,
    /// `(state index, value)` of every component the constraints fix,
    /// recomputed after an impact's resets (empty without impacts).
    pub constrained: Vec<(usize, ExprId)>,
    /// The switching functions of every selection a run evaluates.
    pub switches: Switches,
    /// Every implicit constraint with its candidates' pivots.
    pub candidates: Vec<KernelCandidates>,
    /// The holonomic constraints at position level, with this mode's
    /// dependent coordinates as the unknowns.
    pub closure: Option<KernelClosure>,
    /// The state components a constraint fixes, with the value it requires
    /// at `(t, x)` — `(state index, value)`, the dependent velocities of
    /// first-order constraints (SPEC §2.3): the state is brought back onto
    /// them after steps and at outputs (latched like the motion; this
    /// mode's dependents).
    pub kept: Vec<(usize, ExprId)>,
    /// `(fixed component, velocity component, ∂value/∂velocity)`, non-zero
    /// entries: the projection onto the constraints moves the velocities
    /// along the constraints' normals (a dependent velocity alone would be
    /// moved by the residual over a pivot that may be poor).
    pub kept_gradient: Vec<(usize, usize, ExprId)>,
    /// Where the constraints as written end (square roots, logarithms,
    /// arcsines, poles): the runtime names the constraint there.
    pub domains: Vec<domains::KernelDomain>,
    /// `∂X/∂p` for the forward sensitivities (`None` where a mass law
    /// switches).
    pub param_partials: Option<ParamPartials>,
    /// The kernels of modes 1, 2, …: the same model with other candidates
    /// (their motion only).
    pub modes: Vec<Kernel>,
}

/// Builds the kernel of a derived model.
pub fn build(
    model: &Model,
    derivation: &Derivation,
    field: &FieldSystem,
) -> Result<Kernel, Vec<Diagnostic>> {
    build_with(model, derivation, derivation.arena.clone(), field, true)
}

/// [`build`] from a derivation that is not needed afterwards: its arena is
/// built on instead of copied (a copy of a large model's arena costs about
/// as much as some stages). Not `first_mode`: the kernel of one more mode
/// of a model with implicit constraints (its motion; the initial state,
/// exact solution, outputs, stop and impacts are mode 0's).
pub fn build_owned(
    model: &Model,
    mut derivation: Derivation,
    field: &FieldSystem,
    first_mode: bool,
) -> Result<Kernel, Vec<Diagnostic>> {
    let arena = std::mem::replace(&mut derivation.arena, Arena::new(Default::default()));
    build_with(model, &derivation, arena, field, first_mode)
}

/// The kernel built on `arena`, `derivation.arena` or a copy of it.
fn build_with(
    model: &Model,
    derivation: &Derivation,
    mut arena: Arena,
    field: &FieldSystem,
    first_mode: bool,
) -> Result<Kernel, Vec<Diagnostic>> {
    let reduced = &derivation.reduced;
    let time = TimeDependence::new(&mut arena, &reduced.mass_laws);
    let params = items::params(&mut arena, model);
    let masses = items::masses(&mut arena, model);
    let time_span = items::time_span(&mut arena, model);
    let initial = if first_mode {
        items::initial(&mut arena, model, reduced).map_err(|d| vec![d])?
    } else {
        KernelInitial {
            kinds: Vec::new(),
            sources: Vec::new(),
            stated: Vec::new(),
        }
    };
    let motion = motion::motion(&mut arena, reduced, &time);
    let coefficients = items::coefficients(&mut arena, field, &time);
    let exact = if first_mode {
        items::exact(&mut arena, model, reduced)
    } else {
        Vec::new()
    };
    // One simplifier for all entries: it remembers what they share (and
    // each off-diagonal entry of a symmetric matrix comes twice).
    let mut simplifier = crate::mechanics::tidy::Simplifier::default();
    let mut mass_matrix: Vec<Vec<ExprId>> = reduced
        .mass_matrix
        .iter()
        .map(|row| {
            row.iter()
                .map(|&e| simplifier.simplify(&mut arena, e))
                .collect()
        })
        .collect();
    // A mass law of the state is its expression of `q` wherever the run
    // evaluates it (the reduced system has it so already).
    let state_laws: std::collections::HashMap<Symbol, ExprId> = derivation
        .state_laws
        .iter()
        .map(|&(i, law)| (Symbol::Mass(i), law))
        .collect();
    let (outputs, stop) = if first_mode {
        outputs::outputs(&mut arena, model, &motion, reduced, &state_laws)?
    } else {
        (Vec::new(), None)
    };
    let (impacts, constrained) = if first_mode {
        impacts::impacts(&mut arena, model, &motion, reduced)?
    } else {
        (Vec::new(), Vec::new())
    };
    let candidates = if first_mode {
        candidates::candidates(&mut arena, model, &state_laws)
    } else {
        Vec::new()
    };
    let domains = if first_mode {
        // Those the state determines and that move: an argument with a
        // highest derivative (a constraint of order k = u) or of params
        // alone is not watched.
        let mut found = domains::domains(&mut arena, model);
        found.retain(|d| {
            let symbols = arena.free_symbols(d.argument);
            let moves = symbols.iter().any(|s| {
                matches!(
                    s,
                    Symbol::Time | Symbol::Jet { .. } | Symbol::Mass(_) | Symbol::Input(_)
                )
            });
            moves
                && symbols.iter().all(|s| match s {
                    Symbol::Jet { .. } => reduced.state.contains(s),
                    _ => true,
                })
        });
        found
    } else {
        Vec::new()
    };
    let mut switches = Switches::new(&arena, &masses);
    let mut motion = motion;
    let mut coefficients = coefficients;
    // Outputs are not latched: read at each sample from the state there,
    // their selections test their conditions directly and are no switches.
    // As switches an output's `if` restarted the integrators where it
    // switched, changing the motion it only reports (a pendulum's error at
    // rtol 1e-8, 2.4e-5 without two output conditions, 2.2e-4 with them).
    switches::latch_kernel(
        &mut arena,
        &mut switches,
        &mut motion,
        coefficients.as_mut(),
        &mut mass_matrix,
    );
    let param_partials = sensitivity::param_partials(
        &mut arena,
        &motion,
        reduced.state.len(),
        params.len(),
        &masses,
        &reduced
            .mass_laws
            .iter()
            .map(|&(i, _)| i)
            .collect::<Vec<_>>(),
    );
    let stop = stop.map(|c| switches.condition(&mut arena, &c));
    let kept = kept(&mut arena, &mut switches, reduced);
    let kept_gradient = kept_gradient(&mut arena, &kept, &reduced.state);
    let impacts = impacts::on_branches(&mut arena, &mut switches, impacts);
    let closure = items::closure(&mut arena, reduced);
    Ok(Kernel {
        arena,
        state: reduced.state.clone(),
        coordinates: derivation.coordinates,
        order: reduced.order,
        params,
        inputs: model
            .inputs
            .iter()
            .map(|u| (u.name.clone(), u.default))
            .collect(),
        masses,
        remaining_masses: reduced.mass_laws.iter().map(|&(i, _)| i).collect(),
        state_laws: derivation.state_laws.iter().map(|&(i, _)| i).collect(),
        time_span,
        initial,
        motion,
        mass_matrix,
        coefficients,
        exact,
        integrator: model.integrator.map(|d| d.choice),
        outputs,
        stop,
        impacts,
        constrained,
        switches,
        candidates,
        closure,
        kept,
        kept_gradient,
        domains,
        param_partials,
        modes: Vec::new(),
    })
}

/// The values the constraints require of the state components they fix
/// (`ReducedSystem::fixed`: the same expressions as their initial values),
/// on the motion's branches. Integrated as free state, a dependent velocity
/// drifts from them wherever `φ` depends on a dependent coordinate
/// (`e' = −φ_{q_d} e`, shared/notes/constraint-drift.md).
fn kept(
    arena: &mut Arena,
    switches: &mut Switches,
    reduced: &crate::mechanics::ReducedSystem,
) -> Vec<(usize, ExprId)> {
    reduced
        .fixed
        .iter()
        .map(|&(i, e)| {
            let e = crate::mechanics::tidy::simplify(arena, e);
            (i, switches.latch(arena, e))
        })
        .collect()
}

impl Kernel {
    /// The row of the state holding `q_coord^(u−1)`'s rate, `q_coord^(u)`.
    pub fn highest_row(&self, coord: u32) -> usize {
        (self.order as usize - 1) * self.coordinates + coord as usize
    }

    /// Every root the right side evaluates (for operation counts).
    pub fn rhs_roots(&self) -> Vec<ExprId> {
        match &self.motion {
            Motion::Explicit(e) => e.rhs.clone(),
            Motion::Implicit(i) => {
                let mut roots = i.residual.clone();
                roots.extend(i.g_z.iter().map(|&(_, _, e)| e));
                roots.extend(i.dependent.iter().map(|d| d.value));
                roots
            }
        }
    }
}

/// The non-zero partials of the kept values in the velocities (the state's
/// highest block, `q^(u−1)`).
fn kept_gradient(
    arena: &mut Arena,
    kept: &[(usize, ExprId)],
    state: &[Symbol],
) -> Vec<(usize, usize, ExprId)> {
    let top = state
        .iter()
        .filter_map(|s| match s {
            Symbol::Jet { order, .. } => Some(*order),
            _ => None,
        })
        .max()
        .unwrap_or(0);
    let mut entries = Vec::new();
    for &(i, e) in kept {
        for (j, &s) in state.iter().enumerate() {
            if !matches!(s, Symbol::Jet { order, .. } if order == top) {
                continue;
            }
            let d = arena.diff(e, s);
            if !arena.is_zero(d) {
                entries.push((i, j, crate::mechanics::tidy::simplify(arena, d)));
            }
        }
    }
    entries
}
