//! Readable forms of equations: collect the jets (`c₁·q1'' + c₂·q1' + …`)
//! and write each coefficient in the smallest of a few equal forms
//! (distributed, with common factors pulled out, with fractions over a
//! common denominator). Every rewrite is an algebraic identity; the
//! canonical constructors do the cancelling.

use super::jet_coefficients::jet_coefficients;
use crate::ir::{Arena, ExprId, FxMap, Node, Symbol};
use std::collections::{BTreeSet, HashMap};

/// Sums with more terms than this are left alone by the fraction merging
/// (it tries pairs of terms).
const MERGE_MAX_TERMS: usize = 12;
/// How deep `distribute` multiplies out nested products of sums.
const DISTRIBUTE_DEPTH: u32 = 2;

/// `e` as a sum of collected terms, the highest derivatives first and the
/// jet-free term last. Their sum equals `e`.
pub fn tidy_terms(arena: &mut Arena, e: ExprId) -> Vec<ExprId> {
    tidy_terms_all(arena, &[e]).concat()
}

/// [`tidy_terms`] of each of `es`, their coefficients taken together
/// ([`jet_coefficients`]: one Jacobian per derivative order): the
/// equations of a large model share most of their nodes (the N-link
/// pendulum's inner sums), and a Jacobian of each alone builds the
/// partials of every shared node once per equation.
pub fn tidy_terms_all(arena: &mut Arena, es: &[ExprId]) -> Vec<Vec<ExprId>> {
    let vars: Vec<Vec<Symbol>> = jet_coefficients(arena, es)
        .into_iter()
        .map(|jc| affine_among(arena, jc.vars, &jc.coefficients))
        .collect();
    // The jet-free terms, those of the expressions affine in the same jets
    // substituted together (the nodes they share rebuilt once).
    let mut free = vec![arena.zero(); es.len()];
    let mut groups: Vec<(&[Symbol], Vec<usize>)> = Vec::new();
    for (i, v) in vars.iter().enumerate() {
        match groups.iter_mut().find(|(g, _)| *g == &v[..]) {
            Some((_, members)) => members.push(i),
            None => groups.push((v, vec![i])),
        }
    }
    for (group, members) in groups {
        let zero = arena.zero();
        let at_zero: HashMap<Symbol, ExprId> = group.iter().map(|&v| (v, zero)).collect();
        let roots: Vec<ExprId> = members.iter().map(|&i| es[i]).collect();
        for (i, f) in members.into_iter().zip(arena.subst_all(&roots, &at_zero)) {
            free[i] = f;
        }
    }
    let mut simplifier = Simplifier::default();
    es.iter()
        .zip(&vars)
        .zip(free)
        .map(|((&e, vars), free)| terms_in(arena, &mut simplifier, e, vars, free))
        .collect()
}

/// `e` as `Σ c_v·v + free` over the jets `vars` it is affine in, `free`
/// being `e` at `vars = 0`.
fn terms_in(
    arena: &mut Arena,
    simplifier: &mut Simplifier,
    e: ExprId,
    vars: &[Symbol],
    free: ExprId,
) -> Vec<ExprId> {
    let mut terms = Vec::new();
    for &v in vars {
        let c = arena.diff(e, v);
        if arena.is_zero(c) {
            continue;
        }
        let c = simplifier.simplify(arena, c);
        let x = arena.symbol(v);
        terms.push(arena.mul(&[c, x]));
    }
    if !arena.is_zero(free) || terms.is_empty() {
        terms.push(simplifier.simplify(arena, free));
    }
    terms
}

/// The order of preference of the jets: the highest derivatives first,
/// then by coordinate.
pub(crate) fn priority(s: Symbol) -> (std::cmp::Reverse<u32>, u32) {
    match s {
        Symbol::Jet { coord, order } => (std::cmp::Reverse(order), coord),
        _ => (std::cmp::Reverse(0), 0),
    }
}

/// `e` rewritten as the sum of [`tidy_terms`].
pub fn tidy(arena: &mut Arena, e: ExprId) -> ExprId {
    let terms = tidy_terms(arena, e);
    arena.add(&terms)
}

