//! Stage 2: AST → checked model, collecting every problem.

pub mod model;
