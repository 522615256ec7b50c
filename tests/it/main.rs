//! The one integration-test binary.

mod ir;
mod runtime;