/// The jets among `vars` (in priority order) in which their expression is
/// affine (no coefficient depends on any of them), preferring the highest
/// derivatives; `coefficients[i]` is `∂e/∂vars[i]`. The candidates
/// [`jet_coefficients`] leaves out come after all of `vars` and are held by
/// their coefficients: this rule would drop them, and its decisions on
/// the jets before them do not look at them.
fn affine_among(arena: &Arena, vars: Vec<Symbol>, coefficients: &[ExprId]) -> Vec<Symbol> {
    // The jets each coefficient depends on.
    let slots: Vec<Option<u32>> = vars.iter().map(|&v| arena.symbol_slot(v)).collect();
    let depends: Vec<Vec<usize>> = coefficients
        .iter()
        .map(|&c| {
            (0..vars.len())
                .filter(|&b| slots[b].is_some_and(|s| arena.holds_slot(c, s)))
                .collect()
        })
        .collect();
    let mut dependents: Vec<Vec<usize>> = vec![Vec::new(); vars.len()];
    for (a, ds) in depends.iter().enumerate() {
        for &b in ds {
            dependents[b].push(a);
        }
    }
    // Drop, one at a time, the lowest-priority jet that takes part in a
    // dependence among the jets kept (its coefficient depends on a kept
    // jet, or a kept jet's coefficient depends on it); `uses` and
    // `used_by` count those among the kept. Dropping the last such jet is
    // what a scan of every pair would drop (a var whose coefficient
    // depends on itself, else the lower-priority end of a cross
    // dependence), without rescanning the pairs after each drop.
    let mut kept = vec![true; vars.len()];
    let mut uses: Vec<usize> = depends.iter().map(Vec::len).collect();
    let mut used_by: Vec<usize> = dependents.iter().map(Vec::len).collect();
    while let Some(r) = (0..vars.len())
        .rev()
        .find(|&i| kept[i] && (uses[i] > 0 || used_by[i] > 0))
    {
        kept[r] = false;
        for &b in &depends[r] {
            used_by[b] -= 1;
        }
        for &a in &dependents[r] {
            uses[a] -= 1;
        }
    }
    vars.into_iter()
        .zip(kept)
        .filter_map(|(v, k)| k.then_some(v))
        .collect()
}

/// The smallest (by operation count) of a few equal forms of `e`; on a tie
/// the form with common factors pulled out wins (`M*(1 + t^2)`).
pub fn simplify(arena: &mut Arena, e: ExprId) -> ExprId {
    Simplifier::default().simplify(arena, e)
}

/// [`simplify`] of many expressions that share nodes: each rewrite is a
/// function of the node alone, so its results are remembered across
/// expressions (the equations of the N-link pendulum share their inner
/// sums, which each equation's own walks rewrote afresh).
#[derive(Default)]
pub struct Simplifier {
    /// The result by expression (a symmetric mass matrix has each
    /// off-diagonal entry twice).
    simplified: FxMap<ExprId, ExprId>,
    /// `distribute(e, depth)` by `(e, depth)`.
    distributed: FxMap<(ExprId, u32), ExprId>,
    /// `sin²u + cos²u = 1` by node.
    paired: FxMap<ExprId, ExprId>,
    /// By the other factors of a product of a sum and the depth left: each
    /// term's product with them, distributed. The pendulum's `sin θ_i·S_k`
    /// over its nested inner sums `S_k ⊃ S_{k−1} ⊃ …` multiply the same
    /// term by the same factors once per `k`.
    products: FxMap<(Vec<ExprId>, u32), FxMap<ExprId, ExprId>>,
}

impl Simplifier {
    /// [`simplify`] through the memos.
    pub fn simplify(&mut self, arena: &mut Arena, e: ExprId) -> ExprId {
        if let Some(&r) = self.simplified.get(&e) {
            return r;
        }
        let r = self.simplify_once(arena, e);
        self.simplified.insert(e, r);
        r
    }

