//! The hash-consed expression DAG: ids, symbols, nodes and the arena that
//! owns them.
//!
//! Every node is stored once: building the same canonical expression twice
//! gives the same [`ExprId`], so equality is id equality and derivatives can
//! be cached per node. The canonicalising constructors live in `canon.rs`;
//! this file only interns nodes that are already canonical.

pub(crate) use super::free::FreeSet;
use crate::syntax::ast::Func;
use std::cell::RefCell;
use std::cmp::Ordering;
use std::collections::{BTreeSet, HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hash, Hasher};

/// An expression: an index into its [`Arena`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExprId(pub(crate) u32);

impl ExprId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// The leaves of an expression.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Symbol {
    Time,
    /// A model param: runtime-overridable, so its value is never substituted.
    Param(u32),
    /// The value of mass law `i`: frozen (constant) under the total derivative.
    Mass(u32),
    /// `q_coord^(order)`; order 0 is the coordinate itself.
    Jet {
        coord: u32,
        order: u32,
    },
    /// A named auxiliary symbol (field coefficients, …), see [`Arena::aux`].
    Aux(u32),
    /// Input `i`'s value (SPEC §2.3): set from outside between steps, a
    /// line in `t` on every segment the integrators see, so its total
    /// derivative is [`Symbol::InputRate`].
    Input(u32),
    /// Input `i`'s rate on the current segment (0 when held, the slope
    /// when interpolated linearly): constant under `D`.
    InputRate(u32),
}

/// One node of the DAG. Canonical invariants (kept by the constructors):
/// `Add`/`Mul` are flat (but for long products kept whole as factors,
/// `canon::SEALED_PRODUCT`), have ≥ 2 children in canonical order, and a `Mul`'s
/// numeric coefficient (≠ 1) is its first child; constants are never `-0.0`.
#[derive(Debug, Clone)]
pub enum Node {
    Const(f64),
    Sym(Symbol),
    Add(Box<[ExprId]>),
    Mul(Box<[ExprId]>),
    Pow(ExprId, ExprId),
    Func(Func, ExprId),
    /// `if g < 0 then a else b` (SPEC §2.2's conditionals, `abs`, `sign`,
    /// `min`, `max`, `atan2` all lower to it): `g` is a switching function,
    /// and the generated code evaluates the branch of the current regime.
    Select(ExprId, ExprId, ExprId),
}

// Constants compare by bits so that nodes can be hash-consed (the
// constructors never produce `-0.0` and use one NaN bit pattern).
impl PartialEq for Node {
    fn eq(&self, other: &Node) -> bool {
        match (self, other) {
            (Node::Const(a), Node::Const(b)) => a.to_bits() == b.to_bits(),
            (Node::Sym(a), Node::Sym(b)) => a == b,
            (Node::Add(a), Node::Add(b)) | (Node::Mul(a), Node::Mul(b)) => a == b,
            (Node::Pow(a, b), Node::Pow(c, d)) => a == c && b == d,
            (Node::Func(f, a), Node::Func(g, b)) => f == g && a == b,
            (Node::Select(a, b, c), Node::Select(d, e, f)) => a == d && b == e && c == f,
            _ => false,
        }
    }
}

impl Eq for Node {}

impl Hash for Node {
    fn hash<H: Hasher>(&self, state: &mut H) {
        match self {
            Node::Const(v) => {
                state.write_u8(0);
                state.write_u64(v.to_bits());
            }
            Node::Sym(s) => {
                state.write_u8(1);
                s.hash(state);
            }
            Node::Add(ts) => hash_sequence(Sequence::Add, ts, state),
            Node::Mul(ts) => hash_sequence(Sequence::Mul, ts, state),
            Node::Pow(a, b) => {
                state.write_u8(4);
                (a, b).hash(state);
            }
            Node::Func(f, a) => {
                state.write_u8(5);
                (f, a).hash(state);
            }
            Node::Select(g, a, b) => {
                state.write_u8(6);
                (g, a, b).hash(state);
            }
        }
    }
}

/// Which n-ary node a sequence of children makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Sequence {
    Add,
    Mul,
}

