//! The one integration-test binary.

mod field;
mod ir;
mod runtime;