    fn simplify_once(&mut self, arena: &mut Arena, e: ExprId) -> ExprId {
        // Distributing brings `X sin²u` and `X cos²u` side by side: pair them.
        let distributed = self.distribute(arena, e, DISTRIBUTE_DEPTH);
        let distributed = arena.pythagoras_rec(distributed, &mut self.paired);
        let merged = merge_fractions(arena, distributed);
        // And where distributing merges `sin u · sin²u` into `sin³u`, the
        // squares paired in `e` as it is: `sin u (1 + ½sin²u + ½cos²u)`.
        let paired = arena.pythagoras_rec(e, &mut self.paired);
        let candidates = [
            factor_common(arena, merged),
            factor_common(arena, paired),
            factor_common(arena, e),
            merged,
            distributed,
            merge_fractions(arena, e),
            e,
        ];
        let mut best = e;
        let mut best_cost = usize::MAX;
        for (i, &c) in candidates.iter().enumerate() {
            // A form found again costs what it cost before and cannot win
            // (only a smaller cost replaces the best): often most of the
            // forms are one node, and each count walks the whole form.
            if candidates[..i].contains(&c) {
                continue;
            }
            let cost = arena.op_count(&[c]);
            if cost < best_cost {
                best = c;
                best_cost = cost;
            }
        }
        best
    }

    /// Multiplies out products of sums, `depth` levels deep.
    fn distribute(&mut self, arena: &mut Arena, e: ExprId, depth: u32) -> ExprId {
        if depth == 0 {
            return e;
        }
        if let Some(&r) = self.distributed.get(&(e, depth)) {
            return r;
        }
        let r = match arena.node(e).clone() {
            Node::Add(ts) => {
                let ts: Vec<ExprId> = ts
                    .iter()
                    .map(|&t| self.distribute(arena, t, depth))
                    .collect();
                arena.add(&ts)
            }
            Node::Mul(fs) => match fs
                .iter()
                .position(|&f| matches!(arena.node(f), Node::Add(_)))
            {
                None => e,
                Some(at) => {
                    let rest: Vec<ExprId> = fs
                        .iter()
                        .enumerate()
                        .filter(|&(i, _)| i != at)
                        .map(|(_, &f)| f)
                        .collect();
                    let sum = arena.children(fs[at]);
                    let key = (rest.clone(), depth);
                    let mut done = self.products.remove(&key).unwrap_or_default();
                    let terms: Vec<ExprId> = sum
                        .into_iter()
                        .map(|t| match done.get(&t) {
                            Some(&r) => r,
                            None => {
                                let mut factors = rest.clone();
                                factors.push(t);
                                let product = arena.mul(&factors);
                                let r = self.distribute(arena, product, depth - 1);
                                done.insert(t, r);
                                r
                            }
                        })
                        .collect();
                    self.products.insert(key, done);
                    arena.add(&terms)
                }
            },
            _ => e,
        };
        self.distributed.insert((e, depth), r);
        r
    }
}

/// Multiplies out products of sums, `depth` levels deep.
fn distribute(arena: &mut Arena, e: ExprId, depth: u32) -> ExprId {
    Simplifier::default().distribute(arena, e, depth)
}

/// `(base, exponent)` factors of a term with numeric exponents.
fn factors(arena: &Arena, term: ExprId) -> Vec<(ExprId, f64)> {
    let as_factor = |f: ExprId| match arena.node(f) {
        Node::Pow(b, x) => arena.as_const(*x).map(|x| (*b, x)),
        Node::Const(_) => None,
        _ => Some((f, 1.0)),
    };
    match arena.node(term) {
        Node::Mul(fs) => fs.iter().filter_map(|&f| as_factor(f)).collect(),
        _ => as_factor(term).into_iter().collect(),
    }
}