/// The hash of `Node::Add(ts)` or `Node::Mul(ts)`, from the children alone:
/// a sum or product is looked up without boxing its children first.
fn hash_sequence<H: Hasher>(kind: Sequence, ts: &[ExprId], state: &mut H) {
    state.write_u8(match kind {
        Sequence::Add => 2,
        Sequence::Mul => 3,
    });
    state.write_usize(ts.len());
    for t in ts {
        state.write_u32(t.0);
    }
}

fn sequence_node(kind: Sequence, ts: &[ExprId]) -> Node {
    let ts: Box<[ExprId]> = ts.into();
    match kind {
        Sequence::Add => Node::Add(ts),
        Sequence::Mul => Node::Mul(ts),
    }
}

fn fx_hash(node: &Node) -> u64 {
    let mut state = FxHasher::default();
    node.hash(&mut state);
    state.finish()
}

/// Display names of the model's symbols, by index.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Names {
    pub params: Vec<String>,
    pub coords: Vec<String>,
    pub masses: Vec<String>,
    pub inputs: Vec<String>,
}

/// A small, fast, deterministic hasher (FxHash): the arena hashes millions of
/// small keys and needs no protection against adversarial collisions.
#[derive(Default, Clone, Copy)]
pub(crate) struct FxHasher {
    hash: u64,
}

impl FxHasher {
    fn mix(&mut self, word: u64) {
        self.hash = (self.hash.rotate_left(5) ^ word).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl Hasher for FxHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.mix(u64::from_le_bytes(word));
        }
    }
    fn write_u8(&mut self, i: u8) {
        self.mix(u64::from(i));
    }
    fn write_u32(&mut self, i: u32) {
        self.mix(u64::from(i));
    }
    fn write_u64(&mut self, i: u64) {
        self.mix(i);
    }
    fn write_usize(&mut self, i: usize) {
        self.mix(i as u64);
    }
    fn finish(&self) -> u64 {
        self.hash
    }
}

pub(crate) type FxMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;

/// Which derivation a cached derivative belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Derivation {
    Partial(Symbol),
    Total,
}

/// Per-node facts computed once when the node is interned.
#[derive(Debug, Clone)]
pub(crate) struct Meta {
    /// Free symbols as indices into `Arena::symbols`.
    pub(crate) free: FreeSet,
    /// Depends on `t` or on some jet: moves under the total derivative.
    pub(crate) varies: bool,
    /// Holds a selection (`Node::Select`) somewhere below.
    pub(crate) selects: bool,
}

/// The hash-consed DAG of expressions, with its caches.
#[derive(Debug, Clone)]
pub struct Arena {
    pub(crate) names: Names,
    pub(crate) aux_names: Vec<String>,
    aux_index: HashMap<String, u32>,
    pub(crate) nodes: Vec<Node>,
    pub(crate) meta: Vec<Meta>,
    /// Every node by the hash of its content (`fx_hash`): the node itself
    /// is stored once, in `nodes`. Nodes whose hashes collide with the
    /// first node of that hash are in `collisions`.
    interned: FxMap<u64, ExprId>,
    collisions: FxMap<u64, Vec<ExprId>>,
    pub(crate) symbols: Vec<Symbol>,
    symbol_index: FxMap<Symbol, u32>,
    pub(crate) derivatives: FxMap<(ExprId, Derivation), ExprId>,
    /// Lowered lets by `(index, primes)`: a let is lowered once per arena,
    /// however often it is used (SPEC §2.2: lets are shared).
    pub(crate) lets: FxMap<(u32, u32), Box<[ExprId]>>,
    /// The canonical order of two composite nodes, keyed smaller id first
    /// (`canon.rs`): the order is structural, so comparing `cos(sin^k(u))`
    /// with `cos(sin^j(u))` walks both chains; remembered, every pair of
    /// nodes is walked once for the life of the arena.
    pub(crate) order_memo: RefCell<FxMap<(ExprId, ExprId), Ordering>>,
    /// The marks of [`Arena::reachable`], all false between walks: a walk
    /// clears only what it marked, so walking a small expression of a
    /// large arena (the tidy forms' operation counts, one per expression)
    /// costs its own size, not a fresh `Vec` of the arena's.
    walk_marks: RefCell<Vec<bool>>,
    /// The words of `union_meta`'s free-symbol set, reused.
    symbol_words: Vec<u64>,
    /// A reused buffer for the factors of a product being looked up.
    pub(crate) scratch: Vec<ExprId>,
    zero: ExprId,
    one: ExprId,
}

