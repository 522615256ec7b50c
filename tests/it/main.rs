//! The one integration-test binary.
mod runtime;

fn main() {}