/// Pulls the factors common to every term of a sum out of it:
/// `M + M*t^2 → M*(1 + t^2)`.
fn factor_common(arena: &mut Arena, e: ExprId) -> ExprId {
    let Node::Add(ts) = arena.node(e).clone() else {
        return e;
    };
    let lists: Vec<Vec<(ExprId, f64)>> = ts.iter().map(|&t| factors(arena, t)).collect();
    let mut common: Vec<(ExprId, f64)> = Vec::new();
    let bases: BTreeSet<ExprId> = lists[0].iter().map(|&(b, _)| b).collect();
    for base in bases {
        let exps: Option<Vec<f64>> = lists
            .iter()
            .map(|l| l.iter().find(|&&(b, _)| b == base).map(|&(_, x)| x))
            .collect();
        let Some(exps) = exps else { continue };
        if exps.iter().all(|&x| x > 0.0) {
            common.push((base, exps.iter().copied().fold(f64::INFINITY, f64::min)));
        } else if exps.iter().all(|&x| x < 0.0) {
            common.push((base, exps.iter().copied().fold(f64::NEG_INFINITY, f64::max)));
        }
    }
    if common.is_empty() {
        return e;
    }
    let mut outside = Vec::new();
    let mut inverse = Vec::new();
    for (b, x) in common {
        let xe = arena.constant(x);
        outside.push(arena.pow(b, xe));
        let nx = arena.constant(-x);
        inverse.push(arena.pow(b, nx));
    }
    let inner: Vec<ExprId> = ts
        .iter()
        .map(|&t| {
            let mut fs = inverse.clone();
            fs.push(t);
            arena.mul(&fs)
        })
        .collect();
    let inner = arena.add(&inner);
    outside.push(inner);
    arena.mul(&outside)
}

/// Brings pairs of terms over a common denominator when that makes the sum
/// smaller: `1 − t^2/(1 + t^2) → 1/(1 + t^2)`.
fn merge_fractions(arena: &mut Arena, e: ExprId) -> ExprId {
    let Node::Add(ts) = arena.node(e).clone() else {
        return e;
    };
    if ts.len() > MERGE_MAX_TERMS {
        return e;
    }
    let mut terms: Vec<ExprId> = ts.to_vec();
    let mut cost = arena.op_count(&[e]);
    'improve: loop {
        for a in 0..terms.len() {
            for denominator in denominators(arena, terms[a]) {
                for b in 0..terms.len() {
                    if a == b {
                        continue;
                    }
                    let cleared_a = arena.mul(&[terms[a], denominator]);
                    let cleared_b = arena.mul(&[terms[b], denominator]);
                    let cleared_b = distribute(arena, cleared_b, 1);
                    let numerator = arena.add(&[cleared_a, cleared_b]);
                    let numerator = factor_common(arena, numerator);
                    let inverse = arena.powi(denominator, -1);
                    let merged = arena.mul(&[numerator, inverse]);
                    let mut next: Vec<ExprId> = terms
                        .iter()
                        .enumerate()
                        .filter(|&(i, _)| i != a && i != b)
                        .map(|(_, &t)| t)
                        .collect();
                    next.push(merged);
                    let sum = arena.add(&next);
                    let next_cost = arena.op_count(&[sum]);
                    if next_cost < cost {
                        cost = next_cost;
                        terms = next;
                        continue 'improve;
                    }
                }
            }
        }
        return arena.add(&terms);
    }
}