impl Arena {
    pub fn new(names: Names) -> Arena {
        let mut arena = Arena {
            names,
            aux_names: Vec::new(),
            aux_index: HashMap::new(),
            nodes: Vec::new(),
            meta: Vec::new(),
            interned: FxMap::default(),
            collisions: FxMap::default(),
            symbols: Vec::new(),
            symbol_index: FxMap::default(),
            derivatives: FxMap::default(),
            lets: FxMap::default(),
            order_memo: RefCell::new(FxMap::default()),
            walk_marks: RefCell::new(Vec::new()),
            symbol_words: Vec::new(),
            scratch: Vec::new(),
            zero: ExprId(0),
            one: ExprId(0),
        };
        arena.zero = arena.intern(Node::Const(0.0));
        arena.one = arena.intern(Node::Const(1.0));
        arena
    }

    pub fn names(&self) -> &Names {
        &self.names
    }

    pub fn node(&self, e: ExprId) -> &Node {
        &self.nodes[e.index()]
    }

    /// The number of distinct nodes ever built in this arena.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    pub fn zero(&mut self) -> ExprId {
        self.zero
    }

    pub fn one(&mut self) -> ExprId {
        self.one
    }

    /// A numeric constant. `-0.0` becomes `0.0` and every NaN the same NaN, so
    /// that equal values share one node. Callers should not pass NaN; `lower`
    /// does so only for a name that does not resolve.
    pub fn constant(&mut self, v: f64) -> ExprId {
        let v = if v == 0.0 {
            0.0
        } else if v.is_nan() {
            f64::NAN
        } else {
            v
        };
        self.intern(Node::Const(v))
    }

    pub fn symbol(&mut self, s: Symbol) -> ExprId {
        self.intern(Node::Sym(s))
    }

    /// `q_coord^(order)` as an expression.
    pub fn jet(&mut self, coord: u32, order: u32) -> ExprId {
        self.symbol(Symbol::Jet { coord, order })
    }

    /// Registers a named auxiliary symbol; the same name gives the same symbol.
    pub fn aux(&mut self, name: &str) -> Symbol {
        if let Some(&i) = self.aux_index.get(name) {
            return Symbol::Aux(i);
        }
        let i = self.aux_names.len() as u32;
        self.aux_names.push(name.to_string());
        self.aux_index.insert(name.to_string(), i);
        Symbol::Aux(i)
    }

    pub fn aux_name(&self, i: u32) -> Option<&str> {
        self.aux_names.get(i as usize).map(String::as_str)
    }

    pub fn as_const(&self, e: ExprId) -> Option<f64> {
        match self.node(e) {
            Node::Const(v) => Some(*v),
            _ => None,
        }
    }

    pub fn is_zero(&self, e: ExprId) -> bool {
        e == self.zero
    }

    pub fn is_one(&self, e: ExprId) -> bool {
        e == self.one
    }

    pub fn free_symbols(&self, e: ExprId) -> BTreeSet<Symbol> {
        self.meta[e.index()]
            .free
            .iter()
            .map(|i| self.symbols[i as usize])
            .collect()
    }

    pub fn depends_on(&self, e: ExprId, s: Symbol) -> bool {
        match self.symbol_index.get(&s) {
            Some(&i) => self.meta[e.index()].free.contains(i),
            None => false,
        }
    }

    /// Whether `e` holds the symbol of slot `slot` ([`Arena::symbol_slot`]):
    /// [`Arena::depends_on`] without the symbol's lookup.
    pub(crate) fn holds_slot(&self, e: ExprId, slot: u32) -> bool {
        self.meta[e.index()].free.contains(slot)
    }

    /// The highest derivative order of coordinate `coord` in `e`, if any.
    pub fn max_jet_order(&self, e: ExprId, coord: u32) -> Option<u32> {
        self.meta[e.index()]
            .free
            .iter()
            .filter_map(|i| match self.symbols[i as usize] {
                Symbol::Jet { coord: c, order } if c == coord => Some(order),
                _ => None,
            })
            .max()
    }

    /// Depends on `t` or on a jet variable.
    pub fn varies_in_time(&self, e: ExprId) -> bool {
        self.meta[e.index()].varies
    }

    pub(crate) fn symbol_slot(&self, s: Symbol) -> Option<u32> {
        self.symbol_index.get(&s).copied()
    }

    /// The children of a node, in order.
    pub fn children(&self, e: ExprId) -> Vec<ExprId> {
        match self.node(e) {
            Node::Const(_) | Node::Sym(_) => Vec::new(),
            Node::Add(ts) | Node::Mul(ts) => ts.to_vec(),
            Node::Pow(a, b) => vec![*a, *b],
            Node::Func(_, a) => vec![*a],
            Node::Select(g, a, b) => vec![*g, *a, *b],
        }
    }

    /// Distinct nodes reachable from `roots`, each once (post-order).
    pub fn reachable(&self, roots: &[ExprId]) -> Vec<ExprId> {
        let mut seen = self.walk_marks.take();
        seen.resize(self.nodes.len(), false);
        let order = postorder(roots, |e| self.children(e), &mut seen);
        // Every node marked was put in `order`.
        for &e in &order {
            seen[e.index()] = false;
        }
        self.walk_marks.replace(seen);
        order
    }

    /// Distinct nodes reachable from `roots`.
    pub fn dag_size(&self, roots: &[ExprId]) -> usize {
        self.reachable(roots).len()
    }

    /// Arithmetic operations to evaluate `roots` with every shared node
    /// computed once: an n-ary sum or product costs n − 1, a power or a
    /// function call 1, a leaf 0.
    pub fn op_count(&self, roots: &[ExprId]) -> usize {
        self.reachable(roots)
            .into_iter()
            .map(|e| match self.node(e) {
                Node::Const(_) | Node::Sym(_) => 0,
                Node::Add(ts) | Node::Mul(ts) => ts.len().saturating_sub(1),
                Node::Pow(..) | Node::Func(..) | Node::Select(..) => 1,
            })
            .sum()
    }

    /// Stores `node` (which must already be canonical) once, and returns its id.
    pub(crate) fn intern(&mut self, node: Node) -> ExprId {
        let hash = fx_hash(&node);
        if let Some(id) = self.find(hash, |n| *n == node) {
            return id;
        }
        self.insert(hash, node)
    }

    /// `intern(Node::Add(ts))` or `intern(Node::Mul(ts))`, with the children
    /// boxed only when the node is new.
    pub(crate) fn intern_sequence(&mut self, kind: Sequence, ts: &[ExprId]) -> ExprId {
        let (hash, found) = self.find_sequence(kind, ts);
        match found {
            Some(id) => id,
            None => self.insert(hash, sequence_node(kind, ts)),
        }
    }

    /// `intern_sequence(Sequence::Mul, &fs[1..])` for the product `t = fs`
    /// (its factors but the first, a number); `t` itself when it is not a
    /// product of more than two factors.
    pub(crate) fn intern_product_tail(&mut self, t: ExprId) -> ExprId {
        let (hash, found) = match self.node(t) {
            Node::Mul(fs) if fs.len() > 2 => self.find_sequence(Sequence::Mul, &fs[1..]),
            _ => return t,
        };
        if let Some(id) = found {
            return id;
        }
        let node = match self.node(t) {
            Node::Mul(fs) => sequence_node(Sequence::Mul, &fs[1..]),
            _ => return t,
        };
        self.insert(hash, node)
    }

    /// The hash of a sum or product of `ts`, and the node if it exists.
    fn find_sequence(&self, kind: Sequence, ts: &[ExprId]) -> (u64, Option<ExprId>) {
        let mut state = FxHasher::default();
        hash_sequence(kind, ts, &mut state);
        let hash = state.finish();
        let found = self.find(hash, |n| match (kind, n) {
            (Sequence::Add, Node::Add(xs)) | (Sequence::Mul, Node::Mul(xs)) => xs[..] == *ts,
            _ => false,
        });
        (hash, found)
    }

    /// The node of hash `hash` that `is` accepts.
    fn find(&self, hash: u64, is: impl Fn(&Node) -> bool) -> Option<ExprId> {
        let &first = self.interned.get(&hash)?;
        if is(self.node(first)) {
            return Some(first);
        }
        self.collisions
            .get(&hash)?
            .iter()
            .copied()
            .find(|&id| is(self.node(id)))
    }

    /// Stores a node not yet in the arena.
    fn insert(&mut self, hash: u64, node: Node) -> ExprId {
        let meta = self.meta_of(&node);
        let id = ExprId(self.nodes.len() as u32);
        self.nodes.push(node);
        self.meta.push(meta);
        match self.interned.entry(hash) {
            std::collections::hash_map::Entry::Vacant(slot) => {
                slot.insert(id);
            }
            std::collections::hash_map::Entry::Occupied(_) => {
                self.collisions.entry(hash).or_default().push(id);
            }
        }
        id
    }

    fn meta_of(&mut self, node: &Node) -> Meta {
        match node {
            Node::Const(_) => Meta {
                free: FreeSet::default(),
                varies: false,
                selects: false,
            },
            Node::Sym(s) => {
                let slot = self.slot_for(*s);
                Meta {
                    free: FreeSet::single(slot),
                    varies: matches!(s, Symbol::Time | Symbol::Jet { .. } | Symbol::Input(_)),
                    selects: false,
                }
            }
            Node::Add(ts) | Node::Mul(ts) => self.union_meta(ts),
            Node::Pow(a, b) => self.union_meta(&[*a, *b]),
            Node::Func(_, a) => self.meta[a.index()].clone(),
            Node::Select(g, a, b) => Meta {
                selects: true,
                ..self.union_meta(&[*g, *a, *b])
            },
        }
    }

    fn union_meta(&mut self, children: &[ExprId]) -> Meta {
        let words = &mut self.symbol_words;
        words.clear();
        let mut varies = false;
        let mut selects = false;
        for c in children {
            let m = &self.meta[c.index()];
            m.free.or_into(words);
            varies |= m.varies;
            selects |= m.selects;
        }
        Meta {
            free: FreeSet::from_words(words),
            varies,
            selects,
        }
    }

    fn slot_for(&mut self, s: Symbol) -> u32 {
        if let Some(&i) = self.symbol_index.get(&s) {
            return i;
        }
        let i = self.symbols.len() as u32;
        self.symbols.push(s);
        self.symbol_index.insert(s, i);
        i
    }
}

