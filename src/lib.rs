//! lagc — a compiler for mechanics.
//!
//! The pipeline, one module per stage:
//!
//! ```text
//! .lag text ──syntax::parse──▶ ast::Model ──check::check──▶ check::Model
//!   ──ir::lower──▶ symbolic IR ──mechanics──▶ equations (4), reduced system (7)
//!   ──field──▶ basic equation (9), coefficient system ──emit──▶ Rust crate
//! ```
//!
//! No stage does IO: problems come back as [`diagnostic::Diagnostic`]s and
//! the binary (`cli/commands/`) renders them.

pub mod check;
pub mod diagnostic;
pub mod emit;
pub mod field;
pub mod frontend;
pub mod ir;
pub mod kernel;
pub mod latex;
pub mod linearize;
pub mod mechanics;
pub mod pipeline;
pub mod report;
pub mod span;
mod suggest;
pub mod syntax;

pub use frontend::{
    check_and_derive, check_and_derive_bytes, check_through_kernel, decode_then, frontend,
    frontend_bytes, literal_warnings, on_big_stack, source_warnings,
};
pub use pipeline::{compile, compile_fmu};
