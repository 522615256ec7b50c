//! Switches (SPEC §2.2): every `if`, `abs`, `sign`, `min`, `max` and
//! `atan2` is a selection on a switching function `g(t, x)`. Along a run the
//! generated code does not test `g`: it takes the branch of the current
//! regime (`Model::set_regime`), and the runtime locates every sign change
//! of `g` as an event and restarts there. So within a step the right side
//! is smooth, and a kink costs no order.
//!
//! Here each distinct `g` gets a branch symbol ``branch_k`` (±1 at run time) and
//! every selection the run evaluates is rebuilt on ``branch_k` < 0` instead of
//! `g < 0`.

use crate::ir::{Arena, Cond, ExprId, Symbol};
use std::collections::HashMap;

/// The switching functions and their branch symbols.
#[derive(Debug, Clone, Default)]
pub struct Switches {
    /// `g_k(t, x)`, latched themselves where they hold selections.
    pub functions: Vec<ExprId>,
    /// ``branch_k``: the sign of `g_k` on the current segment.
    pub symbols: Vec<Symbol>,
    index: HashMap<ExprId, usize>,
    memo: crate::ir::FxMap<ExprId, ExprId>,
    /// Mass symbols whose laws switch, with those laws: inside latched
    /// expressions a switching mass law is evaluated in the regime too.
    laws: HashMap<Symbol, ExprId>,
}

impl Switches {
    pub fn new(arena: &Arena, laws: &[(String, ExprId)]) -> Switches {
        let laws = laws
            .iter()
            .enumerate()
            .filter(|(_, (_, law))| arena.has_select(*law))
            .map(|(i, &(_, law))| (Symbol::Mass(i as u32), law))
            .collect();
        Switches {
            laws,
            ..Switches::default()
        }
    }

    /// `e` with every selection on its regime's branch symbol.
    pub fn latch(&mut self, arena: &mut Arena, e: ExprId) -> ExprId {
        let e = if self.laws.is_empty() {
            e
        } else {
            arena.subst(e, &self.laws)
        };
        let mut memo = std::mem::take(&mut self.memo);
        let functions = &mut self.functions;
        let symbols = &mut self.symbols;
        let index = &mut self.index;
        let mut switch = |arena: &mut Arena, g: ExprId| {
            let k = *index.entry(g).or_insert_with(|| {
                functions.push(g);
                let symbol = arena.aux(&format!("branch_{}", symbols.len() + 1));
                symbols.push(symbol);
                symbols.len() - 1
            });
            arena.symbol(symbols[k])
        };
        let r = arena.map_selects(e, &mut switch, &mut memo);
        self.memo = memo;
        r
    }

    /// Latches every expression of `cells` in place.
    pub fn latch_all(&mut self, arena: &mut Arena, cells: &mut [ExprId]) {
        for e in cells {
            *e = self.latch(arena, *e);
        }
    }

    /// A condition (`stop when`) on branch indices: each comparison's
    /// switching function registered, its `g < 0` read from the regime.
    pub fn condition(&mut self, arena: &mut Arena, cond: &Cond) -> BranchCond {
        match cond {
            Cond::Negative(g) => {
                let g = self.latch(arena, *g);
                let k = match self.index.get(&g) {
                    Some(&k) => k,
                    None => {
                        self.functions.push(g);
                        let symbol = arena.aux(&format!("branch_{}", self.symbols.len() + 1));
                        self.symbols.push(symbol);
                        self.index.insert(g, self.functions.len() - 1);
                        self.functions.len() - 1
                    }
                };
                BranchCond::Negative(k)
            }
            Cond::Not(c) => BranchCond::Not(Box::new(self.condition(arena, c))),
            Cond::And(a, b) => BranchCond::And(
                Box::new(self.condition(arena, a)),
                Box::new(self.condition(arena, b)),
            ),
            Cond::Or(a, b) => BranchCond::Or(
                Box::new(self.condition(arena, a)),
                Box::new(self.condition(arena, b)),
            ),
        }
    }
}

/// A condition on the regime: `Negative(k)` holds when `g_k < 0`.
#[derive(Debug, Clone, PartialEq)]
pub enum BranchCond {
    Negative(usize),
    Not(Box<BranchCond>),
    And(Box<BranchCond>, Box<BranchCond>),
    Or(Box<BranchCond>, Box<BranchCond>),
}

/// Latches every expression the integration evaluates: the motion, the
/// coefficient system and the mass matrix (not the outputs, read at each
/// sample as they stand).
pub fn latch_kernel(
    arena: &mut Arena,
    switches: &mut Switches,
    motion: &mut super::Motion,
    coefficients: Option<&mut super::Coefficients>,
    mass_matrix: &mut [Vec<ExprId>],
) {
    let mut cells = |arena: &mut Arena, cells: &mut dyn Iterator<Item = &mut ExprId>| {
        for e in cells {
            *e = switches.latch(arena, *e);
        }
    };
    match motion {
        super::Motion::Explicit(m) => {
            cells(arena, &mut m.rhs.iter_mut());
            cells(arena, &mut m.jacobian.iter_mut().map(|(_, _, e)| e));
            cells(arena, &mut m.time_partial.iter_mut().map(|(_, e)| e));
        }
        super::Motion::Implicit(m) => {
            cells(arena, &mut m.residual.iter_mut());
            cells(arena, &mut m.free.iter_mut());
            cells(arena, &mut m.g_z.iter_mut().map(|(_, _, e)| e));
            cells(arena, &mut m.g_x.iter_mut().map(|(_, _, e)| e));
            cells(arena, &mut m.g_t.iter_mut().map(|(_, e)| e));
            for d in &mut m.dependent {
                cells(arena, &mut std::iter::once(&mut d.value));
                cells(arena, &mut std::iter::once(&mut d.d_t));
                cells(arena, &mut d.d_x.iter_mut().map(|(_, e)| e));
                cells(arena, &mut d.d_z.iter_mut().map(|(_, e)| e));
            }
        }
    }
    if let Some(c) = coefficients {
        cells(arena, &mut c.rhs.iter_mut());
        cells(arena, &mut c.jacobian.iter_mut().map(|(_, _, e)| e));
        cells(arena, &mut c.time_partial.iter_mut().map(|(_, e)| e));
    }
    for row in mass_matrix {
        cells(arena, &mut row.iter_mut());
    }
}

/// The first mode's switching functions by text.
pub fn switch_index(kernel: &super::Kernel) -> HashMap<String, usize> {
    kernel
        .switches
        .functions
        .iter()
        .enumerate()
        .map(|(k, &g)| (kernel.arena.display(g).to_string(), k))
        .collect()
}

/// The switching functions of `mode` that the first mode does not have:
/// a model whose other modes have one is refused (E0040, in
/// `pipeline::kernel_of`, which `lagc check` runs), since every mode reads
/// the first mode's branches.
pub fn unshared_switches(first: &super::Kernel, mode: &super::Kernel) -> Vec<String> {
    let index = switch_index(first);
    mode.switches
        .functions
        .iter()
        .map(|&g| mode.arena.display(g).to_string())
        .filter(|text| !index.contains_key(text))
        .collect()
}