/// The nodes a walk has met: a dense `Vec<bool>` by index when the walk
/// may cover much of an arena ([`Arena::reachable`]), a hash set when it
/// covers a little of a large one (emission, one body at a time).
pub trait Seen {
    /// Marks `e`; false when it was marked already.
    fn insert(&mut self, e: ExprId) -> bool;
    fn contains(&self, e: ExprId) -> bool;
}

impl Seen for Vec<bool> {
    fn insert(&mut self, e: ExprId) -> bool {
        !std::mem::replace(&mut self[e.index()], true)
    }
    fn contains(&self, e: ExprId) -> bool {
        self[e.index()]
    }
}

impl Seen for HashSet<ExprId> {
    fn insert(&mut self, e: ExprId) -> bool {
        HashSet::insert(self, e)
    }
    fn contains(&self, e: ExprId) -> bool {
        HashSet::contains(self, &e)
    }
}

/// Post-order (children before the node, first child first, roots in
/// order) of the nodes reachable from `roots` through `children`, each
/// once; nodes already in `seen` are not visited. Iterative, so no depth
/// overflows the stack. The one walk behind [`Arena::reachable`] and the
/// emitter's order of `let`s.
pub fn postorder(
    roots: &[ExprId],
    children: impl Fn(ExprId) -> Vec<ExprId>,
    seen: &mut impl Seen,
) -> Vec<ExprId> {
    let mut order = Vec::new();
    let mut stack: Vec<(ExprId, bool)> = roots.iter().rev().map(|&r| (r, false)).collect();
    while let Some((e, expanded)) = stack.pop() {
        if expanded {
            order.push(e);
            continue;
        }
        if !seen.insert(e) {
            continue;
        }
        stack.push((e, true));
        for c in children(e).into_iter().rev() {
            if !seen.contains(c) {
                stack.push((c, false));
            }
        }
    }
    order
}
