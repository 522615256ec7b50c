//! The mechanics stage (`lagc::mechanics`): equations (4), the reduced
//! system (7), the cross-check, the mechanics' diagnostics.

mod errors;
mod examples;
mod paper;
mod reduction;

use lagc::mechanics::{derive, Derivation};

/// Parses, checks and derives a model given as source text.
pub fn derive_source(source: &str) -> Derivation {
    let model = lagc::frontend(source).unwrap_or_else(|d| panic!("front end: {d:#?}"));
    derive(&model).unwrap_or_else(|d| panic!("derive: {d:#?}"))
}

/// A small deterministic PRNG (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        lo + (hi - lo) * (z >> 11) as f64 / (1u64 << 53) as f64
    }
}
