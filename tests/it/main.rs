//! The one integration-test binary.

mod field;
mod generated;
mod ir;
mod mechanics;
mod runtime;