/// The sums a term divides by (`x` for a factor `x^-1`, `x` a sum).
fn denominators(arena: &Arena, term: ExprId) -> Vec<ExprId> {
    factors(arena, term)
        .into_iter()
        .filter(|&(b, x)| x == -1.0 && matches!(arena.node(b), Node::Add(_)))
        .map(|(b, _)| b)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::Names;
    use crate::mechanics::jet_coefficients::{candidate_jets, JOINT_JACOBIAN_ROOTS};
    use crate::mechanics::Rng;
    use crate::syntax::ast::Func;

    fn arena() -> Arena {
        Arena::new(Names {
            params: vec!["alpha".into()],
            coords: vec!["q1".into(), "q2".into(), "q3".into()],
            masses: Vec::new(),
            inputs: Vec::new(),
        })
    }

    /// A random sum of products over the jets of three coordinates up to
    /// order 2, `sin`/`cos` of positions, a parameter and sums (products
    /// of sums, for `distribute`); some affine in the highest jets, some
    /// with cross dependences (`q1''·q2''`), some with a jet squared.
    fn random_expr(a: &mut Arena, rng: &mut Rng) -> ExprId {
        let factor = |a: &mut Arena, rng: &mut Rng| -> ExprId {
            let jet = Symbol::Jet {
                coord: rng.below(3) as u32,
                order: rng.below(3) as u32,
            };
            match rng.below(7) {
                0 | 1 => a.symbol(jet),
                2 => {
                    let x = a.symbol(Symbol::Jet {
                        coord: jet_coord(jet),
                        order: 0,
                    });
                    a.func(Func::Sin, x)
                }
                3 => {
                    let x = a.symbol(Symbol::Jet {
                        coord: jet_coord(jet),
                        order: 0,
                    });
                    a.func(Func::Cos, x)
                }
                4 => a.symbol(Symbol::Param(0)),
                5 => {
                    let x = a.symbol(jet);
                    let one = a.one();
                    a.add(&[one, x])
                }
                _ => a.constant(1.0 + rng.below(4) as f64),
            }
        };
        let terms: Vec<ExprId> = (0..1 + rng.below(5))
            .map(|_| {
                let fs: Vec<ExprId> = (0..1 + rng.below(3)).map(|_| factor(a, rng)).collect();
                a.mul(&fs)
            })
            .collect();
        a.add(&terms)
    }

    fn jet_coord(s: Symbol) -> u32 {
        match s {
            Symbol::Jet { coord, .. } => coord,
            _ => 0,
        }
    }

    /// The rule as first written: rescan every pair of jets after each
    /// drop, dropping the last end of the last dependence.
    fn affine_jets_by_pairs(arena: &mut Arena, e: ExprId) -> Vec<Symbol> {
        let mut vars = crate::mechanics::jet_coefficients::candidate_jets(arena, e);
        loop {
            let mut drop: Option<usize> = None;
            for (a, &v) in vars.iter().enumerate() {
                let c = arena.diff(e, v);
                if let Some(b) = vars.iter().rposition(|&w| arena.depends_on(c, w)) {
                    let candidate = a.max(b);
                    drop = Some(drop.map_or(candidate, |d: usize| d.max(candidate)));
                }
            }
            match drop {
                Some(i) => {
                    vars.remove(i);
                }
                None => return vars,
            }
        }
    }

    /// The counting rule keeps the jets the pair scan keeps, on random
    /// expressions with self and cross dependences.
    #[test]
    fn affine_jets_is_the_pair_scan() {
        let mut rng = Rng::new(29);
        let mut a = arena();
        let mut dropped_some = 0;
        for _ in 0..400 {
            let e = random_expr(&mut a, &mut rng);
            let expected = affine_jets_by_pairs(&mut a, e);
            let all = a
                .free_symbols(e)
                .into_iter()
                .filter(|s| matches!(s, Symbol::Jet { .. }));
            if all.count() > expected.len() {
                dropped_some += 1;
            }
            let coefficients: HashMap<Symbol, ExprId> = a
                .free_symbols(e)
                .into_iter()
                .map(|v| (v, a.diff(e, v)))
                .collect();
            let vars = candidate_jets(&a, e);
            let all: Vec<ExprId> = vars.iter().map(|&v| coefficients[&v]).collect();
            let got = affine_among(&a, vars, &all);
            assert_eq!(got, expected, "{}", a.display(e));
            let staged = jet_coefficients(&mut a, &[e]).remove(0);
            let got = affine_among(&a, staged.vars, &staged.coefficients);
            assert_eq!(got, expected, "{}", a.display(e));
        }
        assert!(
            dropped_some > 100,
            "only {dropped_some} expressions drop a jet"
        );
    }

    /// The coefficients taken an order at a time, for many expressions
    /// at once (one Jacobian per order), decide the jets as every
    /// coefficient does; some expressions skip an order, and some take a
    /// skipped order after all (a later order holds a jet no coefficient
    /// taken holds).
    #[test]
    fn staged_coefficients_decide_as_all_do() {
        let mut rng = Rng::new(31);
        let mut a = arena();
        let es: Vec<ExprId> = (0..400).map(|_| random_expr(&mut a, &mut rng)).collect();
        let staged = jet_coefficients(&mut a, &es);
        let (mut skipped, mut retaken) = (0, 0);
        for (&e, jc) in es.iter().zip(staged) {
            let expected = affine_jets_by_pairs(&mut a, e);
            let vars = candidate_jets(&a, e);
            if jc.vars.len() < vars.len() {
                skipped += 1;
            }
            // An order every jet of which the coefficients of the higher
            // orders hold, yet taken: skipped at its turn, taken after
            // all for a later order's jet that nothing held.
            let all: Vec<ExprId> = vars.iter().map(|&v| a.diff(e, v)).collect();
            let order = |s: Symbol| match s {
                Symbol::Jet { order, .. } => order,
                _ => 0,
            };
            let orders: BTreeSet<u32> = vars.iter().map(|&s| order(s)).collect();
            let retook = orders.iter().any(|&o| {
                let first = vars.iter().position(|&s| order(s) == o).unwrap_or(0);
                let group: Vec<Symbol> = vars.iter().copied().filter(|&s| order(s) == o).collect();
                first > 0
                    && jc.vars.contains(&group[0])
                    && group
                        .iter()
                        .all(|&s| all[..first].iter().any(|&c| a.depends_on(c, s)))
            });
            if retook {
                retaken += 1;
            }
            let got = affine_among(&a, jc.vars, &jc.coefficients);
            assert_eq!(got, expected, "{}", a.display(e));
        }
        assert!(skipped > 50, "only {skipped} expressions skip an order");
        assert!(retaken > 5, "only {retaken} expressions retake an order");
    }

    /// Tidying many expressions together (one Jacobian, shared memos)
    /// writes each as tidying it alone does, in both of the batch's ways
    /// of taking the coefficients (few expressions by `diff`, many by the
    /// Jacobian). Compared as text, each in its own copy of the arena.
    #[test]
    fn tidy_together_is_tidy_alone() {
        for (seed, count) in [(1, 3), (2, JOINT_JACOBIAN_ROOTS), (3, 60)] {
            let mut rng = Rng::new(seed);
            let mut a = arena();
            let mut es: Vec<ExprId> = (0..count).map(|_| random_expr(&mut a, &mut rng)).collect();
            // Shared parts and a repeat, as equations have.
            let shared = es[0];
            let extra = a.add(&[es[1], shared]);
            es.push(extra);
            es.push(es[2]);
            let mut alone = a.clone();
            let together = tidy_terms_all(&mut a, &es);
            for (i, &e) in es.iter().enumerate() {
                let one = tidy_terms(&mut alone, e);
                let one: Vec<String> = one.iter().map(|&t| alone.display(t).to_string()).collect();
                let batch: Vec<String> = together[i]
                    .iter()
                    .map(|&t| a.display(t).to_string())
                    .collect();
                assert_eq!(batch, one, "{}", alone.display(e));
            }
        }
    }

    /// A `Simplifier` kept across expressions gives what a fresh
    /// `simplify` gives each.
    #[test]
    fn simplifier_remembers_what_simplify_gives() {
        let mut rng = Rng::new(7);
        let mut a = arena();
        let mut es: Vec<ExprId> = (0..200).map(|_| random_expr(&mut a, &mut rng)).collect();
        // Products of sums sharing factors, for the product memo.
        for i in 0..20 {
            let p = a.mul(&[es[i], es[i + 1], es[i + 2]]);
            es.push(p);
        }
        let mut fresh = a.clone();
        let mut simplifier = Simplifier::default();
        for &e in &es {
            let kept = simplifier.simplify(&mut a, e);
            let alone = simplify(&mut fresh, e);
            assert_eq!(
                a.display(kept).to_string(),
                fresh.display(alone).to_string(),
                "{}",
                a.display(e)
            );
        }
    }
}
