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

/// The project's one PRNG.
pub use lagc::mechanics::Rng;
