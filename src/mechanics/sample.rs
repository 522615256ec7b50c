//! Random points of the jet space and evaluation with a rounding scale:
//! the numeric checks of the mechanics (cross-check, homogeneity in the
//! masses, affinity, singular mass matrix) all compare values at such points.

use crate::ir::{apply_func, pow_value, Arena, ExprId, Func, FxMap, Node, Symbol};
use std::collections::HashMap;

/// The one small deterministic PRNG (SplitMix64) of lagc and its tests:
/// the checks must give the same verdict on every run.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `0..n` (`n > 0`; the modulo bias is far below what a
    /// test's choice can notice).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

/// Values for every symbol: `t`, params near their defaults, positive
/// masses, jets in a moderate range.
#[derive(Debug, Clone)]
pub struct SamplePoint {
    pub t: f64,
    pub params: Vec<f64>,
    pub masses: Vec<f64>,
    jets: HashMap<(u32, u32), f64>,
    jet_seed: u64,
}

impl SamplePoint {
    /// A random point. Params vary by ±25 % around their defaults (a zero
    /// default by ±0.25), so that a formula that only works for the
    /// defaults is not mistaken for an identity.
    pub fn random(rng: &mut Rng, defaults: &[f64], masses: usize) -> SamplePoint {
        let t = rng.range(0.0, 2.0);
        let params = defaults
            .iter()
            .map(|&d| {
                let u = rng.range(-0.25, 0.25);
                if d == 0.0 {
                    u
                } else {
                    d * (1.0 + u)
                }
            })
            .collect();
        let masses = (0..masses).map(|_| rng.range(0.5, 2.0)).collect();
        SamplePoint {
            t,
            params,
            masses,
            jets: HashMap::new(),
            jet_seed: rng.next_u64(),
        }
    }

    /// Overrides the value of one jet variable.
    pub fn set_jet(&mut self, coord: u32, order: u32, value: f64) {
        self.jets.insert((coord, order), value);
    }

    /// The value of a symbol. Jets not set explicitly get a value in
    /// `[-1, 1)` that depends only on the point and the jet.
    pub fn value(&self, s: Symbol) -> f64 {
        match s {
            Symbol::Time => self.t,
            Symbol::Param(i) => self.params.get(i as usize).copied().unwrap_or(f64::NAN),
            Symbol::Mass(i) => self.masses.get(i as usize).copied().unwrap_or(f64::NAN),
            Symbol::Jet { coord, order } => match self.jets.get(&(coord, order)) {
                Some(&v) => v,
                None => {
                    let key = (u64::from(coord) << 32) | u64::from(order);
                    let mut rng = Rng::new(self.jet_seed ^ key.wrapping_mul(0x2545_f491_4f6c_dd1d));
                    rng.range(-1.0, 1.0)
                }
            },
            // Inputs and their rates are free symbols like params: a
            // value in `[-1, 1)` of the point and the input.
            Symbol::Input(i) | Symbol::InputRate(i) => {
                let rate = u64::from(matches!(s, Symbol::InputRate(_)));
                let key = (1u64 << 63) | (rate << 62) | u64::from(i);
                let mut rng = Rng::new(self.jet_seed ^ key.wrapping_mul(0x2545_f491_4f6c_dd1d));
                rng.range(-1.0, 1.0)
            }
            Symbol::Aux(_) => f64::NAN,
        }
    }

    /// The same point with every mass multiplied by `factor`.
    pub fn masses_scaled(&self, factor: f64) -> SamplePoint {
        let mut p = self.clone();
        for m in &mut p.masses {
            *m *= factor;
        }
        p
    }
}

/// A value and its rounding scale: `|error| ≲ ε · scale · (a few)` when the
/// expression is evaluated in floating point. Sums add the scales of their
/// terms, so a value that cancels keeps the scale of what cancelled.
#[derive(Debug, Clone, Copy)]
pub struct Scaled {
    pub value: f64,
    pub scale: f64,
}

impl Scaled {
    /// Whether two values agree to `tol` relative to their rounding scales.
    pub fn agrees(self, other: Scaled, tol: f64) -> bool {
        (self.value - other.value).abs() <= tol * (self.scale + other.scale)
    }

    pub fn is_finite(self) -> bool {
        self.value.is_finite() && self.scale.is_finite()
    }
}

/// Evaluates `roots` with their rounding scales (first-order propagation:
/// `|f'(a)| · scale(a)` through functions and powers).
pub fn eval_scaled(arena: &Arena, roots: &[ExprId], env: &dyn Fn(Symbol) -> f64) -> Vec<Scaled> {
    Tape::new(arena, roots).eval_scaled(env)
}

/// The nodes reachable from some roots, children first, each with its
/// children's positions: a check at many points walks the DAG once and
/// evaluates it by position (a hash lookup per child and point cost more
/// than the arithmetic on the 100-link pendulum's cross-check).
pub struct Tape<'a> {
    arena: &'a Arena,
    nodes: Vec<ExprId>,
    /// Node `p`'s children are `children[first[p]..first[p + 1]]`.
    children: Vec<u32>,
    first: Vec<u32>,
    roots: Vec<u32>,
}

