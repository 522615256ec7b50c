//! The symbolic core (`lagc::ir`).

mod calculus;
mod canon;
mod lower;
mod pendulum;
mod text;

use lagc::ir::{Arena, ExprId, Names, Symbol};

/// params `alpha`, `M0`; coords `q1`, `q2`; mass law `M`.
pub fn arena() -> Arena {
    Arena::new(Names {
        params: vec!["alpha".into(), "M0".into()],
        coords: vec!["q1".into(), "q2".into()],
        masses: vec!["M".into()],
    })
}

pub const ALPHA: Symbol = Symbol::Param(0);
pub const M0: Symbol = Symbol::Param(1);
pub const M: Symbol = Symbol::Mass(0);

pub fn q(coord: u32, order: u32) -> Symbol {
    Symbol::Jet { coord, order }
}

pub fn sym(a: &mut Arena, s: Symbol) -> ExprId {
    a.symbol(s)
}

pub fn num(a: &mut Arena, v: f64) -> ExprId {
    a.constant(v)
}

/// A small deterministic PRNG (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// Values for every symbol, deterministic per symbol and `seed`.
pub fn env_at(seed: u64) -> impl Fn(Symbol) -> f64 {
    move |s: Symbol| {
        let key = match s {
            Symbol::Time => 1,
            Symbol::Param(i) => 100 + u64::from(i),
            Symbol::Mass(i) => 200 + u64::from(i),
            Symbol::Jet { coord, order } => 1000 + 10 * u64::from(coord) + u64::from(order),
            Symbol::Aux(i) => 5000 + u64::from(i),
        };
        Rng(seed.wrapping_mul(7919).wrapping_add(key)).range(0.2, 1.4)
    }
}
