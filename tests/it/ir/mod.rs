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
        inputs: Vec::new(),
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

/// The project's one PRNG.
pub use lagc::mechanics::Rng;

/// Values for every symbol, deterministic per symbol and `seed`.
pub fn env_at(seed: u64) -> impl Fn(Symbol) -> f64 {
    move |s: Symbol| {
        let key = match s {
            Symbol::Time => 1,
            Symbol::Param(i) => 100 + u64::from(i),
            Symbol::Mass(i) => 200 + u64::from(i),
            Symbol::Jet { coord, order } => 1000 + 10 * u64::from(coord) + u64::from(order),
            Symbol::Aux(i) => 5000 + u64::from(i),
            Symbol::Input(i) => 6000 + u64::from(i),
            Symbol::InputRate(i) => 7000 + u64::from(i),
        };
        Rng::new(seed.wrapping_mul(7919).wrapping_add(key)).range(0.2, 1.4)
    }
}