impl<'a> Tape<'a> {
    pub fn new(arena: &'a Arena, roots: &[ExprId]) -> Tape<'a> {
        let nodes = arena.reachable(roots);
        let position: FxMap<ExprId, u32> = nodes
            .iter()
            .enumerate()
            .map(|(p, &e)| (e, p as u32))
            .collect();
        let mut children = Vec::new();
        let mut first = Vec::with_capacity(nodes.len() + 1);
        for &e in &nodes {
            first.push(children.len() as u32);
            children.extend(arena.children(e).iter().map(|c| position[c]));
        }
        first.push(children.len() as u32);
        let roots = roots.iter().map(|r| position[r]).collect();
        Tape {
            arena,
            nodes,
            children,
            first,
            roots,
        }
    }

    /// The roots' values and rounding scales at `env` (first-order
    /// propagation: `|f'(a)| · scale(a)` through functions and powers).
    pub fn eval_scaled(&self, env: &dyn Fn(Symbol) -> f64) -> Vec<Scaled> {
        let mut values: Vec<Scaled> = Vec::with_capacity(self.nodes.len());
        for (p, &e) in self.nodes.iter().enumerate() {
            let kids = &self.children[self.first[p] as usize..self.first[p + 1] as usize];
            let get = |values: &[Scaled], k: usize| values[kids[k] as usize];
            let s = match self.arena.node(e) {
                Node::Const(v) => Scaled {
                    value: *v,
                    scale: v.abs(),
                },
                Node::Sym(s) => {
                    let v = env(*s);
                    Scaled {
                        value: v,
                        scale: v.abs(),
                    }
                }
                Node::Add(_) => kids.iter().fold(
                    Scaled {
                        value: 0.0,
                        scale: 0.0,
                    },
                    |acc, &k| {
                        let x = values[k as usize];
                        Scaled {
                            value: acc.value + x.value,
                            scale: acc.scale + x.scale,
                        }
                    },
                ),
                Node::Mul(_) => kids.iter().fold(
                    Scaled {
                        value: 1.0,
                        scale: 1.0,
                    },
                    |acc, &k| {
                        let x = values[k as usize];
                        Scaled {
                            value: acc.value * x.value,
                            scale: acc.scale * x.scale,
                        }
                    },
                ),
                Node::Pow(..) => {
                    let (a, b) = (get(&values, 0), get(&values, 1));
                    let value = pow_value(a.value, b.value);
                    // d(a^b) = b a^(b-1) da + a^b ln|a| db. A part with no
                    // scale adds nothing (not `0·∞ = NaN`): at `a = 0` the
                    // base's `ln|a|` is infinite, but `a^b ln|a| → 0`
                    // (`b > 0`). A NaN scale once made every `|f| > tol·scale`
                    // false, and `lagc linearize` called a hanging double
                    // pendulum held horizontal at rest an equilibrium (its
                    // `a'^2` at `a' = 0`).
                    let through_base = if a.scale == 0.0 {
                        0.0
                    } else {
                        (b.value * pow_value(a.value, b.value - 1.0)).abs() * a.scale
                    };
                    let through_exp = if b.scale == 0.0 || value == 0.0 {
                        0.0
                    } else {
                        (value * a.value.abs().ln()).abs() * b.scale
                    };
                    Scaled {
                        value,
                        scale: value.abs() + through_base + through_exp,
                    }
                }
                Node::Select(..) => {
                    if get(&values, 0).value < 0.0 {
                        get(&values, 1)
                    } else {
                        get(&values, 2)
                    }
                }
                Node::Func(f, _) => {
                    let a = get(&values, 0);
                    let value = apply_func(*f, a.value);
                    Scaled {
                        value,
                        scale: value.abs() + slope(*f, a.value).abs() * a.scale,
                    }
                }
            };
            values.push(s);
        }
        self.roots.iter().map(|&r| values[r as usize]).collect()
    }
}

/// `f'(x)`.
fn slope(f: Func, x: f64) -> f64 {
    match f {
        Func::Sin => x.cos(),
        Func::Cos => -x.sin(),
        Func::Tan => 1.0 + x.tan().powi(2),
        Func::Asin => 1.0 / (1.0 - x * x).sqrt(),
        Func::Acos => -1.0 / (1.0 - x * x).sqrt(),
        Func::Atan => 1.0 / (1.0 + x * x),
        Func::Sinh => x.cosh(),
        Func::Cosh => x.sinh(),
        Func::Tanh => 1.0 - x.tanh().powi(2),
        Func::Exp => x.exp(),
        Func::Ln => 1.0 / x,
        Func::Sqrt => 0.5 / x.sqrt(),
    }
}
